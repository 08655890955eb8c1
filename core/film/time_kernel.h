// The progressive time kernel (issue 14; Marco, Jarosz, Gutierrez, Jarabo 2019, "Progressive
// Transient Photon Beams"): an estimate's time profile f(t) (time_splat.h: an instant, or an
// exponential segment mapped linearly to time) is convolved with a box of half-width tau (m of OPL),
//   k_tau(t) = 1 / (2 tau) on [-tau, tau],
// before it is binned. Its width shrinks pass after pass with the spatial radius (the schedule and
// why: docs/theory/derivations.md "Progressive time kernel"; integrators/photon_beams.cpp).
//
// Glossary (units): t, a, b, tA, tB OPL time (m); s distance along the camera segment (m); kappa
// the decay of the energy density along s (1/m, per channel); tau the kernel's half-width (m of OPL);
// F the CDF of the arrival time, G its antiderivative (G' = F), H the CDF after the convolution.
//
// The share of bin [a, b] of (f * k_tau) is
//   S = [G(b + tau) - G(b - tau) - G(a + tau) + G(a - tau)] / (2 tau) = H(b) - H(a),          (K1)
//   H(t) = (1 / 2 tau) Int_{t-tau}^{t+tau} F(t') dt',
// the mean of F over the kernel's window. H is evaluated as that mean directly (never as a
// difference of two G's, which would cancel for small tau), at each bin boundary once, so the bins
// telescope: sum of shares + H(start) + (1 - H(end)) = 1 to rounding (OutsideFilm keeps the ends).
//
// (i) An instant at t0: F = step(t - t0), G(t) = max(0, t - t0) (a ramp):
//   H(t) = clamp((t - t0 + tau) / (2 tau), 0, 1).                                              (K2)
// (ii) The exponential segment of splatTime: density exp(-kappa s) on [s0, s1] with t = a + b s.
//   In time it lives on [tA, tB], T = tB - tA = |b| (s1 - s0), with density exp(-lambda (t - tA)),
//   lambda = kappa / b (any signs). When lambda < 0 the profile is mirrored, t -> tA + tB - t (the
//   box is symmetric: smoothing commutes with the mirror; the shares are then read off reversed),
//   so it always decays, with mu = |kappa| (s1 - s0) over x = (t - tA) / T in [0, 1]:
//     F(x) = (1 - e^{-mu x}) / (1 - e^{-mu}) = x phi1(-mu x) / phi1(-mu),
//     G(x) = T x^2 phi2(-mu x) / phi1(-mu)         (x in [0, 1]; G = G(1) + (t - tB) after tB),
//   with phi1(z) = (e^z - 1) / z and phi2(z) = (e^z - 1 - z) / z^2, the phi-functions of
//   exponential integrators. The mean of F over [u, u + w] inside [0, 1] is
//     A(u, w) = [G(u + w) - G(u)] / (T w) = [u phi1(-mu u) + e^{-mu u} w phi2(-mu w)] / phi1(-mu), (K3)
//   (from Int_u^{u+w} (1 - e^{-mu x}) dx = w [1 - e^{-mu u} phi1(-mu w)] and 1 - phi1(-y) = y phi2(-y)):
//   every term is >= 0, so nothing cancels for small mu, small w or both; mu = 0 gives u + w/2 (the
//   uniform profile), w = 0 gives F(u). The window [t - tau, t + tau] is split into the part before
//   tA (F = 0), the part inside (K3) and the part after tB (F = 1):
//     H(t) = [|inside| A + |after|] / (2 tau),                                                (K4)
//   and (K2) is (K4) with T = 0. Per channel (kappa is RGB), one evaluation for a grey kappa.
// Tested against quadrature of the convolution in tests/estimators/test_time_kernel.cpp.
#pragma once
#include "film/time_splat.h"
#include "film/time_axis.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace tpb {

// One pass's time kernel of one estimator (the pass's half-width; None = the bins alone).
struct TimeKernel {
    TimeKernelKind kind = TimeKernelKind::None;
    double halfWidth = 0.0;  // tau, m of OPL
    bool active() const { return kind == TimeKernelKind::Box && halfWidth > 0.0; }
};

// phi1(z) = (e^z - 1) / z, phi1(0) = 1.
inline double expPhi1(double z) {
    if (std::abs(z) < 1e-5) return 1.0 + z * (0.5 + z * (1.0 / 6.0));
    return std::expm1(z) / z;
}

// phi2(z) = (e^z - 1 - z) / z^2, phi2(0) = 1/2. Series sum_k z^k / (k+2)! for |z| < 0.5 (16 terms:
// truncation < 0.5^16 / 18! ~ 2e-21); outside it the direct form cancels by at most ~3 bits.
inline constexpr std::array<double, 16> kPhi2Series = [] {  // 1 / (k+2)!
    std::array<double, 16> c{};
    double factorial = 1.0;
    for (int k = 0; k < 16; ++k) {
        factorial *= static_cast<double>(k + 2);
        c[static_cast<size_t>(k)] = 1.0 / factorial;
    }
    return c;
}();
inline double expPhi2(double z) {
    if (std::abs(z) < 0.5) {
        double s = 0.0;
        for (int k = 15; k >= 0; --k) s = kPhi2Series[static_cast<size_t>(k)] + z * s;
        return s;
    }
    return (std::expm1(z) - z) / (z * z);
}

// H(t) of (K4): the CDF of a decaying exponential profile on [tA, tA + T] (rate mu over the
// support; T = 0: an instant at tA) smoothed by the box of half-width tau > 0.
class SmoothedCdf {
public:
    SmoothedCdf(double tA, double T, double mu, double tau)
        : tA_(tA), T_(T), mu_(mu), tau_(tau), invPhi1Mu_(1.0 / expPhi1(-mu)) {}

    double operator()(double t) const {
        const double p = t - tau_, q = t + tau_;
        const double window = q - p;              // 2 tau as represented around t
        if (!(window > 0.0)) return pointCdf(t);  // tau below the resolution of t: F itself
        const double tB = tA_ + T_;
        const double after = std::max(0.0, q - std::max(p, tB));
        double inside = 0.0;
        if (T_ > 0.0) {
            const double lo = std::max(p, tA_), hi = std::min(q, tB);
            if (hi > lo) {
                const double len = hi - lo;
                const double u = std::clamp((lo - tA_) / T_, 0.0, 1.0);
                inside = len * meanF(u, std::min(len / T_, 1.0 - u));
            }
        }
        return std::min(1.0, (inside + after) / window);
    }

private:
    // (K3): the mean of F over [u, u + w], normalised coordinates.
    double meanF(double u, double w) const {
        return (u * expPhi1(-mu_ * u) + std::exp(-mu_ * u) * w * expPhi2(-mu_ * w)) * invPhi1Mu_;
    }
    double pointCdf(double t) const {
        if (t < tA_) return 0.0;
        if (!(T_ > 0.0) || t >= tA_ + T_) return 1.0;
        return std::min(1.0, meanF((t - tA_) / T_, 0.0));
    }
    double tA_, T_, mu_, tau_, invPhi1Mu_;
};

// splatTime (time_splat.h) with the estimate's time profile convolved with `kernel` first (K1-K4):
// the same arguments, the same instant rule (an interval shorter than 1e-9 bin is an instant at its
// middle), energy before/after the film returned. An inactive kernel calls splatTime itself, so
// the films are bit-identical to the kernel-free code.
// With a floor (time_splat.h, ArrivalFloor) the smoothed profile's part earlier than `floor` is
// mirrored about it: its CDF becomes H_f(t) = H(t) - H(2 floor - t) for t > floor, 0 before (the
// box is applied first, then the floor: the box alone puts light up to tau before any real path).
template <class Sink>
inline OutsideFilm splatTimeSmoothed(const TimeBins& tb, const Color& energy, const Color& kappa, double s0, double s1,
                                     double a, double b, const TimeKernel& kernel, Sink&& sink, double floor = -kInf) {
    if (!kernel.active()) return splatTimeFloored(tb, energy, SegmentProfile(kappa, s0, s1), a, b, floor, sink);
    const double tau = kernel.halfWidth;
    const double tA0 = a + b * s0, tB0 = a + b * s1;
    double tA = std::min(tA0, tB0), tB = std::max(tA0, tB0);
    const double len = s1 - s0;
    const bool instant = !(len > 0.0) || (tB - tA) <= 1e-9 * tb.binWidth;
    if (instant) tA = tB = 0.5 * (tA + tB);
    const double mirrorSum = tA + tB;  // t -> tA + tB - t swaps tA and tB

    OutsideFilm out;
    // A floor above the support's start: the support starts at the floor and ends at the later of
    // its own end and its start's mirror image.
    const bool floored = floor > tA - tau;
    const double lowest = floored ? floor : tA - tau;
    const double highest = floored ? std::max(tB + tau, 2.0 * floor - (tA - tau)) : tB + tau;
    const int k0 = std::max(tb.binOf(lowest), 0);
    const int k1 = std::min(tb.binOf(highest), tb.bins - 1);
    if (k1 < k0) {  // the smoothed support lies wholly before or after the film
        if (tb.binOf(highest) < 0)
            out.before = energy;
        else
            out.after = energy;
        return out;
    }

    // One channel: its CDF on the decaying side, and whether time runs mirrored there.
    struct Channel {
        SmoothedCdf cdf;
        bool mirror;
        // D at boundary j (bin j's lower edge); the film's outer edges exact when the support ends
        // inside the film (P = 0 below e_k0 <= tA - tau, P = 1 above e_{k1+1} >= tB + tau).
        double at(const TimeBins& tb, int j, int k0, int k1, double mirrorSum) const {
            if (j == k0 && k0 > 0) return mirror ? 1.0 : 0.0;
            if (j == k1 + 1 && k1 < tb.bins - 1) return mirror ? 0.0 : 1.0;
            const double e = tb.startOpl + j * tb.binWidth;
            return cdf(mirror ? mirrorSum - e : e);
        }
        double share(double dLo, double dHi) const { return std::max(0.0, mirror ? dLo - dHi : dHi - dLo); }
        double below(double d) const { return mirror ? 1.0 - d : d; }  // P(t < edge)
        double belowAt(double t, double mirrorSum) const { return below(cdf(mirror ? mirrorSum - t : t)); }
        double above(double d) const { return mirror ? d : 1.0 - d; }  // P(t >= edge)
    };
    const auto channel = [&](double k) {
        const bool mirror = !instant && k * b < 0.0;
        return Channel{SmoothedCdf(tA, instant ? 0.0 : tB - tA, instant ? 0.0 : std::abs(k) * len, tau), mirror};
    };
    const bool grey = kappa.x == kappa.y && kappa.y == kappa.z;
    const Channel cx = channel(kappa.x);
    const Channel cy = grey ? cx : channel(kappa.y);
    const Channel cz = grey ? cx : channel(kappa.z);

    if (floored) {
        // P(t < e_j) after the reflection, per channel: 0 up to the floor, H(e) - H(2 floor - e) after.
        const auto below = [&](const Channel& c, int j) {
            const double e = tb.startOpl + j * tb.binWidth;
            if ((j == k0 && k0 > 0) || !(e > floor)) return 0.0;
            if (j == k1 + 1 && k1 < tb.bins - 1) return 1.0;
            return std::clamp(c.belowAt(e, mirrorSum) - c.belowAt(2.0 * floor - e, mirrorSum), 0.0, 1.0);
        };
        const auto belowAll = [&](int j) {
            const double x = below(cx, j);
            return grey ? Color(x) : Color(x, below(cy, j), below(cz, j));
        };
        Color lo = belowAll(k0);
        if (k0 == 0) out.before = energy * lo;
        for (int k = k0; k <= k1; ++k) {
            const Color hi = belowAll(k + 1);
            const Color f(std::max(0.0, hi.x - lo.x), std::max(0.0, hi.y - lo.y), std::max(0.0, hi.z - lo.z));
            if (!isBlack(f)) sink(k, energy * f);
            lo = hi;
        }
        if (k1 == tb.bins - 1) out.after = energy * (Color(1.0) - lo);
        return out;
    }
    Color lo(cx.at(tb, k0, k0, k1, mirrorSum));
    if (!grey) lo = Color(lo.x, cy.at(tb, k0, k0, k1, mirrorSum), cz.at(tb, k0, k0, k1, mirrorSum));
    if (k0 == 0) out.before = energy * Color(cx.below(lo.x), cy.below(lo.y), cz.below(lo.z));
    for (int k = k0; k <= k1; ++k) {
        Color hi(cx.at(tb, k + 1, k0, k1, mirrorSum));
        if (!grey) hi = Color(hi.x, cy.at(tb, k + 1, k0, k1, mirrorSum), cz.at(tb, k + 1, k0, k1, mirrorSum));
        const Color f(cx.share(lo.x, hi.x), cy.share(lo.y, hi.y), cz.share(lo.z, hi.z));
        if (!isBlack(f)) sink(k, energy * f);
        lo = hi;
    }
    if (k1 == tb.bins - 1) out.after = energy * Color(cx.above(lo.x), cy.above(lo.y), cz.above(lo.z));
    return out;
}

}  // namespace tpb
