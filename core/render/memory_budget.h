// Memory budget: what the big allocations of a render will need, the limit they must stay under,
// and how much the process has used. The loader refuses films and photon counts over the limit
// before anything is allocated; the photon tracer stops a pass whose photon map outgrows it.
#pragma once
#include "scene/scene_desc.h"

#include <cstdint>
#include <string>

namespace tpb {

// Memory the live transient film needs, in bytes: the one formula (TransientFilm::bytes() counts what
// it really allocated and must agree; tests/film/test_transient_film.cpp checks it). Per pixel, all in
// double: bins x 2 time axes x RGB, the steady-state RGB and, per axis, the RGB that arrived before
// and after the film. Not included (film_snapshot.h): one tile block per render thread while a pass
// runs, the blocks that snapshots still hold, and the continuous-mode prefix sums of the blocks read.
// Saturates at UINT64_MAX instead of wrapping.
uint64_t filmBytes(int width, int height, int bins);
inline uint64_t filmBytes(const CameraDesc& cam, int bins) { return filmBytes(cam.width, cam.height, bins); }
// Rough memory of one pass's photon map (~4 beam segments per photon, as `tpb info` prints).
uint64_t photonMapBytes(int64_t photonsPerPass);
// The limit for the film and for one pass's photon map: 75% of physical memory by default; the
// environment variable TPB_MAX_FILM_BYTES (a whole number of bytes) overrides it. Throws
// UserError if that variable is malformed.
uint64_t maxFilmBytes();
// Peak resident set size of this process (VmHWM), 0 if unknown.
uint64_t peakRssBytes();

// "1.5 GiB", "386.0 MiB", "512 B".
std::string humanBytes(uint64_t bytes);

}  // namespace tpb
