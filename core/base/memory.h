// Memory: the limit the big allocations of a render (the film, one pass's photon map) must stay
// under, how much the process has used, and byte counts for people. The formulas of what those
// allocations need live with them (film/film_bytes.h, photons/photon_tracer.h).
#pragma once
#include <cstdint>
#include <string>

namespace tpb {

// The limit for the film and for one pass's photon map: 75% of physical memory by default; the
// environment variable TPB_MAX_FILM_BYTES (a whole number of bytes) overrides it. Throws
// UserError if that variable is malformed.
uint64_t maxFilmBytes();
// Peak resident set size of this process (VmHWM), 0 if unknown.
uint64_t peakRssBytes();

// "1.5 GiB", "386.0 MiB", "512 B".
std::string humanBytes(uint64_t bytes);

// a * b and a + b, saturating at UINT64_MAX instead of wrapping.
inline uint64_t saturatingMul(uint64_t a, uint64_t b) { return (a != 0 && b > UINT64_MAX / a) ? UINT64_MAX : a * b; }
inline uint64_t saturatingAdd(uint64_t a, uint64_t b) { return b > UINT64_MAX - a ? UINT64_MAX : a + b; }

}  // namespace tpb
