// Photon counting (film/photon_counting.h): the counts' distributions by chi-square over many seeds;
// the pile-up model and the afterpulse means against a direct event-by-event simulation of the
// counting process (written here, independently: cycles, Poisson arrivals in time, first-photon
// detection, dead time, dark counts, afterpulses); the Coates correction; the limits; the seed; the
// film readers; bad input.
#include "film/film_view.h"
#include "film/photon_counting.h"
#include "film/transient_film.h"
#include "base/error.h"
#include "base/rng.h"
#include "support/chi2.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

namespace tpb {
namespace {

constexpr int kTests = 9;  // chi-square tests in this file, for the Sidak correction

// Pearson's X^2 of observed counts against pmf(k) * samples, cells expecting < 5 pooled.
double goodnessP(const std::map<int64_t, int64_t>& observed, const std::function<double(int64_t)>& pmf, int64_t samples,
                 int64_t lo, int64_t hi) {
    double x2 = 0.0, pooledE = 0.0, pooledO = 0.0, expectedSeen = 0.0;
    int cells = 0;
    int64_t seen = 0;
    for (int64_t k = lo; k <= hi; ++k) {
        const double e = pmf(k) * static_cast<double>(samples);
        const auto it = observed.find(k);
        const double o = it == observed.end() ? 0.0 : static_cast<double>(it->second);
        expectedSeen += e;
        seen += static_cast<int64_t>(o);
        pooledE += e;
        pooledO += o;
        if (pooledE >= 5.0) {
            x2 += (pooledO - pooledE) * (pooledO - pooledE) / pooledE;
            ++cells;
            pooledE = pooledO = 0.0;
        }
    }
    // Everything outside [lo, hi] and the last pooled cell: one more cell.
    const double restE = static_cast<double>(samples) - expectedSeen + pooledE,
                 restO = static_cast<double>(samples - seen) + pooledO;
    if (restE > 0.0) {
        x2 += (restO - restE) * (restO - restE) / restE;
        ++cells;
    }
    return test::chi2PValue(x2, cells - 1);
}

// Two-sample chi-square (equal sizes) of two count histograms, cells with < 10 together pooled.
double homogeneityP(const std::vector<double>& a, const std::vector<double>& b) {
    std::map<int64_t, std::pair<double, double>> h;
    for (double v : a) h[static_cast<int64_t>(v)].first += 1.0;
    for (double v : b) h[static_cast<int64_t>(v)].second += 1.0;
    double x2 = 0.0, pa = 0.0, pb = 0.0;
    int cells = 0;
    for (const auto& [k, ab] : h) {
        pa += ab.first;
        pb += ab.second;
        if (pa + pb >= 10.0) {
            x2 += (pa - pb) * (pa - pb) / (pa + pb);
            ++cells;
            pa = pb = 0.0;
        }
    }
    if (pa + pb > 0.0) {
        x2 += (pa - pb) * (pa - pb) / (pa + pb);
        ++cells;
    }
    return test::chi2PValue(x2, cells - 1);
}

double logPoisson(double mean, int64_t k) {
    return static_cast<double>(k) * std::log(mean) - mean - std::lgamma(static_cast<double>(k) + 1.0);
}

PhotonCounting ideal(uint64_t seed = 1) {
    PhotonCounting m;
    m.enabled = true;
    m.seed = seed;
    return m;
}

// Counts of one pixel whose expected counts are `lam` (scale 1, no background).
std::vector<double> counts(const PhotonCounting& m, const std::vector<double>& lam, double background = 0.0,
                           uint64_t pixel = 0, double binSeconds = 1e-10) {
    CountScale s;
    s.perLuminance = 1.0;
    s.background = background;
    s.binSeconds = binSeconds;
    std::vector<double> out(lam.size(), -1.0);
    countPixel(m, s, pixel, lam.data(), static_cast<int>(lam.size()), 0, static_cast<int>(lam.size()) - 1, out.data());
    return out;
}

TEST(PhotonCounting, IdealCountsArePoissonOverSeeds) {
    const std::vector<double> lam = {0.3, 4.0, 40.0, 2500.0};
    const int64_t seeds = 40000;
    std::vector<std::map<int64_t, int64_t>> hist(lam.size());
    std::vector<double> sum(lam.size(), 0.0);
    for (int64_t s = 0; s < seeds; ++s) {
        const std::vector<double> c = counts(ideal(static_cast<uint64_t>(s)), lam);
        for (size_t k = 0; k < lam.size(); ++k) {
            ASSERT_EQ(c[k], std::floor(c[k]));
            ++hist[k][static_cast<int64_t>(c[k])];
            sum[k] += c[k];
        }
    }
    const double alpha = test::sidakSignificance(0.01, kTests);
    for (size_t k = 0; k < lam.size(); ++k) {
        const double mu = lam[k];
        const double p = goodnessP(
            hist[k], [mu](int64_t n) { return std::exp(logPoisson(mu, n)); }, seeds, 0,
            static_cast<int64_t>(mu + 10 * std::sqrt(mu) + 20));
        std::printf("Poisson(%g): mean %.4f, chi-square p = %.3f\n", mu, sum[k] / seeds, p);
        EXPECT_GT(p, alpha) << "lambda " << mu;
    }
}

TEST(PhotonCounting, BinomialSamplerMatchesItsPmf) {
    // Inversion (n p < 16) and the beta-splitting path (n p >= 16, large n), both sides of p = 1/2.
    const double alpha = test::sidakSignificance(0.01, kTests);
    for (const auto& [n, p] : std::vector<std::pair<double, double>>{{1e6, 3e-5}, {1e9, 2e-7}, {40, 0.7}}) {
        std::map<int64_t, int64_t> hist;
        const int64_t draws = 20000;
        for (int64_t i = 0; i < draws; ++i) {
            Rng rng(3, Stream::Test, static_cast<uint64_t>(n), static_cast<uint64_t>(i));
            ++hist[static_cast<int64_t>(sampleBinomial(rng, n, p))];
        }
        const auto pmf = [n = n, p = p](int64_t k) {
            const double kk = static_cast<double>(k);
            if (kk > n) return 0.0;
            return std::exp(std::lgamma(n + 1) - std::lgamma(kk + 1) - std::lgamma(n - kk + 1) + kk * std::log(p) +
                            (n - kk) * std::log1p(-p));
        };
        const double pv = goodnessP(hist, pmf, draws, 0, static_cast<int64_t>(n * p + 10 * std::sqrt(n * p) + 20));
        std::printf("Binomial(%g, %g): chi-square p = %.3f\n", n, p, pv);
        EXPECT_GT(pv, alpha);
    }
}

// The counting process simulated event by event, for one pixel of `bins` bins of width 1 over
// `cycles` laser cycles: per cycle, signal photons arrive as a Poisson process of rate lam_k /
// (N D) in bin k (D = 1), dark counts at a constant rate; the detector detects the first arrival
// while armed, is then dead for `deadTime` (> bins: one detection per cycle, re-armed by the next
// pulse); each detection triggers an afterpulse with probability p after an Exp(tau) delay, which
// is detected if the detector is armed then (and may trigger another).
struct Direct {
    std::vector<double> lam;  // signal counts per bin per acquisition
    double darkPerBin = 0.0;  // per acquisition
    double cycles = 1.0, deadTime = 0.0, afterpulse = 0.0, tau = 1.0;
    std::vector<double> run(std::mt19937_64& g) const {
        const int bins = static_cast<int>(lam.size());
        std::vector<double> hist(lam.size(), 0.0);
        std::uniform_real_distribution<double> U(0.0, 1.0);
        std::exponential_distribution<double> delay(1.0 / tau);
        std::vector<double> events;
        for (int64_t c = 0; c < static_cast<int64_t>(cycles); ++c) {
            events.clear();
            for (int k = 0; k < bins; ++k) {
                std::poisson_distribution<int> n((lam[static_cast<size_t>(k)] + darkPerBin) / cycles);
                for (int i = n(g); i > 0; --i) events.push_back(k + U(g));
            }
            std::sort(events.begin(), events.end());
            double armedAt = 0.0;
            std::vector<double> pending(events);  // arrivals and afterpulses, processed in time order
            std::make_heap(pending.begin(), pending.end(), std::greater<>());
            while (!pending.empty()) {
                std::pop_heap(pending.begin(), pending.end(), std::greater<>());
                const double t = pending.back();
                pending.pop_back();
                if (t >= bins) break;
                if (t < armedAt) continue;
                hist[static_cast<size_t>(t)] += 1.0;
                armedAt = t + deadTime;
                if (U(g) < afterpulse) {
                    pending.push_back(t + delay(g));
                    std::push_heap(pending.begin(), pending.end(), std::greater<>());
                }
            }
        }
        return hist;
    }
};

TEST(PhotonCounting, PileUpModelMatchesADirectSimulationOfTheCounting) {
    // Strong pile-up: 1.6 arrivals per cycle; afterpulses fall in the dead time (no effect).
    Direct d;
    d.lam = {20, 60, 140, 200, 140, 60, 20, 10, 6, 4, 3, 2, 2, 1, 1, 1};
    d.darkPerBin = 2.0;
    d.cycles = 200;
    d.deadTime = 100.0;
    d.afterpulse = 0.3;
    d.tau = 2.0;
    PhotonCounting m = ideal();
    m.pileup = true;
    m.cycles = d.cycles;
    m.afterpulse = d.afterpulse;
    const int runs = 3000, B = static_cast<int>(d.lam.size());
    std::mt19937_64 g(12345);
    std::vector<std::vector<double>> direct, model;
    for (int r = 0; r < runs; ++r) {
        direct.push_back(d.run(g));
        m.seed = static_cast<uint64_t>(r);
        model.push_back(counts(m, d.lam, d.darkPerBin));
    }
    // The analytic mean N P_k, P_k = (1 - e^-l_k) e^-(sum_{j<k} l_j), l = (lam + dark) / N.
    double before = 0.0;
    const double alpha = test::sidakSignificance(0.01, kTests);
    for (int k = 0; k < B; ++k) {
        const double l = (d.lam[static_cast<size_t>(k)] + d.darkPerBin) / d.cycles;
        const double want = d.cycles * -std::expm1(-l) * std::exp(-before);
        before += l;
        double md = 0.0, mm = 0.0, vd = 0.0, vm = 0.0;
        for (int r = 0; r < runs; ++r) {
            md += direct[static_cast<size_t>(r)][static_cast<size_t>(k)] / runs;
            mm += model[static_cast<size_t>(r)][static_cast<size_t>(k)] / runs;
        }
        for (int r = 0; r < runs; ++r) {
            vd += std::pow(direct[static_cast<size_t>(r)][static_cast<size_t>(k)] - md, 2) / (runs - 1);
            vm += std::pow(model[static_cast<size_t>(r)][static_cast<size_t>(k)] - mm, 2) / (runs - 1);
        }
        const double se = std::sqrt((vd + vm) / runs) + 1e-12;
        EXPECT_LT(std::abs(md - mm), 4.5 * se) << "bin " << k << ": direct " << md << ", model " << mm;
        EXPECT_LT(std::abs(mm - want), 4.5 * std::sqrt(vm / runs) + 1e-9) << "bin " << k;
        // The piled-up histogram is far below the incident light past the peak.
        if (k == 5) {
            EXPECT_LT(mm, 0.2 * d.lam[5]);
        }
    }
    // Distributions: per-bin counts of the two, two-sample chi-square (bins 1, 3, the total).
    for (int k : {1, 3, -1}) {
        std::vector<double> a, b;
        for (int r = 0; r < runs; ++r) {
            const auto pick = [&](const std::vector<double>& h) {
                double t = 0.0;
                for (double v : h) t += v;
                return k < 0 ? t : h[static_cast<size_t>(k)];
            };
            a.push_back(pick(direct[static_cast<size_t>(r)]));
            b.push_back(pick(model[static_cast<size_t>(r)]));
        }
        const double p = homogeneityP(a, b);
        std::printf("pile-up, %s: direct vs model chi-square p = %.3f\n",
                    k < 0 ? "total" : ("bin " + std::to_string(k)).c_str(), p);
        EXPECT_GT(p, alpha) << k;
    }
}

TEST(PhotonCounting, AfterpulseMeansMatchADirectSimulationWithoutDeadTime) {
    Direct d;
    d.lam = {0, 30, 80, 10, 0, 0, 0, 0, 0, 0, 0, 0};
    d.darkPerBin = 0.5;
    d.cycles = 20;  // low flux per cycle; no dead time: every arrival counts
    d.deadTime = 0.0;
    d.afterpulse = 0.2;
    d.tau = 1.5;  // bins
    PhotonCounting m = ideal();
    m.afterpulse = d.afterpulse;
    m.afterpulseNs = d.tau;  // with bins of 1 ns
    CountScale s;
    s.perLuminance = 1.0;
    s.background = d.darkPerBin;
    s.binSeconds = 1e-9;
    std::vector<double> lam(d.lam.size());
    expectedCounts(m, s, d.lam.data(), static_cast<int>(lam.size()), lam.data());
    const int runs = 4000;
    std::mt19937_64 g(777);
    std::vector<double> mean(lam.size(), 0.0), sq(lam.size(), 0.0);
    for (int r = 0; r < runs; ++r) {
        const std::vector<double> h = d.run(g);
        for (size_t k = 0; k < h.size(); ++k) {
            mean[k] += h[k] / runs;
            sq[k] += h[k] * h[k] / runs;
        }
    }
    double afterpulses = 0.0;
    for (size_t k = 0; k < lam.size(); ++k) {
        const double se = std::sqrt(std::max(sq[k] - mean[k] * mean[k], 1e-9) / runs);
        EXPECT_LT(std::abs(mean[k] - lam[k]), 4.5 * se + 1e-9) << "bin " << k << ": direct " << mean[k];
        afterpulses += lam[k] - d.lam[k] - d.darkPerBin;
    }
    // Without afterpulses the mean is the incident light; with them, about p / (1 - p) more
    // (less what falls past the film).
    EXPECT_GT(afterpulses, 0.5 * d.afterpulse * 120.0);
}

TEST(PhotonCounting, CoatesRecoversTheIncidentMeansFromAPiledUpHistogram) {
    PhotonCounting m = ideal();
    m.pileup = true;
    m.coates = true;
    m.cycles = 1e6;
    std::vector<double> lam(32);
    for (size_t k = 0; k < lam.size(); ++k)
        lam[k] = 4e5 * std::exp(-0.5 * std::pow((static_cast<double>(k) - 8.0) / 3.0, 2));  // ~3 per cycle
    double worstZ = 0.0, piled = 0.0;
    PhotonCounting raw = m;
    raw.coates = false;
    const std::vector<double> c = counts(raw, lam), est = counts(m, lam);
    std::vector<double> fromCounts(lam.size());
    coatesCorrection(c.data(), static_cast<int>(c.size()), m.cycles, fromCounts.data());
    double left = m.cycles;
    for (size_t k = 0; k < lam.size(); ++k) {
        EXPECT_DOUBLE_EQ(est[k], fromCounts[k]);
        // Delta method: var(lam^) = N^2 q / (n (1 - q)), q = 1 - e^(-lam/N), n the cycles left.
        const double q = -std::expm1(-lam[k] / m.cycles);
        const double sd = m.cycles * std::sqrt(q / (left * (1.0 - q)));
        if (left > 1000) worstZ = std::max(worstZ, std::abs(est[k] - lam[k]) / sd);
        piled = std::max(piled, std::abs(c[k] - lam[k]) / sd);
        left -= c[k];
    }
    std::printf("Coates: worst |lam^ - lam| / sd = %.2f; uncorrected up to %.0f sd off\n", worstZ, piled);
    EXPECT_LT(worstZ, 4.5);
    EXPECT_GT(piled, 100.0);
}

TEST(PhotonCounting, LimitsDarkOnlyAndHugeBudgets) {
    const std::vector<double> y = {0.0, 1.0, 5.0, 2.0, 0.5};
    PhotonCounting m = ideal();
    // No light, no background: zeros; dark counts only: Poisson(dark D N).
    CountScale s;
    s = countScale(m, 0.0, 0.3);
    EXPECT_EQ(s.perLuminance, 0.0);
    std::vector<double> out(y.size());
    countPixel(m, s, 0, y.data(), 5, 0, 4, out.data());
    for (double v : out) EXPECT_EQ(v, 0.0);
    m.darkHz = 1e3;
    m.cycles = 1e6;
    s = countScale(m, 0.0, 0.3);  // 1 ns bins
    EXPECT_NEAR(s.background, 1e3 * 1.0006922855944562e-9 * 1e6, 1e-9);
    double sum = 0.0;
    for (uint64_t p = 0; p < 4000; ++p) {
        countPixel(m, s, p, y.data(), 5, 0, 4, out.data());
        for (double v : out) sum += v;
    }
    EXPECT_NEAR(sum / 20000.0, s.background, 4.0 * std::sqrt(s.background / 20000.0));
    // A huge budget, no pile-up: counts / scale -> the film (relative error ~ 1/sqrt(counts)).
    PhotonCounting big = ideal();
    big.photons = 1e12;
    s = countScale(big, 2.0, 0.3);  // mean luminance 2: 5e11 counts per unit
    countPixel(big, s, 9, y.data(), 5, 0, 4, out.data());
    for (size_t k = 0; k < y.size(); ++k) EXPECT_NEAR(out[k] / s.perLuminance, y[k], 1e-4 * (y[k] + 1e-6)) << k;
    // The same with pile-up when the cycles are many more than the counts: no pile-up left.
    big.pileup = true;
    big.cycles = 1e18;
    big.photons = 1e10;
    s = countScale(big, 2.0, 0.3);
    countPixel(big, s, 9, y.data(), 5, 0, 4, out.data());
    for (size_t k = 0; k < y.size(); ++k) EXPECT_NEAR(out[k] / s.perLuminance, y[k], 1e-3 * (y[k] + 1e-6)) << k;
}

TEST(PhotonCounting, TheSeedMakesCountsReproducible) {
    const std::vector<double> lam = {3, 8, 1, 0.2, 30};
    for (bool pileup : {false, true}) {
        PhotonCounting m = ideal(7);
        m.pileup = pileup;
        m.cycles = 20;
        EXPECT_EQ(counts(m, lam), counts(m, lam));
        PhotonCounting other = m;
        other.seed = 8;
        EXPECT_NE(counts(m, lam), counts(other, lam));
        EXPECT_NE(counts(m, lam, 0.0, 0), counts(m, lam, 0.0, 1)) << "pixels draw their own numbers";
    }
}

// The film readers count what they read: a frame's bin and the profile, streak and volume agree
// count for count (a frame samples its bin alone, keyed on (seed, pixel, bin)), grey, integers.
TEST(PhotonCounting, FilmReadersShowTheSameCounts) {
    const TimeBins time{1.0, 0.1, 12};
    TransientFilm film(18, 17, time);
    Rng rng(5, Stream::Test, 0, 0);
    for (int tile = 0; tile < film.tileCount(); ++tile) {
        TransientFilm::TileWriter w(film, tile);
        const TileRect r = film.tileRect(tile);
        PixelAccumulator acc(time.bins);
        for (int y = r.y0; y < r.y0 + r.h; ++y)
            for (int x = r.x0; x < r.x0 + r.w; ++x) {
                acc.reset(time.bins);
                Color steady(0.0);
                for (int k = 0; k < time.bins; ++k)
                    if (rng.uniform() < 0.5) {
                        const Color c(rng.uniform(), rng.uniform(), rng.uniform());
                        acc.add(TimeAxis::Real, k, c);
                        steady += c;
                    }
                acc.addSteady(steady);
                w.addPixel(x, y, acc);
            }
    }
    const auto snap = film.snapshot();
    for (bool pileup : {false, true}) {
        TimeResponse resp = *parseSensor("gaussian:0.4");
        resp.counting = parseCounting(pileup ? "photons=30,cycles=10,pileup,dark_hz=1e6,seed=3" : "photons=30,seed=3");
        const std::vector<double> vol = volume(*snap, TimeAxis::Real, EmissionMode::Delta, resp);
        const std::vector<float> prof = pixelProfile(*snap, 4, 9, TimeAxis::Real, EmissionMode::Delta, resp);
        const std::vector<float> streak = streakImage(*snap, 9, TimeAxis::Real, EmissionMode::Delta, resp);
        double total = 0.0;
        for (int bin : {0, 4, 11}) {
            const std::vector<float> f = frameImage(*snap, bin, TimeAxis::Real, EmissionMode::Delta, resp);
            for (int y = 0; y < 17; ++y)
                for (int x = 0; x < 18; ++x) {
                    const size_t v = ((static_cast<size_t>(y) * 18 + x) * 12 + static_cast<size_t>(bin)) * 3;
                    const float* px = &f[(static_cast<size_t>(y) * 18 + x) * 3];
                    ASSERT_EQ(px[0], static_cast<float>(vol[v])) << x << " " << y << " " << bin;
                    ASSERT_EQ(px[1], px[0]);
                    ASSERT_EQ(px[2], px[0]);
                    ASSERT_EQ(px[0], std::floor(px[0]));
                    total += px[0];
                }
            EXPECT_EQ(prof[static_cast<size_t>(bin) * 3], f[(9 * 18 + 4) * 3]);
            EXPECT_EQ(streak[(static_cast<size_t>(bin) * 18 + 4) * 3], f[(9 * 18 + 4) * 3]);
        }
        EXPECT_GT(total, 100.0);
        // The noise-free film stays: the default response reads the sums.
        EXPECT_EQ(frameImage(*snap, 4, TimeAxis::Real, EmissionMode::Delta, TimeResponse{}),
                  frameImage(*snap, 4, TimeAxis::Real, EmissionMode::Delta));
    }
}

TEST(PhotonCounting, ParsesNamesAndRefusesBadInput) {
    const PhotonCounting m = parseCounting(
        "photons=2e4,efficiency=0.4,dark_hz=100,ambient_hz=5e3,cycles=1e7,afterpulse=0.01,"
        "afterpulse_ns=20,pileup,coates,seed=9");
    EXPECT_TRUE(m.enabled && m.pileup && m.coates);
    EXPECT_EQ(m.photons, 2e4);
    EXPECT_EQ(m.darkHz, 100.0);
    EXPECT_EQ(m.seed, 9u);
    EXPECT_EQ(parseCounting(countingName(m)), m);
    EXPECT_FALSE(parseCounting("off").enabled);
    EXPECT_EQ(countingName(parseCounting("off")), "off");
    EXPECT_TRUE(parseCounting("on").enabled);
    const auto message = [](const char* s) {
        try {
            parseCounting(s);
        } catch (const UserError& e) {
            return std::string(e.what());
        }
        return std::string("(accepted)");
    };
    EXPECT_NE(message("dark_hz=-5").find("--counts dark_hz=-5: dark_hz must be >= 0"), std::string::npos);
    EXPECT_NE(message("ambient_hz=-1").find("ambient_hz must be >= 0"), std::string::npos);
    EXPECT_NE(message("photons=-1").find("photons must be > 0"), std::string::npos);
    EXPECT_NE(message("photons=0").find("photons must be > 0"), std::string::npos);
    EXPECT_NE(message("efficiency=1.5").find("(0, 1]"), std::string::npos);
    EXPECT_NE(message("cycles=0.5").find("whole number >= 1"), std::string::npos);
    EXPECT_NE(message("afterpulse=1").find("[0, 1)"), std::string::npos);
    EXPECT_NE(message("photons=lots").find("not a number"), std::string::npos);
    EXPECT_NE(message("darkhz=3").find("unknown key"), std::string::npos);
    EXPECT_NE(message("coates").find("add pileup"), std::string::npos);
}

}  // namespace
}  // namespace tpb
