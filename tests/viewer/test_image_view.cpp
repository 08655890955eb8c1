// The image panel's placement (app/viewer/image_view.h): fitted by default, zoom about the
// pointer keeps the film point under it, pan moves by screen pixels, 1:1 is one pixel per pixel.
#include "viewer/image_view.h"

#include <gtest/gtest.h>

using namespace tpb::app;

// Issue 33 item 11: the image fills its panel (a 256-pixel film was shown at 1:1, a small image in
// an 880 x 430 panel, because the zoom was rounded down to whole pixels).
TEST(ImageView, AFittedImageFillsThePanelAndIsCentred) {
    const ImagePlacement p = placeImage(ImageViewport{}, 880.0f, 430.0f, 256, 256);
    EXPECT_FLOAT_EQ(p.zoom, 430.0f / 256.0f);
    EXPECT_NEAR(p.x + 0.5f * 256 * p.zoom, 440.0f, 1.0f);
    EXPECT_FLOAT_EQ(p.y, 0.0f);
    // A wide film in a tall panel: the width decides, with the markers' margin.
    const ImagePlacement q = placeImage(ImageViewport{}, 400.0f, 900.0f, 512, 64);
    EXPECT_FLOAT_EQ(q.zoom, (400.0f - 2.0f * kFitMarginPx) / 512.0f);
    EXPECT_GE(q.x, kFitMarginPx - 1.0f);
}

TEST(ImageView, ZoomKeepsThePointUnderThePointerAndPanMoves) {
    const ImagePlacement fit = placeImage(ImageViewport{}, 800.0f, 400.0f, 100, 100);
    const float px = 300.0f, py = 150.0f;
    const float fx = (px - fit.x) / fit.zoom, fy = (py - fit.y) / fit.zoom;
    const ImageViewport z = zoomAbout(fit, 2.0f, px, py);
    EXPECT_FALSE(z.fit);
    const ImagePlacement p = placeImage(z, 800.0f, 400.0f, 100, 100);
    EXPECT_FLOAT_EQ(p.zoom, 2.0f * fit.zoom);
    EXPECT_NEAR(p.x + fx * p.zoom, px, 1.0f);  // whole pixels: the placement is floored
    EXPECT_NEAR(p.y + fy * p.zoom, py, 1.0f);
    const ImagePlacement moved = placeImage(panBy(p, 37.0f, -12.0f), 800.0f, 400.0f, 100, 100);
    EXPECT_NEAR(moved.x, p.x + 37.0f, 1.0f);
    EXPECT_NEAR(moved.y, p.y - 12.0f, 1.0f);
    EXPECT_FLOAT_EQ(moved.zoom, p.zoom);
    // Zoom stays within its bounds.
    EXPECT_LE(placeImage(zoomAbout(p, 1e9f, 0, 0), 800, 400, 100, 100).zoom, kMaxImageZoom);
}

TEST(ImageView, OneToOneIsOneFramebufferPixelPerFilmPixel) {
    const ImagePlacement p = placeImage(oneToOne(256, 128, 1.0f), 880.0f, 430.0f, 256, 128);
    EXPECT_FLOAT_EQ(p.zoom, 1.0f);
    EXPECT_FLOAT_EQ(p.x, 440.0f - 128.0f);
    EXPECT_FLOAT_EQ(p.y, 215.0f - 64.0f);
    EXPECT_FLOAT_EQ(placeImage(oneToOne(256, 128, 2.0f), 880.0f, 430.0f, 256, 128).zoom, 0.5f);  // HiDPI
}
