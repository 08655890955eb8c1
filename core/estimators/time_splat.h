// Spreading one ray-beam estimate over the film's time bins (paper Sec. 4, eqs. 12-15, Fig. 2d).
//
// An estimate carries energy E (RGB) produced along s in [s0, s1] of the camera segment, with
// energy density proportional to exp(-kappa s) (kappa per channel, see beam2d.h), and the
// time of flight is linear in s: t(s) = a + b s (OPL, m). Two profiles:
//   Exact:   the density above, integrated over each bin in closed form (stable form with g(x)).
//   Uniform: the paper's even spread over [t-, t+] (= kappa 0, since t is linear in s).
// When the interval collapses (|b| (s1 - s0) tiny, e.g. a beam pointing straight at the camera)
// all energy goes to one bin. Energy before the film's start and after its end is returned
// (OutsideFilm), never dropped silently: the film keeps both, per pixel and axis.
// The optional progressive time kernel (time_kernel.h) convolves these profiles with a box first.
#pragma once
#include "base/math.h"

#include <algorithm>

namespace tpb {

struct TimeBins {
    double startOpl = 0.0;  // m
    double binWidth = 0.01; // m
    int bins = 1;
    double endOpl() const { return startOpl + binWidth * bins; }
    // Bin of time t, or -1 before the film / bins after it (clamped, no integer overflow).
    int binOf(double t) const {
        const double k = std::floor((t - startOpl) / binWidth);
        if (!(k >= 0.0)) return -1;
        if (k >= static_cast<double>(bins)) return bins;
        return static_cast<int>(k);
    }
};

// Cumulative mass of exp(-kappa s) on [s0, s1], reflected so the exponent always decays:
// M(s) = (1 - exp(-|kappa| (s' - s0))) / (1 - exp(-|kappa| len)), s' = s (kappa >= 0) or s0 + s1 - s.
// The mass in a bin is M(v) - M(u): one expm1 per bin boundary. (Differences of M lose relative
// precision only in bins whose share is itself tiny, so the absolute error stays ~1e-16 of E.)
// The normalisation 1 / total is computed on first use: an estimate that lands in one bin (most
// of them on coarse films) never needs it, nor its expm1.
struct ExpProfile {
    double kappa, s0, s1;
    bool uniform;
    ExpProfile(double k, double a, double b) : kappa(std::abs(k)), s0(a), s1(b) {
        uniform = !(kappa * (b - a) > 1e-12);
        reflect = k < 0.0;
    }
    double total() const {  // the unnormalised mass of [s0, s1]: cumulative(far end)
        if (!(total_ >= 0.0)) total_ = uniform ? s1 - s0 : -std::expm1(-kappa * (s1 - s0));
        return total_;
    }
    double invTotal() const {
        if (!(invTotal_ >= 0.0)) invTotal_ = 1.0 / total();
        return invTotal_;
    }
    // Unnormalised mass on the decaying side of s. At the segment's ends (where splatTime's
    // clamped bin boundaries land) without a call: 0 at the near end (-expm1(-0) = 0) and the
    // cached total at the far end (x = s1 - s0, the same expression): the same values, bit for bit.
    double cumulative(double s) const {
        const double x = reflect ? (s1 - s) : (s - s0);
        if (uniform) return x;
        if (x == 0.0) return 0.0;
        if (s == (reflect ? s0 : s1)) return total();
        return -std::expm1(-kappa * x);
    }
    double mass(double u, double v) const {
        const double m = reflect ? cumulative(u) - cumulative(v) : cumulative(v) - cumulative(u);
        return std::max(0.0, m) * invTotal();
    }
    bool reflect = false;

private:
    mutable double total_ = -1.0, invTotal_ = -1.0;  // < 0: not computed yet
};

// Fraction of the mass of exp(-kappa s) on [s0, s1] that lies in [u, v] (s0 <= u <= v <= s1).
inline double expMassFraction(double kappa, double s0, double s1, double u, double v) {
    return ExpProfile(kappa, s0, s1).mass(u, v);
}

// The profile of one estimate on its segment, per channel: built once and spread on both time
// axes (the profile depends on kappa and [s0, s1] only, not on the axis). Grey media (the three
// kappas equal) evaluate one channel.
struct SegmentProfile {
    double s0, s1;
    bool grey;
    ExpProfile x, y, z;
    SegmentProfile(const Color& kappa, double a, double b)
        : s0(a), s1(b), grey(kappa.x == kappa.y && kappa.y == kappa.z), x(kappa.x, a, b),
          y(grey ? x : ExpProfile(kappa.y, a, b)), z(grey ? x : ExpProfile(kappa.z, a, b)) {}
    // Unnormalised mass on the decaying side of s, per channel, s clipped to [s0, s1].
    Color cumulative(double s) const {
        s = std::clamp(s, s0, s1);
        const double cx = x.cumulative(s);
        return grey ? Color(cx) : Color(cx, y.cumulative(s), z.cumulative(s));
    }
    // Share of the energy between two points of the segment (in either order): |M(q) - M(p)|.
    Color share(const Color& cp, const Color& cq) const {
        const double fx = std::abs(cq.x - cp.x) * x.invTotal();
        return grey ? Color(fx) : Color(fx, std::abs(cq.y - cp.y) * y.invTotal(), std::abs(cq.z - cp.z) * z.invTotal());
    }
};

// Energy of one estimate that fell outside the film, split by side: `before` arrived before the
// film's first bin (it still counts for continuous emission: a step response includes everything
// that arrived earlier), `after` after its last bin (it counts only for the steady state).
struct OutsideFilm {
    Color before{0.0};
    Color after{0.0};
};

// Cost: an estimate inside one bin goes there whole (no transcendental call: its share is 1);
// otherwise one expm1 per channel per bin boundary it crosses, each boundary shared by the two
// bins on its sides (k1 - k0 + 2 per channel, not 2 per bin).
template <class Sink>
inline OutsideFilm splatTime(const TimeBins& tb, const Color& energy, const SegmentProfile& p, double a, double b,
                             Sink&& sink) {
    OutsideFilm out;
    const double s0 = p.s0, s1 = p.s1;
    const double tA0 = a + b * s0, tB0 = a + b * s1;
    const double tA = std::min(tA0, tB0), tB = std::max(tA0, tB0);
    const double len = s1 - s0;
    if (!(len > 0.0) || (tB - tA) <= 1e-9 * tb.binWidth) {
        const int k = tb.binOf(0.5 * (tA + tB));
        if (k < 0) out.before = energy;
        else if (k >= tb.bins) out.after = energy;
        else sink(k, energy);
        return out;
    }
    const int kA = tb.binOf(tA), kB = tb.binOf(tB);
    if (kA == kB && kA >= 0 && kA < tb.bins) {  // wholly inside one bin
        sink(kA, energy);
        return out;
    }
    // t(s) = a + b s crosses bin boundary j (time start + j binWidth) at s = (t_j - a) / b (b != 0
    // here: the interval spans time); the film's start is boundary 0, its end boundary `bins`.
    const auto cumulativeAt = [&](int j) { return p.cumulative((tb.startOpl + j * tb.binWidth - a) / b); };
    const bool forward = b > 0.0;  // s grows with t: the segment's early end is s0, else s1
    const int k0 = std::max(kA, 0), k1 = std::min(kB, tb.bins - 1);
    Color lo = cumulativeAt(k0);
    if (tA < tb.startOpl) out.before = energy * p.share(p.cumulative(forward ? s0 : s1), lo);
    for (int k = k0; k <= k1; ++k) {
        const Color hi = cumulativeAt(k + 1);
        const Color f = p.share(lo, hi);
        lo = hi;
        if (isBlack(f)) continue;
        sink(k, energy * f);
    }
    if (tB > tb.endOpl()) out.after = energy * p.share(lo, p.cumulative(forward ? s1 : s0));
    return out;
}

template <class Sink>
inline OutsideFilm splatTime(const TimeBins& tb, const Color& energy, const Color& kappa, double s0, double s1,
                             double a, double b, Sink&& sink) {
    return splatTime(tb, energy, SegmentProfile(kappa, s0, s1), a, b, sink);
}

}  // namespace tpb
