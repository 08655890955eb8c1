// The phasor film on real renders (film/phasor.h, docs/theory/phasor.md): the steady image at
// f = 0, the same phasors whatever the bins, and the binned film's DFT converging to them as the
// bins shrink, while at frequencies near the coarse film's bin rate the coarse DFT is far off
// (aliasing). For both methods: photon beams (segments spread over time) and the path tracer
// (instants).
#include "film/film_view.h"
#include "render/driver.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>

using namespace tpb;

namespace {

// A fog cube lit by a point light inside it, seen from outside; a diffuse floor below. The film
// [0, 24 m) holds all but a negligible tail of the light (max_depth 3 in a 1.6 m scene).
const char* kScene = R"({
  "camera": {"position": [0, 0.3, 3.2], "look_at": [0, 0, 0], "fov": 40, "resolution": [24, 18]},
  "film": {"start_m": 0, "bin_width_m": 0.75, "bins": 32},
  "media": {"fog": {"sigma_s": 1.2, "sigma_a": 0.1, "g": 0.3}},
  "materials": {"air": {"type": "null"}, "floor": {"type": "diffuse", "albedo": 0.6}},
  "shapes": [
    {"name": "cube", "type": "box", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5], "material": "air",
     "interior_medium": "fog"},
    {"name": "floor", "type": "quad", "corner": [-1.5, -0.51, -1.5], "edge_u": [0, 0, 3], "edge_v": [3, 0, 0],
     "material": "floor"}
  ],
  "lights": [{"type": "point", "position": [0.1, 0.05, 0], "power": 10}],
  "render": {"photons_per_pass": 3000, "radius_relative": 0.03, "max_depth": 3, "passes": 4}
})";

struct Render {
    std::vector<double> phasor;  // [y][x][f][re, im][rgb]
    std::vector<double> volume;  // [y][x][k][rgb]
    std::vector<float> steady;
    TimeBins time;
    int width = 0, height = 0;
};

Render render(const std::string& method, int bins, const std::string& phasor, int passes) {
    SettingsOverrides o;
    o.method = parseMethod(method);
    o.bins = bins;
    o.phasor = phasor;
    o.passes = passes;
    o.threads = 2;
    const test::TestScene sc = test::testSceneFrom(kScene, "phasor_render.json", o);
    Driver drv(*sc, sc.settings, sc.time);
    for (int p = 1; p <= passes; ++p) EXPECT_TRUE(drv.runPass(static_cast<uint64_t>(p)));
    const std::shared_ptr<const FilmSnapshot> snap = drv.film().snapshot();
    Render r;
    r.phasor = phasorVolume(*snap, TimeAxis::Real);
    r.volume = volume(*snap, TimeAxis::Real, EmissionMode::Delta);
    r.steady = steadyImage(*snap);
    r.time = sc.time;
    r.width = snap->width();
    r.height = snap->height();
    return r;
}

// Sum over pixels and channels of |DFT of the bins at f - P(f)|, and of the steady image.
double dftError(const Render& r, int fi, double f, int nf) {
    double err = 0.0;
    const size_t pixels = static_cast<size_t>(r.width) * r.height;
    for (size_t p = 0; p < pixels; ++p)
        for (int c = 0; c < 3; ++c) {
            std::complex<double> d(0.0, 0.0);
            for (int k = 0; k < r.time.bins; ++k) {
                const double tc = r.time.startOpl + (k + 0.5) * r.time.binWidth;
                d += r.volume[(p * r.time.bins + k) * 3 + c] *
                     std::exp(std::complex<double>(0.0, -2.0 * kPi * f * (tc - r.time.startOpl)));
            }
            const size_t i = (p * nf + fi) * 6;
            const std::complex<double> exact(r.phasor[i + c], r.phasor[i + 3 + c]);
            err += std::abs(d - exact);
        }
    return err;
}

double total(const std::vector<float>& img) {
    double s = 0.0;
    for (float v : img) s += v;
    return s;
}

}  // namespace

class PhasorRender : public ::testing::TestWithParam<const char*> {};

TEST_P(PhasorRender, ExactPhasorsDoNotDependOnTheBinsAndTheBinnedDftConvergesToThem) {
    const std::string method = GetParam();
    // Coarse bins 0.75 m (Nyquist 0.667 cycles/m); frequencies well below it, near it and at the bin rate.
    const double coarse = 0.75;
    const std::vector<double> freqs = {0.0, 0.1, 0.6, 1.0 / coarse};
    const std::string list = "0,0.1,0.6," + std::to_string(1.0 / coarse);
    const int passes = method == "pt" ? 2 : 3;
    const Render a = render(method, 32, list, passes), b = render(method, 512, list, passes);
    ASSERT_EQ(a.phasor.size(), b.phasor.size());
    ASSERT_EQ(a.phasor.size(), static_cast<size_t>(a.width) * a.height * freqs.size() * 6);
    // The same estimates, whatever the bins: the same sums, bit for bit.
    EXPECT_EQ(a.phasor, b.phasor);
    // P(0) is the steady image (float rounding of the image).
    const int nf = static_cast<int>(freqs.size());
    double worst = 0.0;
    for (size_t p = 0; p < a.steady.size() / 3; ++p)
        for (int c = 0; c < 3; ++c) {
            worst = std::max(worst, std::abs(a.phasor[p * nf * 6 + c] - a.steady[p * 3 + c]) /
                                        (1e-30 + std::abs(a.steady[p * 3 + c])));
            EXPECT_EQ(a.phasor[p * nf * 6 + 3 + c], 0.0);
        }
    EXPECT_LT(worst, 1e-6);
    const double steady = total(a.steady);
    ASSERT_GT(steady, 0.0);
    // The DFT at bin centres moves each arrival by at most half a bin, a phase of at most pi f D:
    // |DFT - P| <= 2 sin(pi f D / 2) of the energy inside the film, plus the light outside it
    // (which the bins miss). The exact film must lie within that bound of every DFT; the fine DFT
    // is much closer than the coarse one, which near the coarse bin rate aliases (at
    // f = 1 / bin width it is the steady image).
    double binned = 0.0;
    for (double v : b.volume) binned += v;
    const double outside = std::max(0.0, 1.0 - binned / steady);
    EXPECT_LT(outside, 0.01);
    for (int fi = 1; fi < nf; ++fi) {
        const double f = freqs[fi];
        const double eCoarse = dftError(a, fi, f, nf) / steady;
        const double eFine = dftError(b, fi, f, nf) / steady;
        const double boundFine = 2.0 * std::sin(0.5 * kPi * f * b.time.binWidth) + outside + 1e-6;
        SCOPED_TRACE(method + " f " + std::to_string(f) + ": coarse " + std::to_string(eCoarse) + " fine " +
                     std::to_string(eFine) + " bound " + std::to_string(boundFine));
        EXPECT_LT(eFine, 0.25 * eCoarse);
        EXPECT_LE(eFine, boundFine);
        if (freqs[fi] > 0.5) {
            EXPECT_GT(eCoarse, 0.1);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, PhasorRender, ::testing::Values("beams", "pt"));

TEST(PhasorSettings, BadFrequenciesAreRefusedByKeyOrFlagBeforeAnyPass) {
    std::string scene = kScene;
    const std::string film = R"("film": {"start_m": 0, "bin_width_m": 0.75, "bins": 32})";
    scene.replace(scene.find(film), film.size(),
                  R"("film": {"start_m": 0, "bin_width_m": 0.75, "bins": 32,
           "phasor": [1, -2]})");
    const std::string e = test::prepareError(scene, "bad.json");
    EXPECT_NE(e.find("bad.json:4: film.phasor"), std::string::npos) << e;
    EXPECT_NE(e.find(">= 0"), std::string::npos) << e;
    SettingsOverrides o;
    o.phasor = "band:0.001:0.01";  // wholly above the 32-bin film's Nyquist frequency
    const std::string f = test::prepareError(kScene, "ok.json", o);
    EXPECT_NE(f.find("--phasor"), std::string::npos) << f;
    EXPECT_NE(f.find("Nyquist"), std::string::npos) << f;
    o.phasor = "0.5";
    o.method = Method::Preview;
    EXPECT_NE(test::prepareError(kScene, "ok.json", o).find("preview has no time"), std::string::npos);
}
