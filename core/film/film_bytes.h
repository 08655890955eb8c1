// Memory the live transient film needs, in bytes: the one formula (TransientFilm::bytes() counts
// what it really allocated and must agree; tests/film/test_transient_film.cpp checks it). Per
// pixel, all in double: bins x 2 time axes x RGB, the steady-state RGB and, per axis, the RGB that
// arrived before and after the film. Not included (film_snapshot.h): one tile block per render
// thread while a pass runs, the blocks that snapshots still hold, and the continuous-mode prefix
// sums of the blocks read. Saturates at UINT64_MAX instead of wrapping.
#pragma once
#include <cstdint>

namespace tpb {

// With a phasor film of `phasorFrequencies` frequencies: 2 axes x (Re, Im) x RGB doubles more per
// frequency (film/phasor.h).
uint64_t filmBytes(int width, int height, int bins, int phasorFrequencies = 0);

}  // namespace tpb
