// Where the film image sits in its panel: fitted to it (the default), or zoomed and panned by the
// user (mouse wheel about the pointer, right/middle drag), or 1:1. Plain arithmetic in panel
// pixels, no GL or ImGui, so it is tested on its own (tests/viewer/test_image_view.cpp).
#pragma once

namespace tpb::app {

inline constexpr float kMinImageZoom = 1.0f / 64.0f, kMaxImageZoom = 256.0f;  // screen px per film px
inline constexpr float kFitMarginPx = 12.0f;  // left and right of a fitted image: the streak row's markers

struct ImageViewport {
    bool fit = true;                 // fitted to the panel, centred (the other fields unused)
    float zoom = 1.0f;               // screen pixels per film pixel
    float centreX = 0, centreY = 0;  // the film point (film pixels) at the panel's centre
};

// The image's top-left corner in the panel (pixels from the panel's top-left) and its zoom.
struct ImagePlacement {
    float x = 0, y = 0, zoom = 1;
    float panelW = 0, panelH = 0;
};

ImagePlacement placeImage(const ImageViewport& v, float panelW, float panelH, int width, int height);
// Zoomed by `factor`, keeping the film point under (px, py) (panel pixels) where it is.
ImageViewport zoomAbout(const ImagePlacement& p, float factor, float px, float py);
// Moved by (dx, dy) screen pixels.
ImageViewport panBy(const ImagePlacement& p, float dx, float dy);
// One screen pixel per film pixel (pixelsPerPoint: the framebuffer's pixels per panel unit), centred.
ImageViewport oneToOne(int width, int height, float pixelsPerPoint);

}  // namespace tpb::app
