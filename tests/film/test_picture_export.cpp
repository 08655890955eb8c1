// Pictures of the film (core/film/picture_export.h, tone_map.h, io/video_encoder.h): the CPU tone
// map's values (the shader's formulas), the contact sheet's layout and content, and the MP4:
// ffprobe counts its frames; a missing ffmpeg is a clear UserError; ffmpeg's failure names its
// stderr; a cancelled encoding leaves no file. The ffmpeg tests skip when ffmpeg/ffprobe are absent.
#include "film/film_view.h"
#include "film/output_names.h"
#include "film/picture_export.h"
#include "film_test_passes.h"
#include "io/video_encoder.h"
#include "base/error.h"
#include "support/temp_dir.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

using namespace tpb;
namespace fs = std::filesystem;

namespace {

std::shared_ptr<const FilmSnapshot> snapshot() {
    static const std::unique_ptr<TransientFilm> film = [] {
        auto f = std::make_unique<TransientFilm>(37, 21, TimeBins{2.0, 0.25, 9});
        for (uint64_t p = 1; p <= 2; ++p) test::addRandomPass(*f, 9, p);
        return f;
    }();
    return film->snapshot();
}

int run(const std::string& cmd, std::string& out) {
    out.clear();
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) return -1;
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
    const int st = ::pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// Sets PATH for the scope.
struct PathScope {
    explicit PathScope(const std::string& path) : old_(std::getenv("PATH") ? std::getenv("PATH") : "") {
        ::setenv("PATH", path.c_str(), 1);
    }
    ~PathScope() { ::setenv("PATH", old_.c_str(), 1); }
    std::string old_;
};

void expectNoTemporaries(const fs::path& dir) {
    for (const auto& e : fs::directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

}  // namespace

TEST(VideoToneMap, ExposureSrgbAndFalseColourFollowTheShader) {
    unsigned char o[3];
    const float half[3] = {0.5f, 0.25f, 0.0f};
    toneMapPixel(half, ToneMap{}, o);
    // sRGB(0.5) = 0.7354, sRGB(0.25) = 0.5371.
    EXPECT_EQ(o[0], 188);
    EXPECT_EQ(o[1], 137);
    EXPECT_EQ(o[2], 0);
    ToneMap lin;
    lin.srgb = false;
    lin.exposureEv = 1.0f;  // x2
    toneMapPixel(half, lin, o);
    EXPECT_EQ(o[0], 255);
    EXPECT_EQ(o[1], 128);
    ToneMap fc;
    fc.falseColor = true;
    const float black[3] = {0, 0, 0}, bright[3] = {2, 2, 2}, white[3] = {1, 1, 1}, bad[3] = {NAN, 0, 0};
    toneMapPixel(black, fc, o);
    EXPECT_EQ(o[0] + o[1] + o[2], 0);
    toneMapPixel(bright, fc, o);
    EXPECT_EQ(o[0] + o[1] + o[2], 3 * 255);
    toneMapPixel(white, fc, o);  // luminance 1: the top of the ramp (red)
    EXPECT_EQ(o[0], 230);
    EXPECT_EQ(o[1], 38);
    EXPECT_EQ(o[2], 13);
    toneMapPixel(bad, ToneMap{}, o);
    EXPECT_EQ(o[0], 255);
    EXPECT_EQ(o[1], 0);
    EXPECT_EQ(o[2], 255);
    // The automatic exposure maps the 99th percentile of the lit pixels to 1.
    std::vector<float> img;
    for (int i = 1; i <= 100; ++i) img.insert(img.end(), {float(i), float(i), float(i)});
    img.insert(img.end(), {0, 0, 0});
    const ExposureFit fit = fitExposure(img);
    EXPECT_TRUE(fit.found);
    EXPECT_EQ(fit.litPixels, 100u);
    EXPECT_NEAR(fit.ev, -std::log2(100.0f), 1e-5);
}

TEST(VideoContactSheet, GridOfLabelledFramesWithTheToneMappedPixels) {
    const auto s = snapshot();
    ExportOptions opt;
    const ToneMap tone = autoExposedToneMap(*s, opt, ToneMap{});
    const ContactSheet sheet = makeContactSheet(*s, 5, opt, tone);
    ASSERT_EQ(sheet.bins.size(), 5u);
    EXPECT_EQ(sheet.bins, energeticBins(*s, 5, opt.axis));
    EXPECT_EQ(sheet.columns, 3);
    EXPECT_EQ(sheet.rows, 2);
    const int gap = ContactSheet::kSheetGap;
    EXPECT_EQ(sheet.cellWidth, std::max(37, static_cast<int>(sheet.labels[0].size()) * 4 - 1));
    EXPECT_EQ(sheet.cellHeight, 21 + 5 + 2 * gap);
    EXPECT_EQ(sheet.width, 3 * sheet.cellWidth + 4 * gap);
    EXPECT_EQ(sheet.height, 2 * sheet.cellHeight + 3 * gap);
    ASSERT_EQ(sheet.rgb.size(), static_cast<size_t>(sheet.width) * sheet.height * 3);
    char label[32];
    std::snprintf(label, sizeof label, "%.4g ns", (2.0 + (sheet.bins[2] + 0.5) * 0.25) / 0.299792458);
    EXPECT_EQ(sheet.labels[2], label);
    for (size_t i = 0; i < sheet.bins.size(); ++i) {
        const std::vector<unsigned char> want = toneMapImage(frameImage(*s, sheet.bins[i], opt.axis, opt.mode), tone);
        size_t diff = 0, lit = 0;
        for (int y = 0; y < 21; ++y)
            for (int x = 0; x < 37; ++x)
                for (int c = 0; c < 3; ++c) {
                    const unsigned char got =
                        sheet.rgb[(static_cast<size_t>(sheet.frameY[i] + y) * sheet.width + sheet.frameX[i] + x) * 3 +
                                  c];
                    const unsigned char w = want[(static_cast<size_t>(y) * 37 + x) * 3 + c];
                    diff += got != w;
                    lit += w > 0;
                }
        EXPECT_EQ(diff, 0u) << "frame " << i;
        EXPECT_GT(lit, 0u) << "frame " << i;
        // The label: light pixels in the bar below the frame.
        size_t labelPixels = 0;
        for (int y = sheet.frameY[i] + 21; y < sheet.frameY[i] + sheet.cellHeight; ++y)
            for (int x = sheet.frameX[i]; x < sheet.frameX[i] + 37; ++x)
                labelPixels += sheet.rgb[(static_cast<size_t>(y) * sheet.width + x) * 3] == 230;
        EXPECT_GT(labelPixels, 10u) << "frame " << i;
    }
}

TEST(VideoEncoder, Mp4HasOneFramePerBinAndEvenDimensions) {
    if (findExecutable("ffmpeg").empty() || findExecutable("ffprobe").empty())
        GTEST_SKIP() << "ffmpeg/ffprobe not on PATH (apt-get install ffmpeg)";
    const auto s = snapshot();
    test::TempDir tmp("mp4");
    const std::string path = (tmp / "t.mp4").string();
    int calls = 0;
    ExportOptions opt;
    opt.mode = EmissionMode::Continuous;
    const int n = exportMp4(*s, path, opt, autoExposedToneMap(*s, opt, ToneMap{}), 12.0, [&](int done, int total) {
        ++calls;
        EXPECT_EQ(total, 9);
        EXPECT_EQ(done, calls);
    });
    EXPECT_EQ(n, 9);
    ASSERT_TRUE(fs::exists(path));
    EXPECT_GT(fs::file_size(path), 0u);
    std::string out;
    ASSERT_EQ(run("ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames,width,height "
                  "-of csv=p=0 '" +
                      path + "'",
                  out),
              0)
        << out;
    EXPECT_EQ(out, "38,22,9\n") << "37x21 padded to even, 9 frames";
    expectNoTemporaries(tmp.path());
    opt.step = 4;  // bins 0, 4, 8
    EXPECT_EQ(exportMp4(*s, path, opt, ToneMap{}, 24.0), 3);
    ASSERT_EQ(
        run("ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 '" +
                path + "'",
            out),
        0);
    EXPECT_EQ(out, "3\n");
}

TEST(VideoEncoder, MissingFfmpegIsAUserErrorSayingHowToInstallIt) {
    test::TempDir empty("nopath");
    const PathScope path(empty.path().string());
    EXPECT_EQ(findExecutable("ffmpeg"), "");
    try {
        VideoEncoder enc((empty / "x.mp4").string(), 4, 4, 24.0);
        FAIL() << "no error";
    } catch (const UserError& e) {
        EXPECT_STREQ(e.what(), "ffmpeg not found on PATH: install it with apt-get install ffmpeg, or drop --mp4");
    }
    EXPECT_TRUE(fs::is_empty(empty.path()));
}

TEST(VideoEncoder, FfmpegFailureReportsItsStderrAndLeavesNoFile) {
    test::TempDir tmp("ffail");
    // A stand-in ffmpeg that reads a little, complains and fails.
    const fs::path fake =
        tmp.write("ffmpeg", "#!/bin/sh\nhead -c 10 >/dev/null\necho 'Unknown encoder libx264' >&2\nexit 3\n");
    fs::permissions(fake, fs::perms::owner_all);
    const PathScope path(tmp.path().string() + ":/usr/bin:/bin");
    const std::string out = (tmp / "x.mp4").string();
    try {
        VideoEncoder enc(out, 64, 64, 24.0);
        std::vector<unsigned char> frame(64 * 64 * 3, 100);
        for (int i = 0; i < 50; ++i) enc.addFrame(frame.data());  // it stops reading: EPIPE, not SIGPIPE
        enc.finish();
        FAIL() << "no error";
    } catch (const UserError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("exit code 3"), std::string::npos) << m;
        EXPECT_NE(m.find("Unknown encoder libx264"), std::string::npos) << m;
    }
    EXPECT_FALSE(fs::exists(out));
    expectNoTemporaries(tmp.path());
}

TEST(VideoEncoder, CancelKillsFfmpegAndLeavesNoHalfWrittenMp4) {
    if (findExecutable("ffmpeg").empty()) GTEST_SKIP() << "ffmpeg not on PATH (apt-get install ffmpeg)";
    const auto s = snapshot();
    test::TempDir tmp("mp4cancel");
    std::atomic<bool> cancel{false};
    const int n = exportMp4(
        *s, (tmp / "t.mp4").string(), ExportOptions{}, ToneMap{}, 24.0,
        [&](int done, int) {
            if (done == 4) cancel = true;
        },
        &cancel);
    EXPECT_EQ(n, 0);
    EXPECT_FALSE(fs::exists(tmp / "t.mp4"));
    expectNoTemporaries(tmp.path());
}

// One set of export names for `tpb render` (untagged) and the viewer (tagged with the axis, the
// emission and, when not delta/ideal, the pulse and sensor).
TEST(OutputNames, UntaggedForTheCliTaggedForTheViewer) {
    EXPECT_EQ(frameName(12), "frame_00012.exr");
    EXPECT_EQ(mp4Name(), "transient.mp4");
    EXPECT_EQ(contactSheetName(), "contact_sheet.png");
    const std::string tag = outputTag(TimeAxis::Unwarped, EmissionMode::Continuous);
    EXPECT_EQ(tag, "unwarped_continuous");
    EXPECT_EQ(frameName(12, tag), "frame_00012_unwarped_continuous.exr");
    EXPECT_EQ(framesDirName(tag), "frames_unwarped_continuous");
    EXPECT_EQ(streakName(31, tag), "streak_row0031_unwarped_continuous.exr");
    EXPECT_EQ(profileName(12, 40, tag), "profile_x12_y40_unwarped_continuous.csv");
    EXPECT_EQ(volumeDirName(tag), "volume_unwarped_continuous");
    EXPECT_EQ(mp4Name(tag), "transient_unwarped_continuous.mp4");
    EXPECT_EQ(contactSheetName(tag), "contact_sheet_unwarped_continuous.png");
    const TimeResponse r = *parseSensor("exp:0.1", *parsePulse("gaussian:0.5"));
    EXPECT_EQ(outputTag(TimeAxis::Real, EmissionMode::Delta, r), "real_delta_pulse-gaussian0.5_sensor-exp0.1");
}
