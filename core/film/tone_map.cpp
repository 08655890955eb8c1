#include "film/tone_map.h"

#include "base/math.h"

#include <algorithm>
#include <cmath>

namespace tpb {

namespace {

float srgbEncode(float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

// The piecewise-linear colour ramp of shaders/display.frag, t in [0, 1].
void ramp(float t, float out[3]) {
    constexpr int N = 6;
    static const float stops[N][3] = {{0.02f, 0.02f, 0.12f}, {0.10f, 0.15f, 0.65f}, {0.00f, 0.60f, 0.85f},
                                      {0.15f, 0.78f, 0.30f}, {0.98f, 0.85f, 0.10f}, {0.90f, 0.15f, 0.05f}};
    const float x = std::clamp(t, 0.0f, 1.0f) * float(N - 1);
    const int i = std::min(static_cast<int>(std::floor(x)), N - 2);
    const float f = x - float(i);
    for (int c = 0; c < 3; ++c) out[c] = stops[i][c] + (stops[i + 1][c] - stops[i][c]) * f;
}

unsigned char toByte(float v) { return static_cast<unsigned char>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); }

}  // namespace

void toneMapPixel(const float rgb[3], const ToneMap& tm, unsigned char out[3]) {
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(rgb[c]) || rgb[c] < 0.0f) {
            out[0] = 255, out[1] = 0, out[2] = 255;
            return;
        }
    const float scale = std::exp2(tm.exposureEv);
    float v[3] = {rgb[0] * scale, rgb[1] * scale, rgb[2] * scale};
    if (tm.falseColor) {
        const float lum = 0.2126f * v[0] + 0.7152f * v[1] + 0.0722f * v[2];
        float o[3] = {0.0f, 0.0f, 0.0f};
        if (lum > 1.0f)
            o[0] = o[1] = o[2] = 1.0f;
        else if (lum > 0.0f)
            ramp(1.0f + std::log(lum) / (std::log(10.0f) * std::max(tm.decades, 0.1f)), o);
        for (int c = 0; c < 3; ++c) out[c] = toByte(o[c]);
        return;
    }
    for (int c = 0; c < 3; ++c) out[c] = toByte(tm.srgb ? srgbEncode(v[c]) : v[c]);
}

std::vector<unsigned char> toneMapImage(const std::vector<float>& rgb, const ToneMap& tm) {
    std::vector<unsigned char> out(rgb.size() / 3 * 3);
    for (size_t i = 0; i + 2 < rgb.size(); i += 3) toneMapPixel(&rgb[i], tm, &out[i]);
    return out;
}

ExposureFit fitExposure(const std::vector<float>& rgb) {
    std::vector<float> lum;
    lum.reserve(rgb.size() / 3);
    for (size_t i = 0; i + 2 < rgb.size(); i += 3) {
        const float l = static_cast<float>(luminance(Color(rgb[i], rgb[i + 1], rgb[i + 2])));
        if (std::isfinite(l) && l > 0.0f) lum.push_back(l);
    }
    ExposureFit fit;
    fit.litPixels = lum.size();
    fit.found = !lum.empty();
    if (!fit.found) return fit;
    // The 99th percentile of the lit pixels maps to 1 (a few highlights may clip).
    const size_t k = std::min(lum.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(lum.size())));
    std::nth_element(lum.begin(), lum.begin() + static_cast<std::ptrdiff_t>(k), lum.end());
    fit.ev = std::clamp(-std::log2(lum[k]), -64.0f, 64.0f);
    return fit;
}

}  // namespace tpb
