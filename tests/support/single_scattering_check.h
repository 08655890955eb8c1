// A statistical comparison of a volume estimator's film with the single-scattering quadrature
// (eval/reference.h, singleScatteringReference) per pixel, bin and channel, on both time axes, for
// delta and continuous emission, with the film's per-pass variance (tests/estimators/test_point*.cpp).
//
// Passes are independent given (seed, pass) (render/driver.h), so each pass is rendered alone, in its
// own Driver, and its film read as one sample X_i of every cell (pixel, bin, channel). With a fixed
// kernel radius (alpha = 1) the samples are i.i.d.; their mean over P passes has the standard error
// se = sqrt(var / P) (var: the sample variance of the X_i), and
//   z_c = (mean_c - ref_c) / se_c
// is close to standard normal when the estimator's expectation equals the reference (its kernel
// bias, O(r^2), is kept well below se). The summary of a set of cells is
//   chi2PerDof = mean of z_c^2 over the cells            (about 1 +- sqrt(2 / cells))
//   zTotal     = (sum of the means - sum of the refs) / (se of the per-pass sums)   (a normalisation test)
// Continuous emission is the step response (film/transient_film.h): cell (p, k) is the running sum
// of bins 0..k plus what came before the film, which is nothing here (the film starts at 0); its
// cells are correlated, so only mean z^2 (still 1 in expectation) and zTotal are read from them.
#pragma once
#include "eval/reference.h"
#include "render/driver.h"
#include "support/test_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>
#include <cstdio>
#include <vector>

namespace tpb::test {

// Per-cell sums of X_i and X_i^2 over the passes, for one (axis, emission mode).
struct CellMoments {
    std::vector<double> sum, sum2;
    std::vector<int> hits;      // passes with a non-zero sample
    std::vector<Color> totals;  // per pass and channel: the sum of X_i over the cells (for zTotal)
    size_t bins = 1;            // the film's bins (cell index = (pixel * bins + bin) * 3 + channel)
};

struct PassMoments {
    int passes = 0;
    CellMoments cells[2][2];  // [axis][mode]: TimeAxis::Real / Unwarped, EmissionMode::Delta / Continuous
    CellMoments& at(TimeAxis a, EmissionMode m) { return cells[static_cast<int>(a)][m == EmissionMode::Delta ? 0 : 1]; }
    const CellMoments& at(TimeAxis a, EmissionMode m) const {
        return cells[static_cast<int>(a)][m == EmissionMode::Delta ? 0 : 1];
    }
};

// Renders passes 1..passes, each alone (its own Driver and film), and collects the moments.
inline PassMoments renderPassMoments(const Scene& scene, const RenderSettings& settings, const TimeBins& time,
                                     int passes) {
    PassMoments pm;
    pm.passes = passes;
    std::vector<double> v;
    for (int p = 1; p <= passes; ++p) {
        Driver drv(scene, settings, time);
        if (!drv.runPass(static_cast<uint64_t>(p))) return pm;
        for (TimeAxis a : {TimeAxis::Real, TimeAxis::Unwarped})
            for (EmissionMode m : {EmissionMode::Delta, EmissionMode::Continuous}) {
                drv.film().volume(a, m, v);
                CellMoments& c = pm.at(a, m);
                c.bins = static_cast<size_t>(time.bins);
                if (c.sum.empty()) {
                    c.sum.assign(v.size(), 0.0);
                    c.sum2.assign(v.size(), 0.0);
                    c.hits.assign(v.size(), 0);
                }
                Color total(0.0);
                for (size_t i = 0; i < v.size(); ++i) {
                    c.sum[i] += v[i];
                    c.sum2[i] += v[i] * v[i];
                    c.hits[i] += v[i] != 0.0;
                    total[static_cast<int>(i % 3)] += v[i];
                }
                c.totals.push_back(total);
            }
    }
    return pm;
}

// The reference's cells for (axis, mode), laid out as the film's volume (pixel, bin, channel).
inline std::vector<double> referenceCells(const ReferenceVolume& ref, TimeAxis axis, EmissionMode mode, int bins) {
    const std::vector<float>& r = ref.volume(axis);
    std::vector<double> out(r.begin(), r.end());
    if (mode == EmissionMode::Continuous) {
        const size_t pixels = out.size() / (static_cast<size_t>(bins) * 3);
        for (size_t p = 0; p < pixels; ++p)
            for (int c = 0; c < 3; ++c)
                for (int k = 1; k < bins; ++k) out[(p * bins + k) * 3 + c] += out[(p * bins + k - 1) * 3 + c];
    }
    return out;
}

struct CellTest {
    int cells = 0;            // cells compared (see compareCells)
    double chi2PerDof = 0.0;  // mean z^2
    double maxAbsZ = 0.0;
    double zTotal = 0.0;         // of the sum over all cells
    double totalRatio = 0.0;     // sum of the means / sum of the refs
    double totalRelError = 0.0;  // se of the total / the reference total: what a normalisation error must exceed
};

// Cells enter the per-cell statistics when the reference holds at least minShare of its largest
// cell and at least minHits passes put something in them (a cell that few passes reach has a
// heavy-tailed mean whose sample variance is no standard error, so its z would not be normal), and
// are not among the first `edgeBins` bins of their pixel that the reference lights: a kernel of
// radius r moves an estimate's time by up to eta r (the photon's time is that of a point within r of
// the ray), so the cells at a pixel's first-arrival edge carry the kernel's O(r) bias, and on the
// real axis they also hold the light scattered next to the camera, where every pixel's ray meets
// the same few photon points. Every cell counts in the totals. `scale` multiplies the film's means
// (a deliberately wrong normalisation, to show the test's power); `channel` restricts the test to
// one channel (-1: all).
inline CellTest compareCells(const CellMoments& m, int passes, const std::vector<double>& ref, double scale = 1.0,
                             int channel = -1, int edgeBins = 2, int minHits = 40, double minShare = 1e-3) {
    CellTest t;
    const double P = passes;
    const size_t B = m.bins, pixels = ref.size() / (3 * B);
    double refMax = 0.0;
    for (double r : ref) refMax = std::max(refMax, r);
    double z2 = 0.0;
    for (size_t p = 0; p < pixels; ++p) {
        size_t firstLit = B;
        for (size_t k = 0; k < B && firstLit == B; ++k)
            if (ref[(p * B + k) * 3] > 0.0 || ref[(p * B + k) * 3 + 1] > 0.0 || ref[(p * B + k) * 3 + 2] > 0.0)
                firstLit = k;
        for (size_t k = firstLit + static_cast<size_t>(edgeBins); k < B; ++k)
            for (int c = 0; c < 3; ++c) {
                const size_t i = (p * B + k) * 3 + static_cast<size_t>(c);
                if (channel >= 0 && c != channel) continue;
                if (!(ref[i] > minShare * refMax) || m.hits[i] < minHits) continue;
                const double mean = m.sum[i] / P;
                const double var = (m.sum2[i] / P - mean * mean) * P / (P - 1.0);
                if (!(var > 0.0)) continue;
                const double z = (scale * mean - ref[i]) / std::sqrt(var / P);
                if (std::getenv("TPB_CELLS_VERBOSE") && std::abs(z) > 4.0 && scale == 1.0 && channel < 0)
                    std::printf("  cell (pixel %zu, bin %zu, channel %d): mean %.6g ref %.6g se %.3g z %.2f\n", p, k, c,
                                mean, ref[i], std::sqrt(var / P), z);
                z2 += z * z;
                t.maxAbsZ = std::max(t.maxAbsZ, std::abs(z));
                ++t.cells;
            }
    }
    t.chi2PerDof = t.cells > 0 ? z2 / t.cells : 0.0;
    double refTotal = 0.0, sum = 0.0, sum2 = 0.0;
    for (size_t i = 0; i < ref.size(); ++i)
        if (channel < 0 || static_cast<int>(i % 3) == channel) refTotal += ref[i];
    for (const Color& c : m.totals) {
        const double x = channel < 0 ? c.x + c.y + c.z : c[channel];
        sum += x;
        sum2 += x * x;
    }
    const double mean = sum / P, var = (sum2 / P - mean * mean) * P / (P - 1.0);
    t.zTotal = (scale * mean - refTotal) / std::sqrt(var / P);
    t.totalRatio = scale * mean / refTotal;
    t.totalRelError = std::sqrt(var / P) / refTotal;
    return t;
}

inline void printCellTest(const char* what, const CellTest& t) {
    std::printf("%-34s cells %5d  chi2/dof %.3f  max|z| %.2f  total ratio %.4f (se %.4f, z %.2f)\n", what, t.cells,
                t.chi2PerDof, t.maxAbsZ, t.totalRatio, t.totalRelError, t.zTotal);
}

// The whole check of a volume estimator on a single-scattering scene (JSON): its film over `passes`
// independent passes against singleScatteringReference, on both axes, for delta and continuous
// emission: mean z^2 of the cells < 1.3 and |z| of each channel's total < 4, with a standard error
// of the totals below 1%. The power of these thresholds is checked on the same data: on each axis,
// delta or continuous emission (one film, read two ways) rejects the film scaled by 1.04 and a
// reference whose time runs 3% slower (the medium's eta x 1.03), so a normalisation or time-profile
// error of a few percent fails.
inline void expectSingleScatteringMatches(const std::string& json, const std::string& estimator, int passes) {
    const TestScene sc = testSceneFrom(json);
    std::string slowJson = json;
    const std::string iorKey = "\"ior\": ";
    const size_t at = slowJson.find(iorKey);
    ASSERT_NE(at, std::string::npos) << "the scene must give the medium's ior";
    const size_t end = slowJson.find_first_of(",}", at);
    slowJson.replace(at, end - at, iorKey + std::to_string(sc->regions[0].ior * 1.03));
    const TestScene slow = testSceneFrom(slowJson);
    ASSERT_NEAR(slow->regions[0].ior, 1.03 * sc->regions[0].ior, 1e-9);
    RenderSettings s = sc.settings;
    s.volumeEstimator = estimator;
    s.threads = 2;
    const int B = sc.time.bins;
    const PassMoments pm = renderPassMoments(*sc, s, sc.time, passes);
    ASSERT_EQ(pm.at(TimeAxis::Real, EmissionMode::Delta).totals.size(), static_cast<size_t>(passes));
    const ReferenceVolume ref = singleScatteringReference(*sc, sc.time, sc.source.path, sc.settings, 8, 2);
    const ReferenceVolume refSlow = singleScatteringReference(*slow, slow.time, slow.source.path, slow.settings, 8, 2);
    // Whether a comparison fails the thresholds: the cells' mean z^2, or one channel's total.
    const auto rejects = [&](const CellMoments& cm, const std::vector<double>& cells, double scale,
                             const std::string& what, bool expectPass) {
        const CellTest all = compareCells(cm, passes, cells, scale);
        printCellTest((what + ":").c_str(), all);
        bool rejected = all.chi2PerDof > 1.3;
        for (int c = 0; c < 3; ++c) {
            const CellTest ch = compareCells(cm, passes, cells, scale, c);
            std::printf("    channel %d: total ratio %.4f (se %.4f, z %.2f)\n", c, ch.totalRatio, ch.totalRelError,
                        ch.zTotal);
            rejected = rejected || std::abs(ch.zTotal) > 4.0;
            if (expectPass) {
                EXPECT_LT(std::abs(ch.zTotal), 4.0) << what << " channel " << c;
                EXPECT_LT(ch.totalRelError, 0.01) << what << " channel " << c;
            }
        }
        if (expectPass) {
            EXPECT_GT(all.cells, 500) << what;
            EXPECT_LT(all.chi2PerDof, 1.3) << what;
        }
        return rejected;
    };
    for (TimeAxis axis : {TimeAxis::Real, TimeAxis::Unwarped}) {
        bool brightRejected = false, lateRejected = false;
        const std::string axisName = estimator + (axis == TimeAxis::Real ? " real" : " unwarped");
        for (EmissionMode mode : {EmissionMode::Delta, EmissionMode::Continuous}) {
            const std::string what = axisName + (mode == EmissionMode::Delta ? " delta" : " continuous");
            const CellMoments& cm = pm.at(axis, mode);
            rejects(cm, referenceCells(ref, axis, mode, B), 1.0, what, true);
            brightRejected =
                rejects(cm, referenceCells(ref, axis, mode, B), 1.04, what + ", film x 1.04", false) || brightRejected;
            lateRejected =
                rejects(cm, referenceCells(refSlow, axis, mode, B), 1.0, what + ", time x 1.03", false) || lateRejected;
        }
        EXPECT_TRUE(brightRejected) << axisName << ": a film 4% too bright passes";
        EXPECT_TRUE(lateRejected) << axisName << ": a time axis 3% slow passes";
    }
}

}  // namespace tpb::test
