#include "base/memory.h"

#include "base/error.h"

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <unistd.h>

namespace tpb {

uint64_t maxFilmBytes() {
    if (const char* env = std::getenv("TPB_MAX_FILM_BYTES"); env && *env) {
        const std::string s(env);
        uint64_t v = 0;
        const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (ec != std::errc() || ptr != s.data() + s.size() || v == 0)
            throw UserError("", 0, "TPB_MAX_FILM_BYTES",
                            "expected a positive whole number of bytes, got \"" + s + "\"");
        return v;
    }
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long pageSize = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || pageSize <= 0) return uint64_t(8) << 30;  // unknown: assume 8 GiB
    return saturatingMul(static_cast<uint64_t>(pages), static_cast<uint64_t>(pageSize)) / 4 * 3;
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
    while (v >= 1024.0 && u < 6) {
        v /= 1024.0;
        ++u;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.*f %s", v < 10.0 ? 2 : 1, v, units[u]);
    return buf;
}

}  // namespace tpb
