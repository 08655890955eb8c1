// Film views (core/film/film_view.h) against brute force on a snapshot of synthetic passes: the
// continuous frame read from the prefix sums is before + the sum of the delta bins for every bin,
// and frame, pixel profile, streak and volume agree value for value in both emission modes.
#include "film/film_view.h"
#include "film_test_passes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

using namespace tpb;

namespace {

// 37x21 pixels: tiles that are and are not full; 9 bins.
std::shared_ptr<const FilmSnapshot> threePassSnapshot() {
    static const std::unique_ptr<TransientFilm> film = [] {
        auto f = std::make_unique<TransientFilm>(37, 21, TimeBins{2.0, 0.25, 9});
        for (uint64_t p = 1; p <= 3; ++p) test::addRandomPass(*f, 11, p);
        return f;
    }();
    return film->snapshot();
}

}  // namespace

// Continuous frame k = before + sum of delta bins 0..k, for every k and both axes: once against
// the film's raw sums in double (the same additions: equal to the last bit), once against the
// float delta frames summed independently (equal up to their float rounding).
TEST(FilmView, ContinuousFrameIsBeforePlusTheDeltaBinsSoFar) {
    const auto s = threePassSnapshot();
    const int W = s->width(), H = s->height(), B = s->bins();
    for (int a = 0; a < 2; ++a) {
        const TimeAxis axis = static_cast<TimeAxis>(a);
        const std::vector<float> before = beforeImage(*s, axis);
        std::vector<double> sumDelta(before.begin(), before.end());  // float frames, summed in double
        std::vector<double> raw(static_cast<size_t>(W) * H * 3);     // raw sums, summed in double
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                const int t = s->tileOf(x, y);
                const TileRect& r = s->tileRect(t);
                const size_t pix = static_cast<size_t>(y - r.y0) * r.w + (x - r.x0);
                for (int c = 0; c < 3; ++c)
                    raw[(static_cast<size_t>(y) * W + x) * 3 + c] = s->block(t).sums.before[a][pix * 3 + c];
            }
        double maxRel = 0.0;
        for (int k = 0; k < B; ++k) {
            const std::vector<float> delta = frameImage(*s, k, axis, EmissionMode::Delta);
            const std::vector<float> cont = frameImage(*s, k, axis, EmissionMode::Continuous);
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    const int t = s->tileOf(x, y);
                    const TileRect& r = s->tileRect(t);
                    const size_t pix = static_cast<size_t>(y - r.y0) * r.w + (x - r.x0);
                    for (int c = 0; c < 3; ++c) {
                        const size_t i = (static_cast<size_t>(y) * W + x) * 3 + c;
                        raw[i] += s->block(t).sums.bins[a][s->block(t).sums.binIndex(pix, k) + c];
                        sumDelta[i] += delta[i];
                        EXPECT_EQ(cont[i], static_cast<float>(raw[i] * (1.0 / 3.0))) << x << "," << y << " bin " << k;
                        maxRel =
                            std::max(maxRel, std::abs(cont[i] - sumDelta[i]) / std::max(1e-30, std::abs(sumDelta[i])));
                    }
                }
        }
        EXPECT_LT(maxRel, 1e-5) << "axis " << a;
    }
}

// The last continuous frame is everything but what arrived after the film: steady - after.
TEST(FilmView, LastContinuousFrameIsSteadyMinusAfter) {
    const auto s = threePassSnapshot();
    const std::vector<float> steady = steadyImage(*s);
    for (int a = 0; a < 2; ++a) {
        const std::vector<float> after = afterImage(*s, static_cast<TimeAxis>(a));
        const std::vector<float> last =
            frameImage(*s, s->bins() - 1, static_cast<TimeAxis>(a), EmissionMode::Continuous);
        for (size_t i = 0; i < steady.size(); ++i)
            EXPECT_NEAR(last[i], steady[i] - after[i], 1e-5 * steady[i] + 1e-7) << i;
    }
}

// One value, four readers: frame(k)[x, y] == profile(x, y)[k] == streak(y)[k, x] == volume[x, y, k],
// in both emission modes and on both axes (the prefix sums and the running sums add the same terms
// in the same order).
TEST(FilmView, FrameProfileStreakAndVolumeAgree) {
    const auto s = threePassSnapshot();
    const int W = s->width(), H = s->height(), B = s->bins();
    for (int a = 0; a < 2; ++a)
        for (EmissionMode mode : {EmissionMode::Delta, EmissionMode::Continuous}) {
            const TimeAxis axis = static_cast<TimeAxis>(a);
            const std::vector<double> vol = volume(*s, axis, mode);
            std::vector<std::vector<float>> frames;
            for (int k = 0; k < B; ++k) frames.push_back(frameImage(*s, k, axis, mode));
            for (int y = 0; y < H; ++y) {
                const std::vector<float> streak = streakImage(*s, y, axis, mode);
                for (int x = 0; x < W; ++x) {
                    const std::vector<float> prof = pixelProfile(*s, x, y, axis, mode);
                    for (int k = 0; k < B; ++k)
                        for (int c = 0; c < 3; ++c) {
                            const float f = frames[k][(static_cast<size_t>(y) * W + x) * 3 + c];
                            EXPECT_EQ(prof[k * 3 + c], f);
                            EXPECT_EQ(streak[(static_cast<size_t>(k) * W + x) * 3 + c], f);
                            EXPECT_EQ(static_cast<float>(vol[((static_cast<size_t>(y) * W + x) * B + k) * 3 + c]), f);
                        }
                }
            }
        }
}

// Outside the film: zeros (no exception, no read out of range); a bin past the end is clamped.
TEST(FilmView, OutOfRangeReadsAreZerosOrClamped) {
    const auto s = threePassSnapshot();
    for (float v : pixelProfile(*s, -1, 0, TimeAxis::Real, EmissionMode::Delta)) EXPECT_EQ(v, 0.0f);
    for (float v : pixelProfile(*s, 0, s->height(), TimeAxis::Real, EmissionMode::Delta)) EXPECT_EQ(v, 0.0f);
    for (float v : streakImage(*s, s->height(), TimeAxis::Real, EmissionMode::Delta)) EXPECT_EQ(v, 0.0f);
    EXPECT_EQ(frameImage(*s, 99, TimeAxis::Real, EmissionMode::Delta),
              frameImage(*s, s->bins() - 1, TimeAxis::Real, EmissionMode::Delta));
}

// The energy per bin is the luminance of the delta frame summed over the image.
TEST(FilmView, BinEnergyIsTheFramesLuminance) {
    const auto s = threePassSnapshot();
    const std::vector<double> e = binEnergy(*s, TimeAxis::Unwarped);
    ASSERT_EQ(e.size(), static_cast<size_t>(s->bins()));
    for (int k = 0; k < s->bins(); ++k) {
        const std::vector<float> f = frameImage(*s, k, TimeAxis::Unwarped, EmissionMode::Delta);
        double sum = 0.0;
        for (size_t p = 0; p < f.size(); p += 3) sum += 0.2126 * f[p] + 0.7152 * f[p + 1] + 0.0722 * f[p + 2];
        EXPECT_NEAR(e[k], sum, 1e-12 * sum) << k;
        EXPECT_GT(e[k], 0.0) << k;
    }
}

// With a stride (the viewer's automatic bin: every 4th pixel in x and y), the same sums over the
// pixels whose coordinates are multiples of the stride, tiles full and partial (37x21 px).
TEST(FilmView, StridedBinEnergyIsTheLuminanceOfEveryStrideThPixel) {
    const auto s = threePassSnapshot();
    for (int stride : {2, 4, 5}) {
        const std::vector<double> e = binEnergy(*s, TimeAxis::Real, stride);
        ASSERT_EQ(e.size(), static_cast<size_t>(s->bins()));
        for (int k = 0; k < s->bins(); ++k) {
            const std::vector<float> f = frameImage(*s, k, TimeAxis::Real, EmissionMode::Delta);
            double sum = 0.0, all = 0.0;
            for (int y = 0; y < s->height(); ++y)
                for (int x = 0; x < s->width(); ++x) {
                    const size_t p = (static_cast<size_t>(y) * s->width() + x) * 3;
                    const double l = 0.2126 * f[p] + 0.7152 * f[p + 1] + 0.0722 * f[p + 2];
                    all += l;
                    if (x % stride == 0 && y % stride == 0) sum += l;
                }
            EXPECT_NEAR(e[k], sum, 1e-12 * sum) << stride << " " << k;
            EXPECT_GT(e[k], 0.0) << stride << " " << k;
            EXPECT_LT(e[k], 0.5 * all) << stride << " " << k;  // a subset, not the whole image
        }
    }
}
