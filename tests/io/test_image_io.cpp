// Image output (core/io/image_io.h): no non-finite texel is ever written (issue 12, item 5).
#include "base/error.h"
#include "io/image_io.h"
#include "scene/scene_loader.h"
#include "support/temp_dir.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

using namespace tpb;
namespace fs = std::filesystem;

TEST(ImageIo, HalfExrClampsToItsRangeInsteadOfWritingInf) {
    const test::TempDir tmp("image_io_half");
    const fs::path& d = tmp.path();
    std::vector<float> rgb = {1.0f, 7e4f, -1e6f, 3e38f, 65504.0f, 0.5f};
    const std::string path = (d / "a.exr").string();
    EXPECT_EQ(writeExr(path, 2, 1, rgb, ExrPixel::Half), 3);  // 7e4, -1e6 and 3e38 do not fit in half
    int w = 0, h = 0;
    std::vector<float> back;
    readExr(path, w, h, back);
    ASSERT_EQ(back.size(), rgb.size());
    for (float v : back) EXPECT_TRUE(std::isfinite(v));
    EXPECT_EQ(back[1], 65504.0f);
    EXPECT_EQ(back[2], -65504.0f);
    EXPECT_EQ(back[3], 65504.0f);
    EXPECT_EQ(back[0], 1.0f);
    EXPECT_EQ(writeExr(path, 2, 1, rgb, ExrPixel::Float), 0);  // float holds them all
}

TEST(ImageIo, NonFiniteTexelIsRefusedAndNothingIsWritten) {
    const test::TempDir tmp("image_io_nan");
    const fs::path& d = tmp.path();
    const std::string path = (d / "b.exr").string();
    for (float bad : {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()}) {
        std::vector<float> rgb(12, 1.0f);
        rgb[7] = bad;  // pixel (0, 1) of a 2x2 image
        try {
            writeExr(path, 2, 2, rgb);
            ADD_FAILURE() << "a non-finite texel was written";
        } catch (const std::logic_error& e) {
            EXPECT_NE(std::string(e.what()).find("pixel (0, 1)"), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(path));
    }
    EXPECT_TRUE(fs::is_empty(d));
}

// A light whose power could overflow the film's float sums is refused at load, naming the key.
TEST(ImageIo, LightPowerBeyondTheFilmsRangeIsRefusedAtLoad) {
    for (const char* power : {"1e100", "1e300", "[1, 1, 1e21]"}) {
        const std::string json =
            std::string(R"({"version": 1, "lights": [{"type": "point", "power": )") + power + "}]}";
        try {
            loadSceneFromString(json, "big.json");
            ADD_FAILURE() << power << " was accepted";
        } catch (const UserError& e) {
            const std::string m = e.what();
            EXPECT_NE(m.find("big.json:1: lights[0].power"), std::string::npos) << m;
            EXPECT_NE(m.find("1e20"), std::string::npos) << m;
            EXPECT_NE(m.find("smaller unit"), std::string::npos) << m;
        }
    }
    EXPECT_NO_THROW(loadSceneFromString(R"({"version": 1, "lights": [{"type": "point", "power": 1e20}]})", "ok.json"));
}
