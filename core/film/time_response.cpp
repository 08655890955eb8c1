// Pulse shapes and sensor responses (see time_response.h for the model and its formulas).
#include "film/time_response.h"

#include "base/math.h"

#include <algorithm>
#include <atomic>
#include <mutex>
#include <charconv>
#include <functional>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace tpb {

namespace {

constexpr double kFwhmToSigma = 1.0 / 2.3548200450309493;  // 1 / (2 sqrt(2 ln 2))
constexpr double kGaussReach = 8.0;                        // sigmas: the tails beyond hold < 1e-15
constexpr double kExpReach = 40.0;                         // decay times: e^-40 < 1e-17

double phi(double z) { return 0.3989422804014327 * std::exp(-0.5 * z * z); }
double Phi(double z) { return 0.5 * std::erfc(-z * 0.7071067811865476); }

// G of the sensor alone (closed forms).
double sensorG(const TimeResponse& r, double t) {
    switch (r.sensor) {
        case SensorShape::Ideal: return std::max(t, 0.0);
        case SensorShape::Gaussian: {
            const double s = r.sensorWidth * kFwhmToSigma;
            return t * Phi(t / s) + s * phi(t / s);
        }
        case SensorShape::Exponential: {
            const double tau = r.sensorWidth;
            return t <= 0.0 ? 0.0 : t + tau * std::expm1(-t / tau);
        }
    }
    return 0.0;
}

// Where the sensor's G has a kink (ideal, exponential: at 0) or none.
bool sensorKinked(const TimeResponse& r) { return r.sensor != SensorShape::Gaussian; }

double integrate(const std::function<double(double)>& f, double a, double b, int panels) {
    static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
    static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                0.2369268850561891};
    if (!(b > a)) return 0.0;
    const double h = (b - a) / panels;
    double s = 0.0;
    for (int i = 0; i < panels; ++i) {
        const double m = a + (i + 0.5) * h;
        for (int j = 0; j < 5; ++j) s += w[j] * f(m + 0.5 * h * x[j]);
    }
    return s * 0.5 * h;
}

// Support of h = p * s, m of OPL.
void support(const TimeResponse& r, double& lo, double& hi) {
    lo = hi = 0.0;
    if (r.pulse == PulseShape::Gaussian) {
        lo -= kGaussReach * r.pulseWidth * kFwhmToSigma;
        hi += kGaussReach * r.pulseWidth * kFwhmToSigma;
    } else if (r.pulse == PulseShape::Square) {
        hi += r.pulseWidth;
    }
    if (r.sensor == SensorShape::Gaussian) {
        lo -= kGaussReach * r.sensorWidth * kFwhmToSigma;
        hi += kGaussReach * r.sensorWidth * kFwhmToSigma;
    } else if (r.sensor == SensorShape::Exponential) {
        hi += kExpReach * r.sensorWidth;
    }
}

std::optional<double> positiveNs(std::string_view s) {
    double v = 0.0;
    const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || p != s.data() + s.size() || !(v > 0.0) || !std::isfinite(v)) return std::nullopt;
    return v;
}

std::string ns(double opl) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", opl / kC_m_per_ns);
    return b;
}

}  // namespace

double responseG(const TimeResponse& r, double t) {
    switch (r.pulse) {
        case PulseShape::Delta: return sensorG(r, t);
        case PulseShape::Gaussian: {
            const double s = r.pulseWidth * kFwhmToSigma, a = -kGaussReach * s, b = kGaussReach * s;
            const auto f = [&](double u) { return phi(u / s) / s * sensorG(r, t - u); };
            // The sensor's kink at u = t on a panel edge (an integrand with a kink inside a panel
            // converges slowly).
            if (sensorKinked(r) && t > a && t < b) return integrate(f, a, t, 128) + integrate(f, t, b, 128);
            return integrate(f, a, b, 256);
        }
        case PulseShape::Square: {
            const double w = r.pulseWidth;
            const auto f = [&](double u) { return sensorG(r, t - u) / w; };
            if (sensorKinked(r) && t > 0.0 && t < w) return integrate(f, 0.0, t, 64) + integrate(f, t, w, 64);
            return integrate(f, 0.0, w, 128);
        }
    }
    return 0.0;
}

double responseSpanBins(const TimeResponse& r, double binWidth) {
    double lo = 0.0, hi = 0.0;
    support(r, lo, hi);
    return (hi - lo) / binWidth;
}

namespace {
std::atomic<uint64_t> gKernelComputations{0};
}  // namespace

uint64_t binKernelComputations() { return gKernelComputations.load(); }

BinKernel binKernel(const TimeResponse& r, double binWidth, int filmBins) {
    BinKernel k;
    if (r.kernelIdentity()) return k;
    if ((r.pulse != PulseShape::Delta && !(r.pulseWidth > 0.0)) ||
        (r.sensor != SensorShape::Ideal && !(r.sensorWidth > 0.0)))
        throw std::invalid_argument("binKernel: a pulse or sensor width must be > 0");
    if (!(responseSpanBins(r, binWidth) <= kMaxResponseBins))
        throw std::invalid_argument("binKernel: the pulse and sensor span more than 2^20 bins");
    ++gKernelComputations;
    double lo = 0.0, hi = 0.0;
    support(r, lo, hi);
    int mlo = static_cast<int>(std::floor(lo / binWidth)) - 1, mhi = static_cast<int>(std::ceil(hi / binWidth)) + 1;
    // Cut to the weights a film of filmBins bins reads (|m| < filmBins); the rest go to before/after.
    const bool cutLo = filmBins > 0 && mlo<1 - filmBins, cutHi = filmBins> 0 && mhi > filmBins - 1;
    if (cutLo) mlo = 1 - filmBins;
    if (cutHi) mhi = filmBins - 1;
    std::vector<double> G(static_cast<size_t>(mhi - mlo + 3));  // G at (mlo - 1 .. mhi + 1) D
    for (int m = mlo - 1; m <= mhi + 1; ++m) G[static_cast<size_t>(m - mlo + 1)] = responseG(r, m * binWidth);
    k.lo = mlo;
    k.w.assign(static_cast<size_t>(mhi - mlo + 1), 0.0);
    for (int m = mlo; m <= mhi; ++m) {
        const size_t i = static_cast<size_t>(m - mlo + 1);
        k.w[static_cast<size_t>(m - mlo)] = std::max(0.0, (G[i + 1] - 2.0 * G[i] + G[i - 1]) / binWidth);
    }
    // The weights beyond a cut: sum_{m > mhi} W_m = 1 - F(mhi + 1), sum_{m < mlo} W_m = F(mlo).
    if (cutHi) k.before = std::max(0.0, 1.0 - (G[G.size() - 1] - G[G.size() - 2]) / binWidth);
    if (cutLo) k.after = std::max(0.0, (G[1] - G[0]) / binWidth);
    // Trim the weights that are zero to rounding at the support's ends (a long exponential tail
    // stays); a cut end keeps its weights.
    size_t a = 0, b = k.w.size();
    while (!cutLo && a + 1 < b && k.w[a] < 1e-15) ++a;
    while (!cutHi && b > a + 1 && k.w[b - 1] < 1e-15) --b;
    k.lo += static_cast<int>(a);
    k.w =
        std::vector<double>(k.w.begin() + static_cast<std::ptrdiff_t>(a), k.w.begin() + static_cast<std::ptrdiff_t>(b));
    return k;
}

std::shared_ptr<const BinKernel> sharedBinKernel(const TimeResponse& r, double binWidth, int filmBins) {
    struct Entry {
        TimeResponse response;
        double binWidth;
        int filmBins;
        std::shared_ptr<const BinKernel> kernel;
    };
    static const auto identity = std::make_shared<const BinKernel>();
    if (r.kernelIdentity()) return identity;  // every frame of every render: no lock
    TimeResponse key = r;                     // the kernel does not depend on the counting
    key.counting = {};
    static std::mutex mutex;
    static std::vector<Entry> cache;  // most recently used last
    constexpr size_t kKept = 8;       // a few: the viewer switches between responses, axes' widths are equal
    const std::lock_guard<std::mutex> lock(mutex);  // held while computing: each kernel once
    for (size_t i = 0; i < cache.size(); ++i)
        if (cache[i].response == key && cache[i].binWidth == binWidth && cache[i].filmBins == filmBins) {
            std::rotate(cache.begin() + static_cast<std::ptrdiff_t>(i),
                        cache.begin() + static_cast<std::ptrdiff_t>(i) + 1, cache.end());
            return cache.back().kernel;
        }
    auto kernel = std::make_shared<const BinKernel>(binKernel(r, binWidth, filmBins));
    if (cache.size() == kKept) cache.erase(cache.begin());
    cache.push_back({key, binWidth, filmBins, kernel});
    return kernel;
}

void applyKernel(const BinKernel& k, const double* x, int bins, const double* left, const double* right, double* out) {
    const int n = static_cast<int>(k.w.size());
    for (int j = 0; j < bins; ++j) {
        double acc[3] = {0.0, 0.0, 0.0};
        if (k.after != 0.0)
            for (int c = 0; c < 3; ++c) acc[c] += k.after * right[c];
        for (int i = 0; i < n; ++i) {
            const int src = j - (k.lo + i);
            const double* v = src < 0 ? left : src >= bins ? right : x + static_cast<size_t>(src) * 3;
            for (int c = 0; c < 3; ++c) acc[c] += k.w[static_cast<size_t>(i)] * v[c];
        }
        if (k.before != 0.0)
            for (int c = 0; c < 3; ++c) acc[c] += k.before * left[c];
        for (int c = 0; c < 3; ++c) out[static_cast<size_t>(j) * 3 + c] = acc[c];
    }
}

std::optional<TimeResponse> parsePulse(std::string_view s, TimeResponse r) {
    if (s == "delta") {
        r.pulse = PulseShape::Delta;
        r.pulseWidth = 0.0;
        return r;
    }
    const size_t colon = s.find(':');
    if (colon == std::string_view::npos) return std::nullopt;
    const std::string_view kind = s.substr(0, colon);
    const std::optional<double> v = positiveNs(s.substr(colon + 1));
    if (!v) return std::nullopt;
    if (kind == "gaussian")
        r.pulse = PulseShape::Gaussian;
    else if (kind == "square")
        r.pulse = PulseShape::Square;
    else
        return std::nullopt;
    r.pulseWidth = *v * kC_m_per_ns;
    return r;
}

std::optional<TimeResponse> parseSensor(std::string_view s, TimeResponse r) {
    if (s == "ideal") {
        r.sensor = SensorShape::Ideal;
        r.sensorWidth = 0.0;
        return r;
    }
    const size_t colon = s.find(':');
    if (colon == std::string_view::npos) return std::nullopt;
    const std::string_view kind = s.substr(0, colon);
    const std::optional<double> v = positiveNs(s.substr(colon + 1));
    if (!v) return std::nullopt;
    if (kind == "gaussian")
        r.sensor = SensorShape::Gaussian;
    else if (kind == "exp")
        r.sensor = SensorShape::Exponential;
    else
        return std::nullopt;
    r.sensorWidth = *v * kC_m_per_ns;
    return r;
}

std::string pulseName(const TimeResponse& r) {
    switch (r.pulse) {
        case PulseShape::Delta: return "delta";
        case PulseShape::Gaussian: return "gaussian:" + ns(r.pulseWidth);
        case PulseShape::Square: return "square:" + ns(r.pulseWidth);
    }
    return "?";
}

std::string sensorName(const TimeResponse& r) {
    switch (r.sensor) {
        case SensorShape::Ideal: return "ideal";
        case SensorShape::Gaussian: return "gaussian:" + ns(r.sensorWidth);
        case SensorShape::Exponential: return "exp:" + ns(r.sensorWidth);
    }
    return "?";
}

std::string describe(const TimeResponse& r) {
    std::string p = r.pulse == PulseShape::Delta      ? "delta pulse"
                    : r.pulse == PulseShape::Gaussian ? "gaussian pulse, FWHM " + ns(r.pulseWidth) + " ns"
                                                      : "square pulse, " + ns(r.pulseWidth) + " ns";
    std::string s = r.sensor == SensorShape::Ideal      ? "ideal sensor"
                    : r.sensor == SensorShape::Gaussian ? "gaussian sensor jitter, FWHM " + ns(r.sensorWidth) + " ns"
                                                        : "exponential sensor decay, " + ns(r.sensorWidth) + " ns";
    return p + "; " + s + (r.counting.enabled ? "; " + describeCounting(r.counting) : "");
}

}  // namespace tpb
