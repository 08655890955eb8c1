// Photon counting (see photon_counting.h and docs/theory/photon-counting.md).
#include "film/photon_counting.h"

#include "base/error.h"
#include "base/math.h"
#include "base/rng.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <vector>

namespace tpb {

namespace {

std::string num(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.10g", v);
    return b;
}

double normal(Rng& rng) {
    const double u1 = rng.uniform(), u2 = rng.uniform();
    return std::sqrt(-2.0 * std::log1p(-u1)) * std::cos(2.0 * kPi * u2);
}

// Gamma(a, 1) for a >= 1 (Marsaglia and Tsang 2000). v = (1 + c x)^3 = e^L; the test's
// d (1 - v + ln v) = d (L - expm1(L)) is written so for a up to 1e18 (d - d v would cancel).
double sampleGamma(Rng& rng, double a) {
    const double d = a - 1.0 / 3.0, c = 1.0 / std::sqrt(9.0 * d);
    for (;;) {
        const double x = normal(rng);
        if (c * x <= -1.0) continue;
        const double L = 3.0 * std::log1p(c * x), w = std::expm1(L), u = rng.uniform();
        if (std::log1p(-u) < 0.5 * x * x + d * (L - w)) return d + d * w;
    }
}

double sampleBeta(Rng& rng, double a, double b) {
    const double x = sampleGamma(rng, a), y = sampleGamma(rng, b);
    return x / (x + y);
}

constexpr double kSmallMean = 16.0;  // below it, inversion (expected steps ~ the mean)

}  // namespace

double sampleBinomial(Rng& rng, double n, double p) {
    n = std::floor(n);
    if (!(p > 0.0) || n < 1.0) return 0.0;
    if (p >= 1.0) return n;
    if (p > 0.5) return n - sampleBinomial(rng, n, 1.0 - p);
    if (n * p < kSmallMean) {
        // Inversion: pmf(0) = (1-p)^n >= e^-23 here.
        const double u = rng.uniform(), r = p / (1.0 - p);
        double pmf = std::exp(n * std::log1p(-p)), cdf = pmf, j = 0.0;
        while (u > cdf && j < n) {
            pmf *= (n - j) / (j + 1.0) * r;
            j += 1.0;
            cdf += pmf;
        }
        return j;
    }
    // Knuth 3.4.1 F: X, the a-th smallest of n uniforms, ~ Beta(a, n + 1 - a); the uniforms below p
    // are then among the a - 1 below X, or the a plus those of the n - a above X.
    const double a = 1.0 + std::floor(n / 2.0), b = n + 1.0 - a;
    const double x = sampleBeta(rng, a, b);
    if (x >= p) return sampleBinomial(rng, a - 1.0, p / x);
    return a + sampleBinomial(rng, b - 1.0, (p - x) / (1.0 - x));
}

double samplePoisson(Rng& rng, double mean) {
    double k = 0.0;
    // Knuth 3.4.1 F: the m-th arrival of a unit-rate process is Gamma(m); before `mean`, m arrivals
    // and the rest Poisson(mean - X); after it, the arrivals before `mean` are Binomial(m - 1, mean / X).
    while (mean > kSmallMean) {
        const double m = std::floor(0.875 * mean), x = sampleGamma(rng, m);
        if (x >= mean) return k + sampleBinomial(rng, m - 1.0, mean / x);
        k += m;
        mean -= x;
    }
    if (!(mean > 0.0)) return k;
    const double u = rng.uniform();
    double pmf = std::exp(-mean), cdf = pmf, j = 0.0;
    while (u > cdf && j < 1000.0) {
        j += 1.0;
        pmf *= mean / j;
        cdf += pmf;
    }
    return k + j;
}

namespace {

// "--counts dark_hz=-5" (or "dark_hz=-5" when the caller names the flag itself).
std::string named(const std::string& what, std::string_view item) {
    return (what.empty() ? std::string() : what + " ") + std::string(item);
}

double parseNumber(std::string_view item, std::string_view value, const std::string& what) {
    double v = 0.0;
    const auto [p, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
    if (ec != std::errc() || p != value.data() + value.size() || !std::isfinite(v))
        throw UserError(named(what, item) + ": not a number; write e.g. photons=1e4");
    return v;
}

void require(bool ok, const std::string& what, std::string_view item, const char* rule) {
    if (!ok) throw UserError(named(what, item) + ": " + rule);
}

}  // namespace

PhotonCounting parseCounting(std::string_view s, const std::string& what) {
    PhotonCounting m;
    if (s == "off" || s.empty()) return m;
    m.enabled = true;
    size_t start = 0;
    while (start <= s.size()) {
        const size_t end = std::min(s.find(',', start), s.size());
        const std::string_view item = s.substr(start, end - start);
        start = end + 1;
        const size_t eq = item.find('=');
        const std::string_view key = item.substr(0, eq), value = eq == item.npos ? "" : item.substr(eq + 1);
        if (eq == item.npos) {
            if (key == "pileup")
                m.pileup = true;
            else if (key == "coates")
                m.coates = true;
            else if (key == "on" || key.empty())
                continue;
            else
                throw UserError(named(what, item) +
                                ": unknown item; use photons=, efficiency=, dark_hz=, ambient_hz=, cycles=, "
                                "afterpulse=, afterpulse_ns=, seed=, pileup, coates (or off)");
            continue;
        }
        const double v = parseNumber(item, value, what);
        if (key == "photons") {
            require(v > 0.0, what, item, "photons must be > 0 (the signal photons a mean pixel expects)");
            m.photons = v;
        } else if (key == "efficiency") {
            require(v > 0.0 && v <= 1.0, what, item, "efficiency must be in (0, 1] (the detection probability)");
            m.efficiency = v;
        } else if (key == "dark_hz") {
            require(v >= 0.0, what, item, "dark_hz must be >= 0 (a rate in Hz; 0 for no dark counts)");
            m.darkHz = v;
        } else if (key == "ambient_hz") {
            require(v >= 0.0, what, item, "ambient_hz must be >= 0 (a detected rate in Hz; 0 for none)");
            m.ambientHz = v;
        } else if (key == "cycles") {
            require(v >= 1.0 && v <= 9e15 && v == std::floor(v), what, item,
                    "cycles must be a whole number >= 1 (the laser pulses of the acquisition)");
            m.cycles = v;
        } else if (key == "afterpulse") {
            require(v >= 0.0 && v < 1.0, what, item, "afterpulse must be in [0, 1) (a probability per detection)");
            m.afterpulse = v;
        } else if (key == "afterpulse_ns") {
            require(v > 0.0, what, item, "afterpulse_ns must be > 0 (the afterpulses' delay time constant, ns)");
            m.afterpulseNs = v;
        } else if (key == "seed") {
            require(v >= 0.0 && v <= 9e15 && v == std::floor(v), what, item, "seed must be a whole number >= 0");
            m.seed = static_cast<uint64_t>(v);
        } else {
            throw UserError(named(what, item) +
                            ": unknown key; use photons=, efficiency=, dark_hz=, ambient_hz=, cycles=, afterpulse=, "
                            "afterpulse_ns=, seed=, pileup, coates (or off)");
        }
    }
    if (m.coates && !m.pileup)
        throw UserError(named(what, "coates") + ": the Coates correction undoes pile-up; add pileup (or drop coates)");
    return m;
}

std::string countingName(const PhotonCounting& m) {
    if (!m.enabled) return "off";
    std::string s = "photons=" + num(m.photons) + ",efficiency=" + num(m.efficiency) + ",dark_hz=" + num(m.darkHz) +
                    ",ambient_hz=" + num(m.ambientHz) + ",cycles=" + num(m.cycles) +
                    ",afterpulse=" + num(m.afterpulse) + ",afterpulse_ns=" + num(m.afterpulseNs) +
                    ",seed=" + std::to_string(m.seed);
    if (m.pileup) s += ",pileup";
    if (m.coates) s += ",coates";
    return s;
}

std::string describeCounting(const PhotonCounting& m) {
    if (!m.enabled) return "noise-free";
    std::string s = m.coates   ? "Coates-corrected TCSPC counts"
                    : m.pileup ? "TCSPC counts with pile-up"
                               : "Poisson counts";
    s += ", " + shortNumber(m.photons) + " photons/pixel";
    if (m.efficiency != 1.0) s += " x " + shortNumber(m.efficiency) + " efficiency";
    s += ", " + shortNumber(m.cycles) + " cycles";
    if (m.darkHz > 0.0) s += ", dark " + shortNumber(m.darkHz) + " Hz";
    if (m.ambientHz > 0.0) s += ", ambient " + shortNumber(m.ambientHz) + " Hz";
    if (m.afterpulse > 0.0 && !m.pileup)
        s += ", afterpulses " + shortNumber(m.afterpulse) + " (" + shortNumber(m.afterpulseNs) + " ns)";
    return s + ", seed " + std::to_string(m.seed);
}

CountScale countScale(const PhotonCounting& m, double meanSteadyLuminance, double binWidthOpl) {
    CountScale c;
    c.perLuminance = meanSteadyLuminance > 0.0 ? m.efficiency * m.photons / meanSteadyLuminance : 0.0;
    c.binSeconds = binWidthOpl / kC_m_per_ns * 1e-9;
    c.background = (m.darkHz + m.ambientHz) * c.binSeconds * m.cycles;
    return c;
}

void expectedCounts(const PhotonCounting& m, const CountScale& scale, const double* y, int bins, double* lam) {
    for (int k = 0; k < bins; ++k) lam[k] = scale.perLuminance * std::max(y[k], 0.0) + scale.background;
    if (m.pileup || !(m.afterpulse > 0.0) || bins == 0) return;
    // Afterpulses: a detection uniform in its bin, delay ~ Exp(tau). x = D / tau, r = e^-x: the
    // share past its own bin is a = (1 - r) / x, the m-th bin on gets a (1 - r) r^(m - 1). With
    // cascades: tot_k = lam_k + p [(1 - a) tot_k + a (1 - r) S_k], S_k = sum_{m>=1} tot_(k-m) r^(m-1).
    const double x = scale.binSeconds / (m.afterpulseNs * 1e-9), r = std::exp(-x);
    const double a = x > 1e-8 ? -std::expm1(-x) / x : 1.0 - 0.5 * x, p = m.afterpulse;
    double S = 0.0;
    for (int k = 0; k < bins; ++k) {
        const double tot = (lam[k] + p * a * (-std::expm1(-x)) * S) / (1.0 - p * (1.0 - a));
        S = tot + r * S;
        lam[k] = tot;
    }
}

void coatesCorrection(const double* counts, int bins, double cycles, double* lamHat) {
    double left = cycles;
    for (int k = 0; k < bins; ++k) {
        const double c = counts[k];
        lamHat[k] = left <= 0.0 ? 0.0 : c >= left ? cycles * std::log(2.0 * c) : -cycles * std::log1p(-c / left);
        left -= c;
    }
}

void countPixel(const PhotonCounting& m, const CountScale& scale, uint64_t pixel, const double* y, int bins, int first,
                int last, double* out) {
    last = std::min(last, bins - 1);
    if (last < 0) return;
    std::vector<double> lam(static_cast<size_t>(last) + 1);
    expectedCounts(m, scale, y, last + 1, lam.data());
    const auto rng = [&](int k) { return Rng(m.seed, Stream::Counts, pixel, static_cast<uint64_t>(k)); };
    if (!m.pileup) {
        for (int k = std::max(first, 0); k <= last; ++k) {
            Rng r = rng(k);
            out[k] = samplePoisson(r, lam[static_cast<size_t>(k)]);
        }
        return;
    }
    // First photon per cycle: of the cycles with no detection before bin k, each detects in bin k
    // with probability 1 - exp(-lam_k / N).
    const double N = m.cycles;
    double left = N;
    for (int k = 0; k <= last; ++k) {
        Rng r = rng(k);
        const double c = sampleBinomial(r, left, -std::expm1(-lam[static_cast<size_t>(k)] / N));
        if (k >= first)
            out[k] = !m.coates ? c : left <= 0.0 ? 0.0 : c >= left ? N * std::log(2.0 * c) : -N * std::log1p(-c / left);
        left -= c;
    }
}

}  // namespace tpb
