#include "film/output_names.h"

#include <algorithm>
#include <cstdio>

namespace tpb {

namespace {

std::string tagged(const std::string& stem, const std::string& tag, const char* ext) {
    return stem + (tag.empty() ? "" : "_" + tag) + ext;
}

}  // namespace

std::string outputTag(TimeAxis axis, EmissionMode mode, const TimeResponse& r) {
    std::string tag = std::string(axis == TimeAxis::Real ? "real" : "unwarped") + "_" +
                      (mode == EmissionMode::Delta ? "delta" : "continuous");
    const auto plain = [](std::string n) {  // "gaussian:0.5" -> "gaussian0.5"
        n.erase(std::remove(n.begin(), n.end(), ':'), n.end());
        return n;
    };
    if (r.pulse != PulseShape::Delta) tag += "_pulse-" + plain(pulseName(r));
    if (r.sensor != SensorShape::Ideal) tag += "_sensor-" + plain(sensorName(r));
    if (r.counting.enabled) tag += "_counts";
    return tag;
}

std::string frameName(int bin, const std::string& tag) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "frame_%05d", bin);
    return tagged(buf, tag, ".exr");
}

std::string framesDirName(const std::string& tag) { return tagged("frames", tag, ""); }

std::string streakName(int row, const std::string& tag) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "streak_row%04d", row);
    return tagged(buf, tag, ".exr");
}

std::string profileName(int x, int y, const std::string& tag) {
    return tagged("profile_x" + std::to_string(x) + "_y" + std::to_string(y), tag, ".csv");
}

std::string volumeDirName(const std::string& tag) { return tagged("volume", tag, ""); }
std::string mp4Name(const std::string& tag) { return tagged("transient", tag, ".mp4"); }
std::string contactSheetName(const std::string& tag) { return tagged("contact_sheet", tag, ".png"); }

}  // namespace tpb
