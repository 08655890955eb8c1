// Deterministic random numbers. Every stream is keyed by (seed, purpose, pass, index) so a pass's
// photons and a pixel's samples are the same whatever thread computes them (replayable).
#pragma once
#include <cstdint>

namespace tpb {

inline uint64_t splitmix64(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

enum class Stream : uint64_t { Photon = 1, Camera = 2, PathTracer = 3, Test = 4, Counts = 5 };

// PCG32 (O'Neill 2014): 64-bit state, 32-bit output, selectable sequence.
class Rng {
public:
    Rng(uint64_t seed, Stream stream, uint64_t pass, uint64_t index) {
        const uint64_t key = splitmix64(
            seed ^ splitmix64(static_cast<uint64_t>(stream) * 0x632BE59BD9B4E019ull + splitmix64(pass + 0x1234567ull)));
        inc_ = (splitmix64(key ^ index) << 1u) | 1u;
        state_ = 0;
        next32();
        state_ += splitmix64(key + index * 0x9E3779B97F4A7C15ull);
        next32();
    }
    uint32_t next32() {
        const uint64_t old = state_;
        state_ = old * 6364136223846793005ull + inc_;
        const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
    }
    // Uniform double in [0, 1), 53 random bits.
    double uniform() {
        const uint64_t hi = next32(), lo = next32();
        return static_cast<double>(((hi << 32) | lo) >> 11) * 0x1.0p-53;
    }

private:
    uint64_t state_ = 0, inc_ = 1;
};

}  // namespace tpb
