#include "film/time_axis.h"

#include "base/error.h"

#include <cstdlib>

namespace tpb {

std::optional<TimeKernelSettings> parseTimeKernel(std::string_view s) {
    if (s == "none") return TimeKernelSettings{};
    if (s == "box") return TimeKernelSettings{TimeKernelKind::Box, 0.0};
    if (s.rfind("box:", 0) == 0) {
        const std::string w(s.substr(4));
        char* end = nullptr;
        const double width = std::strtod(w.c_str(), &end);
        if (w.empty() || end != w.c_str() + w.size() || !(width > 0.0) || !std::isfinite(width)) return std::nullopt;
        return TimeKernelSettings{TimeKernelKind::Box, width};
    }
    return std::nullopt;
}

std::string timeKernelName(const TimeKernelSettings& k) {
    if (k.kind == TimeKernelKind::None) return "none";
    if (!(k.width > 0.0)) return "box";
    return "box:" + shortNumber(k.width);
}

}  // namespace tpb
