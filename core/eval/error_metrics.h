// Error metrics for convergence measurements (`tpb converge`, tests/eval/test_error_metrics.cpp).
//
// Relative RMSE of an estimate x against a reference r, over a set of entries i:
//     e(x, r) = sqrt( sum_i (x_i - r_i)^2 / sum_i r_i^2 )
// The entries are every RGB channel of every pixel and, for a transient volume, of every time bin
// of one time axis (delta emission: a bin holds the energy that arrives within it). The steady
// image uses every RGB channel of every pixel. Per frame: the same sum restricted to one bin.
// e is 0 for a perfect estimate and 1 for an all-black one; undefined (NaN) when the reference is
// all zero. It weighs bright entries more than a per-pixel relative error would, which keeps it
// meaningful where the reference is dark (most of a transient volume is).
//
// Error of a finite reference: if the reference is the mean of two independent halves a (na
// passes) and b (nb passes), each pass an unbiased estimate with the same variance, then
// E[(a - b)^2] = sigma^2 (1/na + 1/nb) and the variance of the full mean is sigma^2 / (na + nb),
// so the relative RMSE of the reference itself is estimated by
//     e_ref = sqrt( na nb / (na + nb)^2 * sum_i (a_i - b_i)^2 / sum_i r_i^2 )
// (halfSplitRelativeError). An estimate x independent of the reference then measures
// E[e(x, r)^2] ~ e_true^2 + e_ref^2, so errors below ~e_ref cannot be measured against it;
// noiseCorrected() subtracts that floor in quadrature.
#pragma once
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace tpb {

// Running sums of a relative RMSE.
struct SquaredError {
    double diff2 = 0.0, ref2 = 0.0;
    void add(double x, double r) {
        const double d = x - r;
        diff2 += d * d;
        ref2 += r * r;
    }
    void add(const SquaredError& o) {
        diff2 += o.diff2;
        ref2 += o.ref2;
    }
    // sqrt(diff2 / ref2); NaN when the reference is all zero.
    double relative() const { return ref2 > 0.0 ? std::sqrt(diff2 / ref2) : std::numeric_limits<double>::quiet_NaN(); }
};

// Running sums of a relative mean absolute error sum |x - r| / sum |r| (robust to rare huge
// samples, which dominate the RMSE of heavy-tailed estimators).
struct AbsoluteError {
    double diff = 0.0, ref = 0.0;
    void add(double x, double r) {
        diff += std::abs(x - r);
        ref += std::abs(r);
    }
    void add(const AbsoluteError& o) {
        diff += o.diff;
        ref += o.ref;
    }
    double relative() const { return ref > 0.0 ? diff / ref : std::numeric_limits<double>::quiet_NaN(); }
};

template <class X, class R>
SquaredError squaredError(const X* x, const R* ref, size_t n) {
    SquaredError e;
    for (size_t i = 0; i < n; ++i) e.add(static_cast<double>(x[i]), static_cast<double>(ref[i]));
    return e;
}

// e(x, ref) over all entries (the arrays must have the same size; a mismatch is a bug).
double relativeRmse(const std::vector<double>& x, const std::vector<double>& ref);
double relativeRmse(const std::vector<float>& x, const std::vector<float>& ref);
double relativeRmse(const std::vector<double>& x, const std::vector<float>& ref);

// Per-frame e of a volume laid out as TransientFilm::volume: ((pixel * bins) + k) * 3 + c.
std::vector<double> perFrameRelativeRmse(const std::vector<double>& x, const std::vector<float>& ref, int bins);

// (sum x - sum ref) / sum ref: the signed relative difference of the totals (energy bias).
double relativeTotalDifference(const std::vector<double>& x, const std::vector<double>& ref);
double relativeTotalDifference(const std::vector<float>& x, const std::vector<float>& ref);

// Relative RMSE of the mean of two independent half estimates (see the top of this file).
// `diff2` = sum (a - b)^2, `ref2` = sum full^2 where full = (na a + nb b) / (na + nb).
double halfSplitRelativeError(double diff2, double ref2, double na, double nb);

// sqrt(max(0, measured^2 - floor^2)): the error of an estimate against the truth, estimated from
// its error against a reference whose own error is `floor` (independent estimates). NaN if
// `floor` is unknown (negative or NaN) or `measured` is NaN.
double noiseCorrected(double measured, double floor);

// Least-squares fit of log(e) = intercept + slope log(t) over the points with t > 0 and e > 0
// (others skipped). points < 2 or all t equal: slope NaN.
struct PowerLawFit {
    double slope = std::numeric_limits<double>::quiet_NaN();
    double intercept = std::numeric_limits<double>::quiet_NaN();  // log(e) at t = 1
    int points = 0;
    double at(double t) const { return std::exp(intercept + slope * std::log(t)); }
    // Time at which the fitted line reaches e (NaN if the slope is not negative).
    double timeFor(double e) const {
        return slope < 0.0 ? std::exp((std::log(e) - intercept) / slope) : std::numeric_limits<double>::quiet_NaN();
    }
};
PowerLawFit fitPowerLaw(const std::vector<double>& t, const std::vector<double>& e);
// The fit over the second half of the points in time order: the last ceil(n / 2) (n >= 4 gives
// at least 2 points; with n < 4, the last 2 points).
PowerLawFit fitPowerLawSecondHalf(const std::vector<double>& t, const std::vector<double>& e);

// Piecewise linear interpolation in log-log of the curve (t_i, e_i) (t increasing):
// value at time T (NaN outside [t_0, t_n-1]), and the first time the curve reaches `target`
// (e <= target; NaN if it never does; t_0 if e_0 already does).
double interpolateLogLog(const std::vector<double>& t, const std::vector<double>& e, double T);
double timeToReach(const std::vector<double>& t, const std::vector<double>& e, double target);

// Checkpoint times: n values geometric from `first` to `last` (both included; n >= 2 and
// 0 < first < last, else just {last}), merged with `extra` (values in (0, last] only), sorted,
// with duplicates (within 1e-9 relative) removed.
std::vector<double> geometricCheckpoints(double first, double last, int n, const std::vector<double>& extra = {});

}  // namespace tpb
