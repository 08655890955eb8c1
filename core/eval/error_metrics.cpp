#include "eval/error_metrics.h"

#include "base/error.h"

#include <algorithm>
#include <numeric>

namespace tpb {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <class X, class R>
double relRmse(const std::vector<X>& x, const std::vector<R>& ref) {
    TPB_CHECK(x.size() == ref.size());
    return squaredError(x.data(), ref.data(), x.size()).relative();
}

template <class X, class R>
double totalDiff(const std::vector<X>& x, const std::vector<R>& ref) {
    TPB_CHECK(x.size() == ref.size());
    double sx = 0.0, sr = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
        sx += static_cast<double>(x[i]);
        sr += static_cast<double>(ref[i]);
    }
    return sr != 0.0 ? (sx - sr) / sr : kNaN;
}
}  // namespace

double relativeRmse(const std::vector<double>& x, const std::vector<double>& ref) { return relRmse(x, ref); }
double relativeRmse(const std::vector<float>& x, const std::vector<float>& ref) { return relRmse(x, ref); }
double relativeRmse(const std::vector<double>& x, const std::vector<float>& ref) { return relRmse(x, ref); }

std::vector<double> perFrameRelativeRmse(const std::vector<double>& x, const std::vector<float>& ref, int bins) {
    TPB_CHECK(x.size() == ref.size() && bins > 0 && x.size() % (static_cast<size_t>(bins) * 3) == 0);
    const size_t pixels = x.size() / (static_cast<size_t>(bins) * 3);
    std::vector<SquaredError> e(static_cast<size_t>(bins));
    for (size_t p = 0; p < pixels; ++p)
        for (int k = 0; k < bins; ++k) {
            const size_t i = (p * bins + k) * 3;
            for (int c = 0; c < 3; ++c) e[k].add(x[i + c], ref[i + c]);
        }
    std::vector<double> out(static_cast<size_t>(bins));
    for (int k = 0; k < bins; ++k) out[k] = e[k].relative();
    return out;
}

double relativeTotalDifference(const std::vector<double>& x, const std::vector<double>& ref) {
    return totalDiff(x, ref);
}
double relativeTotalDifference(const std::vector<float>& x, const std::vector<float>& ref) { return totalDiff(x, ref); }

double halfSplitRelativeError(double diff2, double ref2, double na, double nb) {
    if (!(ref2 > 0.0) || !(na > 0.0) || !(nb > 0.0)) return kNaN;
    const double n = na + nb;
    return std::sqrt(na * nb / (n * n) * diff2 / ref2);
}

double noiseCorrected(double measured, double floor) {
    if (!(floor >= 0.0) || std::isnan(measured)) return kNaN;
    return std::sqrt(std::max(0.0, measured * measured - floor * floor));
}

PowerLawFit fitPowerLaw(const std::vector<double>& t, const std::vector<double>& e) {
    PowerLawFit f;
    double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
    int n = 0;
    for (size_t i = 0; i < std::min(t.size(), e.size()); ++i) {
        if (!(t[i] > 0.0) || !(e[i] > 0.0) || !std::isfinite(t[i]) || !std::isfinite(e[i])) continue;
        const double x = std::log(t[i]), y = std::log(e[i]);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
        ++n;
    }
    f.points = n;
    if (n < 2) return f;
    const double mx = sx / n, my = sy / n;
    const double vxx = sxx / n - mx * mx, vxy = sxy / n - mx * my;
    if (!(vxx > 1e-300)) return f;
    f.slope = vxy / vxx;
    f.intercept = my - f.slope * mx;
    return f;
}

PowerLawFit fitPowerLawSecondHalf(const std::vector<double>& t, const std::vector<double>& e) {
    const size_t n = std::min(t.size(), e.size());
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), size_t(0));
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return t[a] < t[b]; });
    const size_t keep = std::min(n, std::max<size_t>(2, (n + 1) / 2));
    std::vector<double> ts, es;
    for (size_t i = n - keep; i < n; ++i) {
        ts.push_back(t[order[i]]);
        es.push_back(e[order[i]]);
    }
    return fitPowerLaw(ts, es);
}

double interpolateLogLog(const std::vector<double>& t, const std::vector<double>& e, double T) {
    const size_t n = std::min(t.size(), e.size());
    if (n == 0 || !(T > 0.0)) return kNaN;
    if (T < t[0] || T > t[n - 1]) return kNaN;
    for (size_t i = 0; i + 1 < n; ++i) {
        if (T > t[i + 1]) continue;
        if (!(e[i] > 0.0) || !(e[i + 1] > 0.0) || !(t[i] > 0.0)) return kNaN;
        if (t[i + 1] <= t[i]) return e[i + 1];
        const double u = std::log(T / t[i]) / std::log(t[i + 1] / t[i]);
        return std::exp(std::log(e[i]) + u * std::log(e[i + 1] / e[i]));
    }
    return e[n - 1];  // n == 1 and T == t[0]
}

double timeToReach(const std::vector<double>& t, const std::vector<double>& e, double target) {
    const size_t n = std::min(t.size(), e.size());
    if (n == 0 || !(target > 0.0)) return kNaN;
    if (e[0] <= target) return t[0];
    for (size_t i = 0; i + 1 < n; ++i) {
        if (!(e[i + 1] <= target)) continue;
        // Crossing between i and i + 1 (e[i] > target >= e[i + 1]).
        if (!(e[i] > 0.0) || !(e[i + 1] > 0.0) || !(t[i] > 0.0) || !(t[i + 1] > t[i])) return t[i + 1];
        const double u = std::log(target / e[i]) / std::log(e[i + 1] / e[i]);
        return std::exp(std::log(t[i]) + u * std::log(t[i + 1] / t[i]));
    }
    return kNaN;
}

std::vector<double> geometricCheckpoints(double first, double last, int n, const std::vector<double>& extra) {
    std::vector<double> out;
    if (!(last > 0.0)) return out;
    if (n >= 2 && first > 0.0 && first < last) {
        const double ratio = std::log(last / first) / (n - 1);
        for (int i = 0; i < n; ++i) out.push_back(i == n - 1 ? last : first * std::exp(ratio * i));
    } else {
        out.push_back(last);
    }
    for (double x : extra)
        if (x > 0.0 && x <= last) out.push_back(x);
    std::sort(out.begin(), out.end());
    std::vector<double> unique;
    for (double x : out)
        if (unique.empty() || x > unique.back() * (1.0 + 1e-9)) unique.push_back(x);
    return unique;
}

}  // namespace tpb
