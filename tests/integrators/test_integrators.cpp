// Every integrator (integrators/integrator.h) on the analytic scenes, run the way the CLI and the
// viewer run them: through the Driver, one film per run, read from its snapshots (film_view.h).
// Physically-based methods (photon beams, the path tracer) are a TEST_P over Method, the geometry
// preview has its own checks:
//   1. a diffuse plane under a point light in vacuum: per-pixel steady radiance against the closed
//      form averaged over the pixel (and, for beams, over the surface kernel's disc), and every
//      pixel's energy in the bins of its arrival times on both time axes;
//   2. single scattering in an infinite homogeneous medium against the quadrature oracle
//      singleScatteringReference (eval/reference.h), steady image and per-bin volume;
//   3. energy conservation in a closed diffuse sphere with the light at its centre (furnace);
//   4. what the Driver promises for every method: pass i depends only on (seed, i) (passes 1..4 =
//      merge of passes 1,2 and 3,4; passes 1,3 = passes 3,1), the film does not depend on the
//      thread count, an abort before a pass drops it and leaves the film as it was;
//   5. the preview's one pass is renderPreview() in the steady image, with nothing in the bins.
//
// The references are written here from the formulas (own pixel-footprint and kernel-disc
// quadratures); only Camera::generate (raster to ray) and the quadrature oracle of test 2 are shared
// with the renderer. Statistical checks are z-tests on pixel means over independent passes (the
// standard error from the spread of the passes), with fixed seeds.
#include "eval/reference.h"
#include "film/film_view.h"
#include "integrators/integrator.h"
#include "integrators/preview.h"
#include "render/driver.h"
#include "scene/scene.h"
#include "support/scene_builder.h"

#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

using namespace tpb;
using tpb::test::SceneBuilder;

namespace {

// ---- scene setup: the one place that turns a description into what a render needs ---------------
// (the scene, its settings for `method`, the film's time axis: when settings and the time axis come
// from elsewhere, e.g. a prepareRender(), only this function changes).

struct RenderSetup {
    std::unique_ptr<const Scene> scene;
    RenderSettings settings;
    TimeBins time;  // the film's time axis
};

RenderSetup prepare(const SceneDesc& desc, Method method) {
    test::TestScene t = test::prepareTestScene(desc);
    RenderSetup s;
    s.scene = std::move(t.scene);
    s.settings = t.settings;
    s.settings.method = method;
    s.time = t.time;
    return s;
}

// ---- rendering and reading films ---------------------------------------------------------------

constexpr double kPiT = 3.14159265358979323846;

struct FilmValues {
    std::vector<double> real, unwarped;  // delta volume, pixel-major ((y W + x) bins + k) 3
    std::vector<float> steady;           // W H 3
    std::vector<float> before[2], after[2];
};

// Everything a test compares, read from one snapshot through the views (film_view.h).
FilmValues read(const FilmSnapshot& snap) {
    FilmValues v;
    v.real = volume(snap, TimeAxis::Real, EmissionMode::Delta);
    v.unwarped = volume(snap, TimeAxis::Unwarped, EmissionMode::Delta);
    v.steady = steadyImage(snap);
    for (TimeAxis a : {TimeAxis::Real, TimeAxis::Unwarped}) {
        v.before[static_cast<int>(a)] = beforeImage(snap, a);
        v.after[static_cast<int>(a)] = afterImage(snap, a);
    }
    return v;
}

// Passes 1..n, each in its own film (pass i depends only on (seed, i), test 4), so that the steady
// image of every pass is an independent sample; the volumes are averaged over the passes.
struct PassSeries {
    int W = 0, H = 0, bins = 0, passes = 0;
    std::vector<std::vector<float>> steady;                  // per pass, W H 3
    std::vector<std::vector<double>> realPass, unwarpedPass;  // per pass, delta volumes
    std::vector<double> real, unwarped;                      // mean over passes
    std::vector<PassStats> stats;                            // per pass

    size_t pixels() const { return static_cast<size_t>(W) * H; }
    struct MeanSe { double mean, se; };
    // Mean over passes and its standard error of pixel p's channel c (steady image).
    MeanSe pixel(size_t p, int c) const {
        std::vector<double> v;
        for (const auto& img : steady) v.push_back(img[p * 3 + c]);
        return meanSe(v);
    }
    // The same for volume value i on one axis.
    MeanSe bin(TimeAxis axis, size_t i) const {
        std::vector<double> v;
        for (const auto& vol : axis == TimeAxis::Real ? realPass : unwarpedPass) v.push_back(vol[i]);
        return meanSe(v);
    }
    static MeanSe meanSe(const std::vector<double>& v) {
        const double n = static_cast<double>(v.size());
        double mean = 0.0, ss = 0.0;
        for (double x : v) mean += x / n;
        for (double x : v) ss += (x - mean) * (x - mean);
        return {mean, std::sqrt(ss / (n - 1.0) / n)};
    }
};

PassSeries renderPasses(const RenderSetup& s, int passes) {
    PassSeries r;
    r.W = s.scene->camera.width;
    r.H = s.scene->camera.height;
    r.bins = s.time.bins;
    r.passes = passes;
    for (int p = 1; p <= passes; ++p) {
        Driver drv(*s.scene, s.settings, s.time);
        EXPECT_TRUE(drv.runPass(static_cast<uint64_t>(p)));
        FilmValues v = read(*drv.snapshot());
        if (r.real.empty()) {
            r.real.assign(v.real.size(), 0.0);
            r.unwarped.assign(v.unwarped.size(), 0.0);
        }
        for (size_t i = 0; i < v.real.size(); ++i) {
            r.real[i] += v.real[i] / passes;
            r.unwarped[i] += v.unwarped[i] / passes;
        }
        r.realPass.push_back(std::move(v.real));
        r.unwarpedPass.push_back(std::move(v.unwarped));
        r.steady.push_back(std::move(v.steady));
        r.stats.push_back(drv.lastPass());
    }
    return r;
}

// z of a mean against a reference; `relFloor` adds a standard error of relFloor * ref for what the
// reference itself is only known to (its quadrature), so a noiseless estimate is not held to 1e-16.
double zScore(const PassSeries::MeanSe& m, double ref, double relFloor) {
    const double se = std::sqrt(m.se * m.se + (relFloor * ref) * (relFloor * ref));
    return (m.mean - ref) / std::max(se, 1e-300);
}

// Sub-pixel sample positions of pixel (x, y): n x n stratum centres (quadrature of the box filter,
// which is what the integrators' uniform jitter in [x, x+1) x [y, y+1) averages over).
template <class Fn>
void overPixel(int x, int y, int n, Fn&& fn) {
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) fn(x + (i + 0.5) / n, y + (j + 0.5) / n, 1.0 / (n * n));
}

const char* methodLabel(Method m) { return methodName(m); }

class PhysicalIntegrator : public ::testing::TestWithParam<Method> {};
class AnyIntegrator : public ::testing::TestWithParam<Method> {};

}  // namespace

// ---- 1. diffuse plane under a point light in vacuum -----------------------------------------------
//
// Derivation. A point light of power Phi (W) radiates Phi / (4 pi) W/sr in every direction; at a
// plane point x at distance d = |l - x|, with cos(theta_l) = (l - x).n / d, the irradiance is
// E(x) = Phi cos(theta_l) / (4 pi d^2). A Lambertian surface of albedo a reflects L = (a / pi) E(x)
// in every direction. The plane is the only surface and nothing comes back to it (its reflected
// light leaves for infinity), so that is the whole answer; a pixel's value is L averaged over the
// points its footprint sees (quadrature overPixel). Light that leaves at emitOpl arrives at x at
// emitOpl + |l - x| (the unwarped axis) and at the camera at emitOpl + |l - x| + |x - camera| (the
// real axis, vacuum: OPL = distance).
//
// The path tracer's next-event estimate is that L exactly at each jittered sub-pixel point. The
// beams' surface photon estimate with a fixed radius rs (alpha = 1) is the photon power inside the
// sphere of radius rs around x divided by pi rs^2: on the plane, its expectation is E averaged over
// the disc of radius rs (kernel bias, computed exactly below instead of being bounded); each photon
// arrives at its own landing OPL, so its time is off by at most rs on both axes.
//
// Fails if: a factor (pi, 4 pi, the cosine, the albedo) is wrong or missing in either estimator, the
// pixel filter is not the box the camera jitter promises, the kernel area or photon power
// normalisation is off, or times are binned on the wrong axis or with the camera leg missing/doubled.
namespace {

struct PlaneScene {
    Vec3 camera{0.0, 1.2, 1.6}, light{0.2, 0.9, 0.1};
    Color power{3.0, 2.0, 1.0};
    double albedo = 0.6, emitOpl = 0.1;
    double binWidth = 0.1;  // m
    int bins = 80;          // 0 .. 8 m: every arrival (< 7.5 m on the real axis) is in the film
    int W = 16, H = 16;
    double surfaceRadius = 0.1;  // m, beams

    SceneDesc desc() const {
        SceneBuilder b;
        b.camera(camera, Vec3(0.0), 40.0, W, H).film(0.0, binWidth, bins);
        // 8 m x 8 m, normal +y: the view covers |x| < 1.6, -2.4 < z < 0.9 of it (checked in the
        // test), so the kernel never reaches its edges.
        b.quad(Vec3(-4, 0, -4), Vec3(0, 0, 8), Vec3(8, 0, 0), b.diffuse(Color(albedo)));
        b.pointLight(light, power, emitOpl);
        return b.desc();
    }
    // Irradiance per unit power at plane point x (y = 0).
    double irradiance(const Vec3& x) const {
        const Vec3 v = light - x;
        const double d = glm::length(v);
        return (v.y / d) / (4.0 * kPiT * d * d);
    }
    // Irradiance averaged over the disc of radius r around x: midpoints of 16 rings of equal area
    // times 32 angles (E is smooth at the scale r; the quadrature error is < 1e-5 relative).
    double discIrradiance(const Vec3& x, double r) const {
        const int nr = 16, na = 32;
        double s = 0.0;
        for (int i = 0; i < nr; ++i) {
            const double rho = r * std::sqrt((i + 0.5) / nr);
            for (int j = 0; j < na; ++j) {
                const double phi = 2.0 * kPiT * (j + 0.5) / na;
                s += irradiance(x + Vec3(rho * std::cos(phi), 0.0, rho * std::sin(phi)));
            }
        }
        return s / (nr * na);
    }
};

Vec3 hitPlane(const Ray& r) { return r.o - (r.o.y / r.d.y) * r.d; }

}  // namespace

TEST_P(PhysicalIntegrator, DiffusePlaneUnderPointLightMatchesClosedForm) {
    const Method method = GetParam();
    const bool beams = method == Method::Beams;
    PlaneScene ps;
    RenderSetup s = prepare(ps.desc(), method);
    s.settings.seed = 5;
    s.settings.threads = 2;
    s.settings.samplesPerPixel = 4;
    s.settings.photonsPerPass = 200000;
    s.settings.surfaceRadius0 = ps.surfaceRadius;
    s.settings.alpha = 1.0;  // fixed radius: the expectation is the disc average below
    const int passes = 16;
    const PassSeries r = renderPasses(s, passes);
    const Camera& cam = s.scene->camera;

    // Steady image, per pixel and channel: z-test of the pass mean against the reference (path
    // tracer: only the sub-pixel jitter is random, the floor 1e-4 covers the 8x8 quadrature's error,
    // below the jitter noise; beams:
    // Poisson noise of the ~25 (far corner) to ~600 (under the light) photons per disc per pass,
    // i.e. 5 % to 20 % per pass, 1.3 % to 5 % for the mean of 16). 768 z values: |z| < 5 each
    // (P(|z| > 5) ~ 6e-7 for a normal mean, a Student t_15 has heavier tails: ~2e-4, 0.15 expected
    // failures), their mean square within [0.5, 1.8] (~ chi2_768 / 768 inflated by t_15's variance
    // 15/13: 1.15 +- 0.06), and the image total within 4 of its own standard error.
    double z2 = 0.0, sumMean = 0.0, sumRef = 0.0;
    int nz = 0, worst = 0;
    double worstZ = 0.0;
    std::vector<double> totalPerPass(passes, 0.0);
    for (int y = 0; y < ps.H; ++y)
        for (int x = 0; x < ps.W; ++x) {
            double e = 0.0;
            overPixel(x, y, 8, [&](double px, double py, double w) {
                const Vec3 p = hitPlane(cam.generate(px, py));
                ASSERT_LT(std::max(std::abs(p.x), std::abs(p.z)), 3.0);  // > 1 m from the plane's edges
                e += w * (beams ? ps.discIrradiance(p, ps.surfaceRadius) : ps.irradiance(p));
            });
            const size_t pix = static_cast<size_t>(y) * ps.W + x;
            for (int c = 0; c < 3; ++c) {
                const double ref = ps.albedo / kPiT * ps.power[c] * e;
                const PassSeries::MeanSe m = r.pixel(pix, c);
                const double z = zScore(m, ref, 1e-4);
                EXPECT_LT(std::abs(z), 5.0) << methodLabel(method) << " pixel " << x << "," << y << " channel " << c
                                            << ": " << m.mean << " +- " << m.se << " vs " << ref;
                z2 += z * z;
                ++nz;
                if (std::abs(z) > std::abs(worstZ)) worstZ = z, worst = static_cast<int>(pix);
                sumMean += m.mean;
                sumRef += ref;
                for (int p = 0; p < passes; ++p) totalPerPass[p] += r.steady[p][pix * 3 + c];
            }
        }
    double tm = 0.0, t2 = 0.0;
    for (double v : totalPerPass) tm += v / passes, t2 += v * v;
    const double totalSe = std::sqrt(std::max(0.0, (t2 - passes * tm * tm) / (passes - 1.0)) / passes);
    std::printf("%s plane: mean z^2 %.3f over %d, worst z %.2f at pixel %d, total %.6g vs %.6g (%.2g se)\n",
                methodLabel(method), z2 / nz, nz, worstZ, worst, sumMean, sumRef, (sumMean - sumRef) / totalSe);
    EXPECT_GT(z2 / nz, 0.5);  // too small: the standard errors are overestimated (or passes repeat)
    EXPECT_LT(z2 / nz, 1.8);
    EXPECT_LT(std::abs(sumMean - sumRef), 4.0 * std::sqrt(totalSe * totalSe + 1e-8 * sumRef * sumRef));
    if (beams) {  // the disc average is the expectation; it differs from the point value by < 1.5 %
        double point = 0.0, disc = 0.0;
        overPixel(ps.W / 2, ps.H / 2, 4, [&](double px, double py, double) {
            const Vec3 p = hitPlane(cam.generate(px, py));
            point += ps.irradiance(p);
            disc += ps.discIrradiance(p, ps.surfaceRadius);
        });
        EXPECT_NEAR(disc / point, 1.0, 0.015);
    }

    // Time: per pixel, the arrival OPL on each axis over the footprint (9 x 9 points including its
    // edges; the extremes between them are missed by < 2e-5 m), widened by the kernel's time blur
    // (beams: a photon lands up to rs from x, so its OPL is off by up to rs) and 1e-3 m. Every bin
    // outside that window must be empty, and the window's bins must hold all of the steady energy
    // (nothing before or after the film).
    const double blur = (beams ? ps.surfaceRadius : 0.0) + 1e-3;
    for (int y = 0; y < ps.H; ++y)
        for (int x = 0; x < ps.W; ++x) {
            double lo[2] = {kInf, kInf}, hi[2] = {-kInf, -kInf};
            for (int j = 0; j <= 8; ++j)
                for (int i = 0; i <= 8; ++i) {
                    const Ray ray = cam.generate(x + i / 8.0, y + j / 8.0);
                    const Vec3 p = hitPlane(ray);
                    const double tu = ps.emitOpl + glm::length(ps.light - p), tr = tu + glm::length(p - cam.position);
                    lo[0] = std::min(lo[0], tr), hi[0] = std::max(hi[0], tr);
                    lo[1] = std::min(lo[1], tu), hi[1] = std::max(hi[1], tu);
                }
            const size_t pix = static_cast<size_t>(y) * ps.W + x;
            double steady = 0.0;
            for (int p = 0; p < passes; ++p) steady += r.steady[p][pix * 3 + 1] / passes;
            for (int ax = 0; ax < 2; ++ax) {
                const std::vector<double>& vol = ax == 0 ? r.real : r.unwarped;
                const int k0 = s.time.binOf(lo[ax] - blur), k1 = s.time.binOf(hi[ax] + blur);
                ASSERT_GE(k0, 0);
                ASSERT_LT(k1, s.time.bins);
                double inside = 0.0, outside = 0.0;
                for (int k = 0; k < s.time.bins; ++k) {
                    const double v = vol[(pix * s.time.bins + k) * 3 + 1];
                    (k >= k0 && k <= k1 ? inside : outside) += v;
                }
                EXPECT_EQ(outside, 0.0) << methodLabel(method) << (ax == 0 ? " real" : " unwarped") << " pixel " << x
                                        << "," << y << ": energy outside bins " << k0 << ".." << k1;
                EXPECT_NEAR(inside, steady, 1e-5 * steady) << methodLabel(method) << " pixel " << x << "," << y;
            }
        }
}

// ---- 2. single scattering in an infinite homogeneous medium ----------------------------------------
//
// The quadrature oracle singleScatteringReference integrates, along every camera ray (4 x 4 rays per
// pixel), sigma_s e^{-sigma_t s} p(cos) Phi / (4 pi d(s)^2) e^{-sigma_t d(s)} ds binned at
// OPL emit + s + d(s) (real) and emit + d(s) (unwarped): an independent implementation of the same
// integral. The light is outside the view (11.3 deg off the axis, half field of view 6 deg), so the
// closest camera ray passes 0.28 m from it: the beams' kernel (r = 0.03) sees no singularity. The
// film (0..8 m, 0.2 m bins) holds both axes' arrivals up to 8 m.
//
// Tolerances. Steady image: per pixel z-tests of the pass means, with a floor of 1 % for the
// quadrature (4 x 4 rays per pixel) and, for beams, the kernel bias (~ r^2 / 0.28^2 ~ 1 % at most);
// the mean of the 300 z^2 below 2 (path tracer: independent pixels, ~ chi2_300 / 300 = 1 +- 0.1,
// inflated by t_15) or 3.5 (beams: one beam crosses many pixels, so their z are correlated and
// heavy-tailed, a beam passing close to a camera ray being rare and large; measured 0.8 to 2.5 over
// seeds 11-15); the image total within 4 standard errors (+ the 1 % floor). Volume: relative RMSE
// over all bins within 1.5 x the noise-only RMSE (from the spread of the passes, per value) plus
// 0.02 for the bias and bin-edge blur, and below 0.15 outright so a noisy estimator cannot pass.
// The beams' per-pass totals are skewed (mean of seeds 11-15 at 20000 photons: -1.6 %, at 40000:
// -0.3 %): their deviation shrinks with the photon count, as an unbiased but heavy-tailed noise.
// Fails if: phase function, transmittance, 1/d^2, the beam kernel's normalisation or its time profile
// along the beam are wrong; if the two time axes are swapped.
TEST_P(PhysicalIntegrator, SingleScatteringMatchesQuadratureOracle) {
    const Method method = GetParam();
    const bool beams = method == Method::Beams;
    SceneBuilder b;
    b.camera(Vec3(0, 0, 3), Vec3(0.6, 0, 0), 12.0, 10, 10).film(0.0, 0.2, 40);
    b.globalMedium(b.medium(Color(0.4), Color(0.1), 0.3));
    b.pointLight(Vec3(0.0), Color(10.0, 8.0, 6.0), 0.0);
    RenderSetup s = prepare(b.desc(), method);
    s.settings.seed = 11;
    s.settings.threads = 2;
    s.settings.maxDepth = 1;  // single scattering only
    s.settings.samplesPerPixel = 32;
    s.settings.photonsPerPass = 20000;
    s.settings.beamRadius0 = 0.03;
    s.settings.alpha = 1.0;
    const int passes = 16;
    const PassSeries r = renderPasses(s, passes);
    const ReferenceVolume ref = singleScatteringReference(*s.scene, s.time, "test.json", s.settings, 4, 2);

    // Steady image: per pixel, and the image total (its standard error from the passes' totals).
    double z2 = 0.0;
    int nz = 0;
    for (size_t p = 0; p < r.pixels(); ++p)
        for (int c = 0; c < 3; ++c) {
            const PassSeries::MeanSe m = r.pixel(p, c);
            const double z = zScore(m, ref.steady[p * 3 + c], 0.01);
            EXPECT_LT(std::abs(z), 5.0) << methodLabel(method) << " pixel " << p << " channel " << c << ": " << m.mean
                                        << " +- " << m.se << " vs " << ref.steady[p * 3 + c];
            z2 += z * z;
            ++nz;
        }
    std::printf("%s single scattering: mean z^2 %.3f over %d\n", methodLabel(method), z2 / nz, nz);
    EXPECT_LT(z2 / nz, beams ? 3.5 : 2.0) << methodLabel(method);
    for (int c = 0; c < 3; ++c) {
        std::vector<double> totals;
        for (const auto& img : r.steady) {
            double t = 0.0;
            for (size_t p = 0; p < r.pixels(); ++p) t += img[p * 3 + c];
            totals.push_back(t);
        }
        double refTotal = 0.0;
        for (size_t p = 0; p < r.pixels(); ++p) refTotal += ref.steady[p * 3 + c];
        const PassSeries::MeanSe m = PassSeries::meanSe(totals);
        std::printf("%s single scattering, channel %d: steady total %.5f +- %.5f vs %.5f\n", methodLabel(method), c,
                    m.mean, m.se, refTotal);
        EXPECT_LT(std::abs(zScore(m, refTotal, 0.01)), 4.0) << methodLabel(method) << " channel " << c;
    }

    // Volume, both axes: relative RMSE against the noise-only RMSE, sqrt(sum se^2 / sum ref^2) with
    // each value's standard error from the spread of the passes.
    for (TimeAxis axis : {TimeAxis::Real, TimeAxis::Unwarped}) {
        const std::vector<double>& vol = axis == TimeAxis::Real ? r.real : r.unwarped;
        const std::vector<float>& rv = ref.volume(axis);
        double e2 = 0.0, r2 = 0.0, n2 = 0.0, sumFilm = 0.0, sumRef = 0.0;
        for (size_t i = 0; i < vol.size(); ++i) {
            const double se = r.bin(axis, i).se;
            e2 += (vol[i] - rv[i]) * (vol[i] - rv[i]);
            r2 += static_cast<double>(rv[i]) * rv[i];
            n2 += se * se;
            sumFilm += vol[i];
            sumRef += rv[i];
        }
        const double rmse = std::sqrt(e2 / r2), noise = std::sqrt(n2 / r2);
        std::printf("%s single scattering, %s axis: relative RMSE %.4f (noise alone %.4f), energy ratio %.4f\n",
                    methodLabel(method), axis == TimeAxis::Real ? "real" : "unwarped", rmse, noise, sumFilm / sumRef);
        EXPECT_LT(rmse, 1.5 * noise + 0.02) << methodLabel(method);
        EXPECT_LT(rmse, 0.15) << methodLabel(method);
    }
}

// ---- 3. energy conservation: diffuse sphere furnace ------------------------------------------------
//
// A point light of power Phi at the centre of a closed diffuse sphere (radius R, albedo a): the
// direct irradiance is E0 = Phi / (4 pi R^2) everywhere; a Lambertian wall of uniform radiance
// sends the same irradiance to every point of the sphere (the form factor from any patch to dA is
// dA / (4 pi R^2)), so every bounce multiplies the uniform irradiance by a: E = E0 / (1 - a) and the
// radiance of every wall point is L = a E / pi = a Phi / (4 pi^2 R^2 (1 - a)). Depth 64 truncates
// the series at a^64. Beams: the photons inside a sphere of radius rs around a wall point lie on a
// cap of area exactly pi rs^2 (Archimedes: cap area 2 pi R h with h = rs^2 / (2 R)), so the kernel
// has no bias here. The unwarped axis: the first light reaches the wall at emit + R, nothing earlier.
// Fails if: energy is lost or created per bounce (roulette weights, albedo applied twice, photon
// power not divided by the photon count), or the first arrival is not at emit + R.
TEST_P(PhysicalIntegrator, FurnaceSphereConservesEnergy) {
    const Method method = GetParam();
    const double R = 1.0, a = 0.5, emit = 0.12;
    const Color power(4.0 * kPiT, 2.0 * kPiT, 8.0 * kPiT);
    SceneBuilder b;
    b.camera(Vec3(0.1, 0.0, 0.5), Vec3(0.0, 0.0, -1.0), 60.0, 16, 16).film(0.0, 0.05, 80);
    b.sphere(Vec3(0.0), R, b.diffuse(Color(a)));
    b.pointLight(Vec3(0.0), power, emit);
    RenderSetup s = prepare(b.desc(), method);
    s.settings.seed = 9;
    s.settings.threads = 2;
    s.settings.maxDepth = 64;
    s.settings.samplesPerPixel = 4;
    s.settings.photonsPerPass = 40000;
    s.settings.surfaceRadius0 = 0.08;
    s.settings.alpha = 1.0;
    const int passes = 12;
    const PassSeries r = renderPasses(s, passes);
    const Color expected = a * power / (4.0 * kPiT * kPiT * R * R * (1.0 - a));

    // Image mean per channel: z-test over passes (|z| < 4) and within 3 %.
    for (int c = 0; c < 3; ++c) {
        std::vector<double> perPass(passes, 0.0);
        for (int p = 0; p < passes; ++p)
            for (size_t i = 0; i < r.pixels(); ++i) perPass[p] += r.steady[p][i * 3 + c] / r.pixels();
        double m = 0.0, m2 = 0.0;
        for (double v : perPass) m += v / passes, m2 += v * v;
        const double se = std::sqrt(std::max(0.0, (m2 - passes * m * m) / (passes - 1.0)) / passes);
        std::printf("%s furnace channel %d: %.5f +- %.5f vs %.5f\n", methodLabel(method), c, m, se, expected[c]);
        EXPECT_LT(std::abs(m - expected[c]), 4.0 * se + 1e-4 * expected[c]) << methodLabel(method) << " channel " << c;
        EXPECT_NEAR(m / expected[c], 1.0, 0.03) << methodLabel(method) << " channel " << c;
    }
    // Causality on the unwarped axis (beams: photons land at their own OPL, >= emit + R - 0 since
    // the wall is at distance R exactly; the kernel only moves the gather point, not the photon).
    const int kFirst = s.time.binOf(emit + R);
    double early = 0.0, total = 0.0;
    for (size_t p = 0; p < r.pixels(); ++p)
        for (int k = 0; k < r.bins; ++k) {
            const double v = r.unwarped[(p * r.bins + k) * 3 + 1];
            (k < kFirst ? early : total) += v;
        }
    EXPECT_EQ(early, 0.0) << methodLabel(method);
    EXPECT_GT(total, 0.0) << methodLabel(method);
}

INSTANTIATE_TEST_SUITE_P(Methods, PhysicalIntegrator, ::testing::Values(Method::Beams, Method::PathTracer),
                         [](const ::testing::TestParamInfo<Method>& i) { return std::string(methodName(i.param)); });

// ---- 4. what the Driver promises for every integrator ----------------------------------------------
//
// A small scene with everything the integrators handle: fog (photon beams, medium paths), a diffuse
// floor and sphere (surface photons, diffuse bounces), four film tiles (32 x 24 pixels).
namespace {

SceneDesc consistencyScene() {
    SceneBuilder b;
    b.camera(Vec3(0.0, 1.0, 3.0), Vec3(0.0, 0.6, 0.0), 45.0, 32, 24).film(1.0, 0.25, 24);
    b.globalMedium(b.medium(Color(0.3, 0.35, 0.4), Color(0.05), 0.2));
    const int white = b.diffuse(Color(0.7));
    b.quad(Vec3(-3, 0, -3), Vec3(0, 0, 6), Vec3(6, 0, 0), white);
    b.sphere(Vec3(0.3, 0.5, -0.2), 0.5, b.diffuse(Color(0.6, 0.3, 0.2)));
    b.pointLight(Vec3(-0.5, 1.6, 0.5), Color(20.0, 18.0, 15.0), 0.0);
    return b.desc();
}

RenderSetup consistencySetup(Method method, int threads) {
    RenderSetup s = prepare(consistencyScene(), method);
    s.settings.seed = 21;
    s.settings.threads = threads;
    s.settings.maxDepth = 4;
    s.settings.photonsPerPass = 3000;
    s.settings.beamRadius0 = 0.05;
    s.settings.surfaceRadius0 = 0.08;
    s.settings.samplesPerPixel = 1;
    return s;
}

void expectIdentical(const FilmValues& a, const FilmValues& b, const char* what) {
    EXPECT_EQ(a.real, b.real) << what;
    EXPECT_EQ(a.unwarped, b.unwarped) << what;
    EXPECT_EQ(a.steady, b.steady) << what;
    for (int ax = 0; ax < 2; ++ax) {
        EXPECT_EQ(a.before[ax], b.before[ax]) << what;
        EXPECT_EQ(a.after[ax], b.after[ax]) << what;
    }
}

double sumOf(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s;
}

}  // namespace

// The film must not depend on the thread count: pass i's random numbers are keyed by (seed, i,
// pixel / photon), tiles are written by one thread each, counters are summed in tile order.
// Fails if: an integrator keeps per-thread random state, or sums photons in thread order.
TEST_P(AnyIntegrator, FilmDoesNotDependOnThreadCount) {
    const Method method = GetParam();
    FilmValues v[2];
    for (int t = 0; t < 2; ++t) {
        const RenderSetup s = consistencySetup(method, t + 1);
        Driver drv(*s.scene, s.settings, s.time);
        for (uint64_t p = 1; p <= 2; ++p) ASSERT_TRUE(drv.runPass(p));
        v[t] = read(*drv.snapshot());
    }
    if (method != Method::Preview) {
        EXPECT_GT(sumOf(v[0].real), 0.0) << methodLabel(method);
    }
    expectIdentical(v[0], v[1], methodLabel(method));
}

// Pass i depends only on (seed, i): a film of passes 1..4 equals the merge of a film of passes 1, 2
// and a film of passes 3, 4 (TransientFilm::merge adds the double sums and pass counts: one extra
// rounding per value, so 1e-12 relative; values below 1e-300 absolute compare as equal). Fails if:
// an integrator carries state from one pass to the next (a random stream, a radius that shrinks per
// call instead of per pass index, photons of an earlier pass), or merge drops pass counts.
TEST_P(AnyIntegrator, PassesOneToFourAreTheMergeOfOneTwoAndThreeFour) {
    const Method method = GetParam();
    const RenderSetup s = consistencySetup(method, 2);
    Driver all(*s.scene, s.settings, s.time), first(*s.scene, s.settings, s.time), second(*s.scene, s.settings, s.time);
    for (uint64_t p = 1; p <= 4; ++p) ASSERT_TRUE(all.runPass(p));
    for (uint64_t p = 1; p <= 2; ++p) ASSERT_TRUE(first.runPass(p));
    for (uint64_t p = 3; p <= 4; ++p) ASSERT_TRUE(second.runPass(p));
    first.film().merge(second.film());
    EXPECT_EQ(first.film().minPasses(), 4);
    const FilmValues a = read(*all.snapshot()), m = read(*first.snapshot());
    auto close = [](double x, double y) {
        return std::abs(x - y) <= 1e-12 * std::max(std::abs(x), std::abs(y)) + 1e-300;
    };
    for (int ax = 0; ax < 2; ++ax) {
        const std::vector<double>& va = ax == 0 ? a.real : a.unwarped;
        const std::vector<double>& vm = ax == 0 ? m.real : m.unwarped;
        ASSERT_EQ(va.size(), vm.size());
        size_t bad = 0, firstBad = 0;
        for (size_t i = 0; i < va.size(); ++i)
            if (!close(va[i], vm[i]) && bad++ == 0) firstBad = i;
        EXPECT_EQ(bad, 0u) << methodLabel(method) << (ax == 0 ? " real" : " unwarped") << ": first at " << firstBad
                           << ": " << va[firstBad] << " vs " << vm[firstBad];
    }
    // Steady, before and after are read as float images: equal up to the float conversion of two
    // doubles 1e-12 apart (one float ulp: at most 2^-23 = 1.2e-7 relative, checked at 2.4e-7).
    auto closeF = [](float x, float y) { return std::abs(x - y) <= 2.4e-7f * std::max(std::abs(x), std::abs(y)); };
    for (size_t i = 0; i < a.steady.size(); ++i)
        ASSERT_TRUE(closeF(a.steady[i], m.steady[i])) << methodLabel(method) << " " << i;
    for (int ax = 0; ax < 2; ++ax)
        for (size_t i = 0; i < a.before[ax].size(); ++i) {
            ASSERT_TRUE(closeF(a.before[ax][i], m.before[ax][i])) << methodLabel(method) << " " << i;
            ASSERT_TRUE(closeF(a.after[ax][i], m.after[ax][i])) << methodLabel(method) << " " << i;
        }
    if (method != Method::Preview) {
        EXPECT_GT(sumOf(a.real), 0.0) << methodLabel(method);
    }
}

// Pass i depends only on (seed, i), so the order passes run in does not matter: a film of passes 3
// then 1 is the film of passes 1 then 3, bit for bit (each sum is 0 + x + y, and floating-point
// addition is commutative). Fails if: an integrator carries state from one pass to the next (a
// random stream, a radius shrunk per call instead of per pass index, photons of an earlier pass).
TEST_P(AnyIntegrator, PassOrderDoesNotMatter) {
    const Method method = GetParam();
    const RenderSetup s = consistencySetup(method, 2);
    FilmValues v[2];
    const uint64_t order[2][2] = {{1, 3}, {3, 1}};
    for (int o = 0; o < 2; ++o) {
        Driver drv(*s.scene, s.settings, s.time);
        for (uint64_t p : order[o]) ASSERT_TRUE(drv.runPass(p));
        v[o] = read(*drv.snapshot());
    }
    expectIdentical(v[0], v[1], methodLabel(method));
}

// An abort requested before a pass (Driver::stop sets the abort flag) makes runPass return false and
// drops the pass: the film is what the earlier passes left. Fails if: beginPass or the tile loop
// ignores the flag, or a dropped pass still adds its tiles.
TEST_P(AnyIntegrator, AbortBeforeAPassLeavesTheFilmUnchanged) {
    const Method method = GetParam();
    const RenderSetup s = consistencySetup(method, 2);
    Driver drv(*s.scene, s.settings, s.time);
    ASSERT_TRUE(drv.runPass(1));
    const FilmValues before = read(*drv.snapshot());
    const int64_t passesBefore = drv.film().minPasses();
    drv.stop();  // no background run: only sets the abort flag
    EXPECT_FALSE(drv.runPass(2)) << methodLabel(method);
    EXPECT_EQ(drv.film().minPasses(), passesBefore);
    EXPECT_EQ(drv.history().size(), 1u);
    expectIdentical(before, read(*drv.snapshot()), methodLabel(method));
}

INSTANTIATE_TEST_SUITE_P(Methods, AnyIntegrator,
                         ::testing::Values(Method::Beams, Method::PathTracer, Method::Preview),
                         [](const ::testing::TestParamInfo<Method>& i) { return std::string(methodName(i.param)); });

// ---- 5. the preview ---------------------------------------------------------------------------------
//
// One pass of the preview integrator is renderPreview() (integrators/preview.h) in the steady image,
// and no light transport: every bin, and before/after, empty. Fails if: the integrator shades other
// pixels than renderPreview, or writes time bins.
TEST(PreviewIntegrator, OnePassIsRenderPreviewWithEmptyBins) {
    const RenderSetup s = consistencySetup(Method::Preview, 2);
    Driver drv(*s.scene, s.settings, s.time);
    ASSERT_TRUE(drv.runPass(1));
    const FilmValues v = read(*drv.snapshot());
    const std::vector<float> preview = renderPreview(*s.scene, 2);
    ASSERT_EQ(v.steady.size(), preview.size());
    EXPECT_EQ(v.steady, preview);
    double lit = 0.0;
    for (float x : preview) lit += x;
    EXPECT_GT(lit, 0.0);
    for (double x : v.real) ASSERT_EQ(x, 0.0);
    for (double x : v.unwarped) ASSERT_EQ(x, 0.0);
    for (int ax = 0; ax < 2; ++ax) {
        for (float x : v.before[ax]) ASSERT_EQ(x, 0.0f);
        for (float x : v.after[ax]) ASSERT_EQ(x, 0.0f);
    }
    EXPECT_EQ(drv.integrator().usefulPasses(), 1);
}
