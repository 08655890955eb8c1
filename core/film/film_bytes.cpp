#include "film/film_bytes.h"

#include "base/memory.h"
#include "film/film_snapshot.h"

#include <algorithm>

namespace tpb {

uint64_t filmBytes(int width, int height, int bins, int phasorFrequencies) {
    const uint64_t w = static_cast<uint64_t>(std::max(width, 0));
    const uint64_t h = static_cast<uint64_t>(std::max(height, 0));
    const uint64_t b = static_cast<uint64_t>(std::max(bins, 0));
    // Transient: bins x 2 time axes x RGB x double (FilmSum). Steady RGB + 2 axes x (before, after) x RGB, double.
    const uint64_t perPixel =
        saturatingAdd(saturatingAdd(saturatingMul(b, 2 * 3 * sizeof(FilmSum)), (3 + 2 * 2 * 3) * sizeof(double)),
                      saturatingMul(static_cast<uint64_t>(std::max(phasorFrequencies, 0)), 2 * 2 * 3 * sizeof(double)));
    return saturatingMul(saturatingMul(w, h), perPixel);
}

}  // namespace tpb
