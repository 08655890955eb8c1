#include "render/memory_budget.h"

#include "base/error.h"
#include "film/film_snapshot.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <unistd.h>

namespace tpb {

namespace {

uint64_t satMul(uint64_t a, uint64_t b) { return (a != 0 && b > UINT64_MAX / a) ? UINT64_MAX : a * b; }
uint64_t satAdd(uint64_t a, uint64_t b) { return b > UINT64_MAX - a ? UINT64_MAX : a + b; }

}  // namespace

uint64_t filmBytes(int width, int height, int bins) {
    const uint64_t w = static_cast<uint64_t>(std::max(width, 0));
    const uint64_t h = static_cast<uint64_t>(std::max(height, 0));
    const uint64_t b = static_cast<uint64_t>(std::max(bins, 0));
    // Transient: bins x 2 time axes x RGB x double (FilmSum). Steady RGB + 2 axes x (before, after) x RGB, double.
    const uint64_t perPixel = satAdd(satMul(b, 2 * 3 * sizeof(FilmSum)), (3 + 2 * 2 * 3) * sizeof(double));
    return satMul(satMul(w, h), perPixel);
}

uint64_t photonMapBytes(int64_t photonsPerPass) {
    return satMul(static_cast<uint64_t>(std::max<int64_t>(photonsPerPass, 0)), 4 * (sizeof(double) * 12 + 16));
}

uint64_t maxFilmBytes() {
    if (const char* env = std::getenv("TPB_MAX_FILM_BYTES"); env && *env) {
        const std::string s(env);
        uint64_t v = 0;
        const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (ec != std::errc() || ptr != s.data() + s.size() || v == 0)
            throw UserError("", 0, "TPB_MAX_FILM_BYTES", "expected a positive whole number of bytes, got \"" + s + "\"");
        return v;
    }
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long pageSize = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || pageSize <= 0) return uint64_t(8) << 30;  // unknown: assume 8 GiB
    return satMul(static_cast<uint64_t>(pages), static_cast<uint64_t>(pageSize)) / 4 * 3;
}

uint64_t peakRssBytes() {
    std::ifstream f("/proc/self/status");
    std::string line;
    while (std::getline(f, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024ull;
    return 0;
}

std::string humanBytes(uint64_t bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    if (bytes < 1024) return std::to_string(bytes) + " B";
    double v = static_cast<double>(bytes);
    int u = 0;
    while (v >= 1024.0 && u < 6) { v /= 1024.0; ++u; }
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.*f %s", v < 10.0 ? 2 : 1, v, units[u]);
    return buf;
}

}  // namespace tpb
