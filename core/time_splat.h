// Spreading one ray-beam estimate over the film's time bins (paper Sec. 4, eqs. 12-15, Fig. 2d).
//
// An estimate carries energy E (RGB) produced along s in [s0, s1] of the camera segment, with
// energy density proportional to exp(-kappa s) (kappa per channel, see beam_kernel.h), and the
// time of flight is linear in s: t(s) = a + b s (OPL, m). Two profiles:
//   Exact:   the density above, integrated over each bin in closed form (stable form with g(x)).
//   Uniform: the paper's even spread over [t-, t+] (= kappa 0, since t is linear in s).
// When the interval collapses (|b| (s1 - s0) tiny, e.g. a beam pointing straight at the camera)
// all energy goes to one bin. Energy before the film's start or after its end is added to
// `outside` (counted, never dropped silently).
#pragma once
#include "beam_kernel.h"
#include "math.h"

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

// Fraction of the mass of exp(-kappa s) on [s0, s1] that lies in [u, v] (s0 <= u <= v <= s1).
inline double expMassFraction(double kappa, double s0, double s1, double u, double v) {
    const double len = s1 - s0;
    if (kappa < 0.0) {  // reflect s -> s0 + s1 - s so the exponent decays
        const double u2 = s0 + s1 - v, v2 = s0 + s1 - u;
        u = u2; v = v2; kappa = -kappa;
    }
    return std::exp(-kappa * (u - s0)) * (v - u) * expRel(kappa * (v - u)) / (len * expRel(kappa * len));
}

template <class Sink>
inline void splatTime(const TimeBins& tb, const Color& energy, const Color& kappa, double s0, double s1,
                      double a, double b, Sink&& sink, Color& outside) {
    const double tA0 = a + b * s0, tB0 = a + b * s1;
    const double tA = std::min(tA0, tB0), tB = std::max(tA0, tB0);
    const double len = s1 - s0;
    if (!(len > 0.0) || (tB - tA) <= 1e-9 * tb.binWidth) {
        const int k = tb.binOf(0.5 * (tA + tB));
        if (k >= 0 && k < tb.bins) sink(k, energy);
        else outside += energy;
        return;
    }
    const int k0 = std::max(tb.binOf(tA), 0);
    const int k1 = std::min(tb.binOf(tB), tb.bins - 1);
    const bool grey = kappa.x == kappa.y && kappa.y == kappa.z;
    Color inside(0.0);
    for (int k = k0; k <= k1; ++k) {
        const double tLo = tb.startOpl + k * tb.binWidth;
        double u = (tLo - a) / b, v = (tLo + tb.binWidth - a) / b;
        if (u > v) std::swap(u, v);
        u = std::max(u, s0);
        v = std::min(v, s1);
        if (!(v > u)) continue;
        Color f;
        if (grey) {
            f = Color(expMassFraction(kappa.x, s0, s1, u, v));
        } else {
            f = Color(expMassFraction(kappa.x, s0, s1, u, v), expMassFraction(kappa.y, s0, s1, u, v),
                      expMassFraction(kappa.z, s0, s1, u, v));
        }
        sink(k, energy * f);
        inside += f;
    }
    outside += energy * glm::max(Color(1.0) - inside, Color(0.0));
}

}  // namespace tpb
