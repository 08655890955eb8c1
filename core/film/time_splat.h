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
#include "film/time_axis.h"

#include <algorithm>

namespace tpb {

// The exponential profile exp(-kappa s) on [s0, s1] of one channel, seen from its decaying end:
// x = s - s0 (kappa >= 0) or s1 - s (kappa < 0, `reflect`), density exp(-|kappa| x), unnormalised
// mass of [0, x] u(x) = 1 - exp(-|kappa| x) (splat_detail::massTo). `uniform` when |kappa| len is
// too small to matter (<= 1e-12): density 1, u(x) = x. The total u(len) and its inverse are
// computed on first use: an estimate that lands in one bin (most of them on coarse films) never
// needs them, nor their expm1.
struct ExpProfile {
    double kappa, s0, s1;
    bool uniform;
    ExpProfile() = default;  // unset: SegmentProfile's y and z of a grey profile (never read)
    ExpProfile(double k, double a, double b) : kappa(std::abs(k)), s0(a), s1(b) {
        uniform = !(kappa * (b - a) > 1e-12);
        reflect = k < 0.0;
    }
    double total() const {  // the unnormalised mass of [s0, s1]
        if (!(total_ >= 0.0)) total_ = uniform ? s1 - s0 : oneMinusExpNeg(kappa * (s1 - s0));
        return total_;
    }
    // Gives the total computed elsewhere with the same expression, oneMinusExpNeg(|k| (s1 - s0))
    // (beam2d's transmittance integral has it: ChannelIntegral), so it is not computed twice;
    // ignored when uniform or when t < 0 (not computed there).
    void shareTotal(double t) {
        if (!uniform && t >= 0.0) total_ = t;
    }
    double invTotal() const {
        if (!(invTotal_ >= 0.0)) invTotal_ = 1.0 / total();
        return invTotal_;
    }
    bool reflect = false;

private:
    mutable double total_ = -1.0, invTotal_ = -1.0;  // < 0: not computed yet
};

// The profile of one estimate on its segment, per channel: built once and spread on both time
// axes (the profile depends on kappa and [s0, s1] only, not on the axis). Grey media (the three
// kappas equal) evaluate one channel.
struct SegmentProfile {
    double s0, s1;
    Color kappa;  // 1/m, signed, per channel
    bool grey;
    ExpProfile x, y, z;
    // A grey profile (three equal kappas) sets and reads x only: y and z stay unset.
    SegmentProfile(const Color& k, double a, double b)
        : s0(a), s1(b), kappa(k), grey(k.x == k.y && k.y == k.z), x(k.x, a, b) {
        if (!grey) {
            y = ExpProfile(k.y, a, b);
            z = ExpProfile(k.z, a, b);
        }
    }
    // The totals oneMinusExpNeg(|kappa| (s1 - s0)) per channel where already computed (< 0: not).
    void shareTotals(const Color& t) {
        x.shareTotal(t.x);
        if (!grey) {
            y.shareTotal(t.y);
            z.shareTotal(t.z);
        }
    }
};

// Energy of one estimate that fell outside the film, split by side: `before` arrived before the
// film's first bin (it still counts for continuous emission: a step response includes everything
// that arrived earlier), `after` after its last bin (it counts only for the steady state).
struct OutsideFilm {
    Color before{0.0};
    Color after{0.0};
};

namespace splat_detail {

// u(x) = 1 - exp(-kappa x) (oneMinusExpNeg, base/math.h): the unnormalised mass of [0, x] on the
// decaying side (x for a uniform profile).
TPB_HOT_INLINE double massTo(const ExpProfile& p, double x) { return p.uniform ? x : oneMinusExpNeg(p.kappa * x); }

// The pieces of one estimate, in the order of x = the distance from the segment's end where the
// density is largest (the decaying side of its channels' profiles, which all share it here): piece
// 0 is [0, x_1], piece i is [x_i, x_i + dx] (dx = one bin width of time, in s), piece n is
// [x_n, len], with n >= 1 bin boundaries x_1 < ... < x_n inside the segment. Piece i lands in bin
// kFirst + step i (-1: before the film, `bins`: after it). C channels: 1 (grey, or one channel of
// a colour splat whose channels decay towards different ends), or 3 sharing the side.
//
// Masses, per channel, normalised by the profile's total T = u(len):
//   n <= 3: from the boundaries, u(x_1) / T, (u(x_{i+1}) - u(x_i)) / T, (T - u(x_n)) / T (one
//           expm1 per boundary; differences of u lose relative precision only in bins whose share
//           is itself tiny: the absolute error stays ~1e-16 of the estimate);
//   n >= 4: by recurrence, since the interior cuts are equally spaced: with E_i = exp(-kappa x_i) =
//           E_1 q^(i-1), q = exp(-kappa dx), the interior piece i has E_i u(dx) / T and the last
//           E_n u(len - x_n) / T: three expm1 whatever n (E_1 = 1 - u(x_1), q = 1 - u(dx), each to
//           ~1e-16 absolute; the recurrence adds ~n ulp relative). Uniform profiles: E = 1, q = 1.
// Each channel's masses depend only on its own profile, so a colour splat equals, channel by
// channel, the grey splat with that channel's kappa (tests/estimators/test_beam2d.cpp).
// cut(i) is x_i, i = 1..n (clamped to [0, len], so that a boundary within rounding of the
// segment's end gives the piece beyond it exactly nothing).
template <int C, class Cut, class Dx, class Sink>
TPB_HOT_INLINE void splatPieces(const ExpProfile* const (&ch)[C], const Color& energy, int n, const Cut& cut,
                                const Dx& dxOf, double len, int kFirst, int step, int bins, OutsideFilm& out,
                                Sink& sink) {
    const auto emit = [&](int k, const double(&m)[C]) TPB_HOT_LAMBDA {
        Color f;
        if constexpr (C == 1)
            f = Color(std::max(0.0, m[0]));
        else
            f = Color(std::max(0.0, m[0]), std::max(0.0, m[1]), std::max(0.0, m[2]));
        if (isBlack(f)) return;
        const Color e = energy * f;
        if (k < 0)
            out.before += e;
        else if (k >= bins)
            out.after += e;
        else
            sink(k, e);
    };
    double invT[C], u1[C], m[C];
    const double x1 = cut(1);
    for (int c = 0; c < C; ++c) {
        invT[c] = ch[c]->invTotal();
        u1[c] = massTo(*ch[c], x1);
        m[c] = u1[c] * invT[c];
    }
    emit(kFirst, m);
    if (n <= 3) {
        double prev[C];
        for (int c = 0; c < C; ++c) prev[c] = u1[c];
        for (int i = 1; i <= n; ++i) {
            double next[C];
            if (i < n) {
                const double x = cut(i + 1);
                for (int c = 0; c < C; ++c) next[c] = massTo(*ch[c], x);
            } else {
                for (int c = 0; c < C; ++c) next[c] = ch[c]->total();
            }
            for (int c = 0; c < C; ++c) {
                m[c] = (next[c] - prev[c]) * invT[c];
                prev[c] = next[c];
            }
            emit(kFirst + step * i, m);
        }
        return;
    }
    double E[C], q[C], g[C];
    const double dx = dxOf();
    for (int c = 0; c < C; ++c) {
        const double uDx = massTo(*ch[c], dx);
        E[c] = ch[c]->uniform ? 1.0 : 1.0 - u1[c];
        q[c] = ch[c]->uniform ? 1.0 : 1.0 - uDx;
        g[c] = uDx * invT[c];
    }
    for (int i = 1; i < n; ++i) {
        for (int c = 0; c < C; ++c) {
            m[c] = E[c] * g[c];
            E[c] *= q[c];
        }
        emit(kFirst + step * i, m);
    }
    const double last = len - cut(n);
    for (int c = 0; c < C; ++c) m[c] = E[c] * massTo(*ch[c], last) * invT[c];
    emit(kFirst + step * n, m);
}

}  // namespace splat_detail

// Cost: an estimate inside one bin goes there whole (no transcendental call: its share is 1);
// otherwise splat_detail::splatPieces: per channel one expm1 per bin boundary it crosses up to
// three boundaries, three in all beyond (plus the profile's total, shared by both time axes).
template <class Sink>
TPB_HOT_INLINE OutsideFilm splatTime(const TimeBins& tb, const Color& energy, const SegmentProfile& p, double a,
                                     double b, Sink&& sink) {
    OutsideFilm out;
    const double invWidth = 1.0 / tb.binWidth;  // for binOf's two calls (the same bins as dividing)
    const double s0 = p.s0, s1 = p.s1;
    const double tA0 = a + b * s0, tB0 = a + b * s1;
    const double tA = std::min(tA0, tB0), tB = std::max(tA0, tB0);
    const double len = s1 - s0;
    if (!(len > 0.0) || (tB - tA) <= 1e-9 * tb.binWidth) {
        const int k = tb.binOf(0.5 * (tA + tB), invWidth);
        if (k < 0)
            out.before = energy;
        else if (k >= tb.bins)
            out.after = energy;
        else
            sink(k, energy);
        return out;
    }
    const int kA = tb.binOf(tA, invWidth), kB = tb.binOf(tB, invWidth);
    if (kA == kB) {  // wholly inside one bin, or wholly before or after the film
        if (kA < 0)
            out.before = energy;
        else if (kA >= tb.bins)
            out.after = energy;
        else
            sink(kA, energy);
        return out;
    }
    // Boundaries T_j = start + j binWidth, j = kA+1 .. kB, cut [tA, tB] (b != 0 here: the interval
    // spans time) into pieces kA .. kB. Boundary j lies at s_j = (T_j - a) / b, clamped to [s0, s1];
    // in x (from the decaying end of the channels at hand, `reflect`) at s_j - s0 or s1 - s_j.
    // x grows with time when b > 0 and the profile decays along s, or b < 0 and it is reflected.
    // One bin width of time in s, computed only by the recurrence (n >= 4; a division).
    const auto dxOf = [&]() TPB_HOT_LAMBDA { return tb.binWidth / std::abs(b); };
    const int n = kB - kA;
    const auto side = [&](const ExpProfile& e, const Color& en, const auto& channels) TPB_HOT_LAMBDA {
        const bool xWithTime = (b > 0.0) != e.reflect;
        const auto cut = [&](int i) TPB_HOT_LAMBDA {  // x of the i-th boundary in x order
            const int j = xWithTime ? kA + i : kB + 1 - i;
            const double sj = std::clamp((tb.startOpl + j * tb.binWidth - a) / b, s0, s1);
            return e.reflect ? s1 - sj : sj - s0;
        };
        splat_detail::splatPieces(channels, en, n, cut, dxOf, len, xWithTime ? kA : kB, xWithTime ? 1 : -1, tb.bins,
                                  out, sink);
    };
    if (p.grey) {
        const ExpProfile* const ch[1] = {&p.x};
        side(p.x, energy, ch);
    } else if (p.x.reflect == p.y.reflect && p.y.reflect == p.z.reflect) {
        const ExpProfile* const ch[3] = {&p.x, &p.y, &p.z};
        side(p.x, energy, ch);
    } else {  // the channels decay towards different ends: each on its own
        const ExpProfile* const cx[1] = {&p.x};
        const ExpProfile* const cy[1] = {&p.y};
        const ExpProfile* const cz[1] = {&p.z};
        side(p.x, Color(energy.x, 0.0, 0.0), cx);
        side(p.y, Color(0.0, energy.y, 0.0), cy);
        side(p.z, Color(0.0, 0.0, energy.z), cz);
    }
    return out;
}

// The earliest time, per axis (OPL, m), at which a real path through an estimate's photon can
// arrive (docs/developer/adding-an-estimator.md, "Causality"): no part of the estimate's time profile is binned
// earlier; the part that would be is mirrored about the floor instead. -inf: no floor (the default).
struct ArrivalFloor {
    double real = -kInf;
    double unwarped = -kInf;
    bool active() const { return real > -kInf || unwarped > -kInf; }
};

// A profile with its part earlier than `floor` mirrored about it (t -> 2 floor - t, the
// reflection of kernel density estimation at a boundary): calls piece(share, profile, a', b') for
// each part, share the part's mass per channel. Nothing earlier than the floor: the whole profile
// (share 1, a, b). Else the late part at a + b s and the early part, mirrored, at (2 floor - a) - b s
// (late first). An interval of time no wider than `instantWidth` is an instant at its middle.
// The bins (splatTimeFloored) and the phasor film (film/phasor.cpp) split alike.
template <class Piece>
TPB_HOT_INLINE void flooredPieces(const SegmentProfile& p, double a, double b, double floor, double instantWidth,
                                  Piece&& piece) {
    const double tA0 = a + b * p.s0, tB0 = a + b * p.s1;
    const double tA = std::min(tA0, tB0), tB = std::max(tA0, tB0);
    // (A floor within rounding of the profile's start, as the unwarped floor of a beam at its
    // overlap's first point, changes nothing.)
    if (!(floor > tA + 1e-12 * (1.0 + std::abs(tA)))) return piece(Color(1.0), p, a, b);
    const double mirrored = 2.0 * floor - a;  // t = mirrored - b s after the reflection
    const bool collapsed = !(p.s1 - p.s0 > 0.0) || (tB - tA) <= instantWidth;
    if (collapsed) return 0.5 * (tA + tB) >= floor ? piece(Color(1.0), p, a, b) : piece(Color(1.0), p, mirrored, -b);
    if (!(floor < tB)) return piece(Color(1.0), p, mirrored, -b);
    // t(s) = floor at s_c inside the segment (b != 0 here): the early part is [s0, s_c] when time
    // grows along s, [s_c, s1] when it falls. Its share per channel, from the profile's mass.
    const double sc = std::clamp((floor - a) / b, p.s0, p.s1);
    const auto earlyShare = [&](const ExpProfile& e) {
        const double below = e.reflect ? 1.0 - splat_detail::massTo(e, p.s1 - sc) * e.invTotal()
                                       : splat_detail::massTo(e, sc - p.s0) * e.invTotal();
        return std::clamp(b > 0.0 ? below : 1.0 - below, 0.0, 1.0);
    };
    const double fx = earlyShare(p.x);
    const Color early = p.grey ? Color(fx) : Color(fx, earlyShare(p.y), earlyShare(p.z));
    const SegmentProfile late(p.kappa, b > 0.0 ? sc : p.s0, b > 0.0 ? p.s1 : sc);
    const SegmentProfile before(p.kappa, b > 0.0 ? p.s0 : sc, b > 0.0 ? sc : p.s1);
    piece(Color(1.0) - early, late, a, b);
    piece(early, before, mirrored, -b);
}

// splatTime with the profile's part earlier than `floor` mirrored about it (flooredPieces): energy
// kept, nothing before the floor, no spike. When nothing is earlier than the floor it is splatTime
// itself (bit for bit).
template <class Sink>
TPB_HOT_INLINE OutsideFilm splatTimeFloored(const TimeBins& tb, const Color& energy, const SegmentProfile& p, double a,
                                            double b, double floor, Sink&& sink) {
    OutsideFilm out;
    // (splatTime's instant rule: an interval narrower than 1e-9 bin.)
    flooredPieces(p, a, b, floor, 1e-9 * tb.binWidth,
                  [&](const Color& share, const SegmentProfile& q, double qa, double qb) TPB_HOT_LAMBDA {
                      const OutsideFilm o = splatTime(tb, energy * share, q, qa, qb, sink);
                      out.before += o.before;
                      out.after += o.after;
                  });
    return out;
}

template <class Sink>
inline OutsideFilm splatTime(const TimeBins& tb, const Color& energy, const Color& kappa, double s0, double s1,
                             double a, double b, Sink&& sink) {
    return splatTime(tb, energy, SegmentProfile(kappa, s0, s1), a, b, sink);
}

}  // namespace tpb
