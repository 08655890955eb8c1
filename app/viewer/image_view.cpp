#include "viewer/image_view.h"

#include <algorithm>
#include <cmath>

namespace tpb::app {

namespace {

ImageViewport viewportOf(const ImagePlacement& p, float zoom, float x, float y) {
    // The film point at the panel's centre, for an image drawn at (x, y) with this zoom.
    ImageViewport v;
    v.fit = false;
    v.zoom = zoom;
    v.centreX = (0.5f * p.panelW - x) / zoom;
    v.centreY = (0.5f * p.panelH - y) / zoom;
    return v;
}

}  // namespace

ImagePlacement placeImage(const ImageViewport& v, float panelW, float panelH, int width, int height) {
    ImagePlacement p;
    p.panelW = panelW;
    p.panelH = panelH;
    const float w = static_cast<float>(std::max(width, 1)), h = static_cast<float>(std::max(height, 1));
    if (v.fit) {
        p.zoom = std::clamp(std::min((panelW - 2.0f * kFitMarginPx) / w, panelH / h), kMinImageZoom, kMaxImageZoom);
        p.x = std::floor(0.5f * (panelW - w * p.zoom));
        p.y = std::floor(0.5f * std::max(0.0f, panelH - h * p.zoom));
        return p;
    }
    p.zoom = std::clamp(v.zoom, kMinImageZoom, kMaxImageZoom);
    p.x = std::floor(0.5f * panelW - v.centreX * p.zoom);
    p.y = std::floor(0.5f * panelH - v.centreY * p.zoom);
    return p;
}

ImageViewport zoomAbout(const ImagePlacement& p, float factor, float px, float py) {
    const float zoom = std::clamp(p.zoom * factor, kMinImageZoom, kMaxImageZoom);
    const float fx = (px - p.x) / p.zoom, fy = (py - p.y) / p.zoom;  // the film point under the pointer
    return viewportOf(p, zoom, px - fx * zoom, py - fy * zoom);
}

ImageViewport panBy(const ImagePlacement& p, float dx, float dy) { return viewportOf(p, p.zoom, p.x + dx, p.y + dy); }

ImageViewport oneToOne(int width, int height, float pixelsPerPoint) {
    ImageViewport v;
    v.fit = false;
    v.zoom = 1.0f / std::max(pixelsPerPoint, 1e-3f);
    v.centreX = 0.5f * static_cast<float>(width);
    v.centreY = 0.5f * static_cast<float>(height);
    return v;
}

}  // namespace tpb::app
