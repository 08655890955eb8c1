// Display mapping of linear radiance to 8-bit colour: exposure, sRGB encoding, a false-colour map
// of log luminance, and the automatic exposure. One implementation for every picture tpb makes
// from a film on the CPU (the MP4 and the contact sheet, app/cli and the viewer's exports); the
// viewer's screen does the same mapping on the GPU (shaders/display.frag: keep the two in step;
// tests/film/test_picture_export.cpp checks this file's values, tests/viewer/test_viewer.cpp the
// screen's pixels against them, in sRGB and false colour).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace tpb {

struct ToneMap {
    float exposureEv = 0.0f;  // radiance x 2^EV
    bool srgb = true;         // sRGB-encode (else clamp linearly)
    bool falseColor = false;  // log10 luminance over `decades` below 1 (after exposure), blue to red
    float decades = 4.0f;
};

// One pixel: linear RGB -> 8-bit RGB. Black = no energy; white (false colour) = over-exposed;
// magenta = NaN/Inf or negative (never expected from the film).
void toneMapPixel(const float rgb[3], const ToneMap& tm, unsigned char out[3]);
// A whole image: rgb has 3 floats per pixel; returns 3 bytes per pixel.
std::vector<unsigned char> toneMapImage(const std::vector<float>& rgb, const ToneMap& tm);

// Exposure that maps the 99th percentile of the lit pixels' luminance to 1 (black pixels, e.g. of
// tiles not rendered yet, are left out): the viewer's automatic exposure.
struct ExposureFit {
    bool found = false;  // some pixel has light
    float ev = 0.0f;
    size_t litPixels = 0;
};
ExposureFit fitExposure(const std::vector<float>& rgb);

}  // namespace tpb
