// Pearson chi-square goodness-of-fit tests for sampling routines, in the style of the chi-square
// tests of Mitsuba 3 (src/python/python/chi2.py) and pbrt: N samples are histogrammed over a
// rectangular 2D domain, the pdf is integrated over every cell (nested adaptive Simpson), cells with
// fewer than 5 expected samples are pooled, and the statistic
//     X^2 = sum_cells (observed - expected)^2 / expected,   dof = cells - 1
// is compared with the chi-square distribution: p = Q(dof / 2, X^2 / 2), Q the regularised upper
// incomplete gamma function. The null hypothesis "the samples follow the pdf" is rejected when
// p < the per-test significance, the overall significance Sidak-corrected for the number of tests
// run: alpha_1 = 1 - (1 - alpha)^(1 / tests).
//
// With the environment variable TPB_CHI2_VERBOSE set, every test prints its Chi2Result::summary().
//
// Directions are tested in spherical coordinates (cos theta, phi) around an axis, where
// d omega = d cos(theta) d phi, so the density over that rectangle is the solid-angle pdf pdfW.
#pragma once
#include "base/math.h"
#include "base/rng.h"

#include <cstdint>
#include <functional>
#include <string>

namespace tpb::test {

// Regularised gamma functions P(a, x) = gamma(a, x) / Gamma(a) and Q = 1 - P, a > 0, x >= 0
// (series for x < a + 1, Lentz continued fraction otherwise).
double regularizedGammaP(double a, double x);
double regularizedGammaQ(double a, double x);
// Upper tail of the chi-square distribution with `dof` degrees of freedom: P(X^2 >= x).
double chi2PValue(double x, int dof);
// Per-test significance for `tests` independent tests at overall significance `alpha` (Sidak).
double sidakSignificance(double alpha, int tests);

// The rectangle [x0, x1] x [y0, y1] a sampler's points lie in.
struct Domain2D {
    double x0 = 0.0, x1 = 1.0, y0 = 0.0, y1 = 1.0;
};
// (cos theta, phi) in [cosMin, 1] x [0, 2 pi): the sphere (cosMin = -1), the hemisphere (0), a cone.
inline Domain2D sphericalDomain(double cosMin = -1.0) { return {cosMin, 1.0, 0.0, 2.0 * kPi}; }

struct Point2D {
    double x = 0.0, y = 0.0;
};

struct Chi2Settings {
    int binsX = 32, binsY = 32;
    int64_t samples = 500000;
    uint64_t seed = 1;
    double minExpected = 5.0;       // cells expecting fewer samples are pooled
    double alpha = 0.01;            // overall significance ...
    int testCount = 1;              // ... shared by this many tests (Sidak)
    double integrationTol = 1e-10;  // absolute tolerance of the per-cell adaptive Simpson
};

struct Chi2Result {
    double statistic = 0.0;
    int dof = 0;
    double pValue = 0.0;
    double significance = 0.0;  // the per-test threshold used
    bool rejected = true;
    double pdfIntegral = 0.0;  // integral of the pdf over the domain (1 for a normalised pdf)
    int64_t outside = 0;       // samples outside the domain or NaN (any rejects)
    int64_t impossible = 0;    // samples in cells where the pdf integrates to 0 (any rejects)
    int pooledCells = 0;       // cells pooled because they expected < minExpected
    std::string summary() const;
};

// One sample per call from `rng` (all the sampler's numbers must come from it).
using Sampler2D = std::function<Point2D(Rng& rng)>;
using Pdf2D = std::function<double(double x, double y)>;

// Integral of f over [x0, x1] x [y0, y1] (nested adaptive Simpson, absolute tolerance tol).
double integrate2D(const Pdf2D& f, const Domain2D& d, double tol = 1e-10);
// Integral of f over [a, b] (adaptive Simpson).
double integrate1D(const std::function<double(double)>& f, double a, double b, double tol = 1e-12);

Chi2Result chi2Test2D(const Sampler2D& sample, const Pdf2D& pdf, const Domain2D& domain, const Chi2Settings& s);

// A 1D sampler on [x0, x1] with pdf(x): chi2Test2D with one bin in y.
Chi2Result chi2Test1D(const std::function<double(Rng&)>& sample, const std::function<double(double)>& pdf, double x0,
                      double x1, Chi2Settings s);

// Directions around the unit axis `n`: each sample is mapped to (cos theta, phi) in a frame of
// the test's own (not the renderer's coordinateSystem), pdfW(w) is the solid-angle density.
struct DirectionFrame {
    Vec3 t, b, n;
    explicit DirectionFrame(const Vec3& axis);
    Point2D toSpherical(const Vec3& w) const;  // (cos theta, phi in [0, 2 pi))
    Vec3 fromSpherical(double cosTheta, double phi) const;
};
Chi2Result chi2TestDirections(const std::function<Vec3(Rng&)>& sample, const std::function<double(const Vec3&)>& pdfW,
                              const Vec3& axis, double cosMin, const Chi2Settings& s);

}  // namespace tpb::test
