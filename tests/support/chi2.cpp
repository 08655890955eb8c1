// Pearson chi-square goodness-of-fit tests (see chi2.h): histogram, per-cell adaptive Simpson
// integration of the pdf, pooling of cells expecting < 5 samples, and the p-value from the
// regularised incomplete gamma function.
#include "support/chi2.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <vector>

namespace tpb::test {

// ---- incomplete gamma ------------------------------------------------------------------------------

namespace {

// ln(x^a e^-x / Gamma(a)): the prefactor of both the series and the continued fraction.
double gammaPrefactorLog(double a, double x) { return -x + a * std::log(x) - std::lgamma(a); }

// P(a, x) = x^a e^-x / Gamma(a) * sum_n x^n / (a (a+1) ... (a+n)), for x < a + 1.
double gammaPSeries(double a, double x) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 100000; ++n) {
        term *= x / (a + n);
        sum += term;
        if (std::abs(term) < std::abs(sum) * 1e-17) break;
    }
    return sum * std::exp(gammaPrefactorLog(a, x));
}

// Q(a, x) = x^a e^-x / Gamma(a) * 1 / (x + 1 - a - 1 (1 - a) / (x + 3 - a - 2 (2 - a) / (x + 5 - a - ...))),
// for x >= a + 1, evaluated with the modified Lentz method.
double gammaQContinuedFraction(double a, double x) {
    constexpr double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1.0 / d;
        const double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1.0) < 1e-16) break;
    }
    return std::exp(gammaPrefactorLog(a, x)) * h;
}

}  // namespace

double regularizedGammaP(double a, double x) {
    if (!(a > 0.0) || !(x >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
    if (x == 0.0) return 0.0;
    return x < a + 1.0 ? gammaPSeries(a, x) : 1.0 - gammaQContinuedFraction(a, x);
}

double regularizedGammaQ(double a, double x) {
    if (!(a > 0.0) || !(x >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
    if (x == 0.0) return 1.0;
    return x < a + 1.0 ? 1.0 - gammaPSeries(a, x) : gammaQContinuedFraction(a, x);
}

double chi2PValue(double x, int dof) { return regularizedGammaQ(0.5 * dof, 0.5 * x); }

double sidakSignificance(double alpha, int tests) { return -std::expm1(std::log1p(-alpha) / tests); }

// ---- integration -----------------------------------------------------------------------------------

namespace {

// Adaptive Simpson on [a, b] given f at a, m = (a + b) / 2, b and the Simpson estimate `whole`.
// At least `minDepth` levels of splitting, so that a narrow peak between the first nodes is seen.
double adaptiveSimpson(const std::function<double(double)>& f, double a, double b, double fa, double fm, double fb,
                       double whole, double tol, int depth, int minDepth) {
    const double m = 0.5 * (a + b), lm = 0.5 * (a + m), rm = 0.5 * (m + b);
    const double flm = f(lm), frm = f(rm);
    const double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm), right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    const double diff = left + right - whole;
    if (depth >= 40 || (depth >= minDepth && std::abs(diff) <= 15.0 * tol)) return left + right + diff / 15.0;
    return adaptiveSimpson(f, a, m, fa, flm, fm, left, 0.5 * tol, depth + 1, minDepth) +
           adaptiveSimpson(f, m, b, fm, frm, fb, right, 0.5 * tol, depth + 1, minDepth);
}

}  // namespace

double integrate1D(const std::function<double(double)>& f, double a, double b, double tol) {
    if (!(b > a)) return 0.0;
    const double fa = f(a), fm = f(0.5 * (a + b)), fb = f(b);
    const double whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    return adaptiveSimpson(f, a, b, fa, fm, fb, whole, tol, 0, 3);
}

double integrate2D(const Pdf2D& f, const Domain2D& d, double tol) {
    const double innerTol = tol / std::max(d.x1 - d.x0, 1e-300);
    return integrate1D([&](double x) { return integrate1D([&](double y) { return f(x, y); }, d.y0, d.y1, innerTol); },
                       d.x0, d.x1, tol);
}

// ---- the test --------------------------------------------------------------------------------------

std::string Chi2Result::summary() const {
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "chi2 = %.3f, dof = %d, p = %.3g (reject below %.3g): %s; pdf integral %.8f, %lld samples outside "
                  "the domain, %lld where the pdf is 0, %d cells pooled",
                  statistic, dof, pValue, significance, rejected ? "REJECTED" : "accepted", pdfIntegral,
                  static_cast<long long>(outside), static_cast<long long>(impossible), pooledCells);
    return buf;
}

Chi2Result chi2Test2D(const Sampler2D& sample, const Pdf2D& pdf, const Domain2D& dom, const Chi2Settings& s) {
    Chi2Result r;
    r.significance = sidakSignificance(s.alpha, s.testCount);
    const int nx = s.binsX, ny = s.binsY;
    const double wx = dom.x1 - dom.x0, wy = dom.y1 - dom.y0;
    // Points within rounding of the domain's edges count as inside (a direction normalised in
    // one frame and measured in another can land 1e-16 past cos theta = 1).
    const double slackX = 1e-12 * wx, slackY = 1e-12 * wy;

    // Observed counts.
    std::vector<int64_t> observed(static_cast<size_t>(nx) * ny, 0);
    Rng rng(s.seed, Stream::Test, 0, 0);
    for (int64_t i = 0; i < s.samples; ++i) {
        const Point2D p = sample(rng);
        if (!(p.x >= dom.x0 - slackX && p.x <= dom.x1 + slackX && p.y >= dom.y0 - slackY && p.y <= dom.y1 + slackY)) {
            ++r.outside;
            continue;
        }
        const int ix = std::clamp(static_cast<int>((p.x - dom.x0) / wx * nx), 0, nx - 1);
        const int iy = std::clamp(static_cast<int>((p.y - dom.y0) / wy * ny), 0, ny - 1);
        ++observed[static_cast<size_t>(iy) * nx + ix];
    }

    // Expected counts: N times the integral of the pdf over each cell.
    std::vector<double> expected(observed.size());
    for (int iy = 0; iy < ny; ++iy) {
        for (int ix = 0; ix < nx; ++ix) {
            const Domain2D cell{dom.x0 + wx * ix / nx, dom.x0 + wx * (ix + 1) / nx, dom.y0 + wy * iy / ny,
                                dom.y0 + wy * (iy + 1) / ny};
            const double mass = integrate2D(pdf, cell, s.integrationTol / (static_cast<double>(nx) * ny));
            r.pdfIntegral += mass;
            expected[static_cast<size_t>(iy) * nx + ix] = mass * static_cast<double>(s.samples);
        }
    }

    // Pool the cells expecting fewer than minExpected samples, smallest first; what is left in the
    // pool at the end joins the last cell emitted.
    std::vector<size_t> order(observed.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    double poolObs = 0.0, poolExp = 0.0, lastObs = 0.0, lastExp = 0.0;
    int cells = 0, poolSize = 0;
    auto term = [](double o, double e) { return (o - e) * (o - e) / e; };
    for (const size_t c : order) {
        if (!(expected[c] > 0.0)) {
            r.impossible += observed[c];
            continue;
        }
        poolObs += static_cast<double>(observed[c]);
        poolExp += expected[c];
        ++poolSize;
        if (poolExp >= s.minExpected) {
            if (poolSize > 1) r.pooledCells += poolSize;
            r.statistic += term(poolObs, poolExp);
            lastObs = poolObs;
            lastExp = poolExp;
            ++cells;
            poolObs = poolExp = 0.0;
            poolSize = 0;
        }
    }
    if (poolSize > 0) {
        r.pooledCells += poolSize;
        if (cells > 0) {
            r.statistic += term(lastObs + poolObs, lastExp + poolExp) - term(lastObs, lastExp);
        } else {
            r.statistic += term(poolObs, poolExp);
            cells = 1;
        }
    }
    r.dof = cells - 1;
    r.pValue = r.dof > 0 ? chi2PValue(r.statistic, r.dof) : 0.0;
    r.rejected = r.outside > 0 || r.impossible > 0 || r.dof < 1 || !(r.pValue >= r.significance);
    if (std::getenv("TPB_CHI2_VERBOSE")) std::fprintf(stderr, "%s\n", r.summary().c_str());
    return r;
}

Chi2Result chi2Test1D(const std::function<double(Rng&)>& sample, const std::function<double(double)>& pdf, double x0,
                      double x1, Chi2Settings s) {
    s.binsY = 1;
    return chi2Test2D(
        [&](Rng& rng) {
            return Point2D{sample(rng), 0.5};
        },
        [&](double x, double) { return pdf(x); }, Domain2D{x0, x1, 0.0, 1.0}, s);
}

DirectionFrame::DirectionFrame(const Vec3& axis) {
    n = glm::normalize(axis);
    const Vec3 helper = std::abs(n.x) > 0.9 ? Vec3(0.0, 1.0, 0.0) : Vec3(1.0, 0.0, 0.0);
    t = glm::normalize(glm::cross(helper, n));
    b = glm::cross(n, t);
}

Point2D DirectionFrame::toSpherical(const Vec3& w) const {
    double phi = std::atan2(glm::dot(w, b), glm::dot(w, t));
    if (phi < 0.0) phi += 2.0 * kPi;
    return {glm::dot(w, n), phi};
}

Vec3 DirectionFrame::fromSpherical(double cosTheta, double phi) const {
    const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
    return sinTheta * std::cos(phi) * t + sinTheta * std::sin(phi) * b + cosTheta * n;
}

Chi2Result chi2TestDirections(const std::function<Vec3(Rng&)>& sample, const std::function<double(const Vec3&)>& pdfW,
                              const Vec3& axis, double cosMin, const Chi2Settings& s) {
    const DirectionFrame frame(axis);
    return chi2Test2D([&](Rng& rng) { return frame.toSpherical(sample(rng)); },
                      [&](double cosTheta, double phi) { return pdfW(frame.fromSpherical(cosTheta, phi)); },
                      sphericalDomain(cosMin), s);
}

}  // namespace tpb::test
