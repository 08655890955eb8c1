// The exact frequency-domain film (issue 36): per pixel, per time axis and per chosen frequency f
// (cycles per m of OPL), the complex sum over estimates of
//     P(f) = Int E(t) exp(-i 2 pi f (t - t_ref)) dt,
// E(t) the estimate's own time profile (time_splat.h: an instant, or an exponential along s mapped
// linearly to time, with the causal floor's mirrored part), in closed form: no bins, so no
// aliasing. t_ref is the film's start (mitransient's phasor_hdr_film convention: phase of
// exp(-i 2 pi f (opl - start_opl))). The progressive time kernel is not applied: it only smooths
// histograms (its transform, sinc(2 pi f tau), tends to 1 as tau shrinks).
// Derivation, stability and limits: docs/theory/phasor.md; tests/film/test_phasor.cpp checks them
// against quadrature.
#pragma once
#include "base/math.h"
#include "film/time_response.h"
#include "film/time_splat.h"

#include <cmath>
#include <complex>
#include <string>
#include <vector>

namespace tpb {

using Complex = std::complex<double>;

// The frequencies of the phasor film (empty = no phasor film).
struct PhasorSpec {
    std::vector<double> frequencies;  // cycles per m of OPL, each > 0
    double refOpl = 0.0;              // m: t_ref (the film's start)
    bool active() const { return !frequencies.empty(); }
    int count() const { return static_cast<int>(frequencies.size()); }
    bool operator==(const PhasorSpec&) const = default;
};

// phi(w) = (1 - e^{-w}) / w for complex w = x + i y, x >= 0 (phi(0) = 1). The numerator's real part
// is -expm1(-x) + e^{-x} 2 sin^2(y / 2), a sum of two terms >= 0, and its imaginary part
// e^{-x} sin y: no cancellation for any |w| (docs/theory/phasor.md "Stable form").
inline Complex phasorPhi(double x, double y) {
    if (x == 0.0 && y == 0.0) return Complex(1.0, 0.0);
    const double e = std::exp(-x);
    const double h = std::sin(0.5 * y);
    const Complex num(-std::expm1(-x) + 2.0 * e * h * h, e * std::sin(y));
    return num / Complex(x, y);
}

// exp(-i theta) with theta reduced to [-pi, pi] first (theta can be 2 pi f t with f t ~ 1e4).
inline Complex phasorTurn(double cycles) {
    const double r = cycles - std::nearbyint(cycles);
    const double th = 2.0 * kPi * r;
    return Complex(std::cos(th), -std::sin(th));
}

// The phasor at frequency f of one channel's unit-mass profile: density exp(-kappa x) on the
// segment, x measured from its decaying end (ExpProfile: from s0, or from s1 when `reflect`),
// arriving at t = a + b s. Eq. (P2) of docs/theory/phasor.md:
//   P = exp(-i 2 pi f (t_e - t_ref)) phi(kappa L + i 2 pi f b' L) / phi(kappa L),
// t_e the time at the decaying end, b' = +b (from s0) or -b (from s1), L = s1 - s0.
inline Complex profilePhasor(const ExpProfile& e, double a, double b, double f, double tRef) {
    const double len = std::max(0.0, e.s1 - e.s0);
    const double kappa = e.uniform ? 0.0 : e.kappa;
    const double tEnd = e.reflect ? a + b * e.s1 : a + b * e.s0;
    const double bSigned = e.reflect ? -b : b;
    const double y = 2.0 * kPi * f * bSigned * len;
    const Complex shape = phasorPhi(kappa * len, y) / phasorPhi(kappa * len, 0.0).real();
    return phasorTurn(f * (tEnd - tRef)) * shape;
}

// Adds the phasors of one estimate (energy per channel, profile, time a + b s; with a floor, the
// part earlier than it mirrored about it as splatTimeFloored does) at every frequency of `spec`
// to out[f * 6 + {0,1,2} = Re rgb, + {3,4,5} = Im rgb].
void addEstimatePhasor(const PhasorSpec& spec, const Color& energy, const SegmentProfile& p, double a, double b,
                       double floor, double* out);

// The transform at f of the pulse-and-sensor response h = p * s (time_response.h), with the phasor
// film's sign: H(f) = Int h(t) exp(-i 2 pi f t) dt. Closed forms (docs/theory/phasor.md):
// gaussian FWHM exp(-(2 pi f sigma)^2 / 2); square WIDTH phi(i 2 pi f WIDTH); exponential TAU
// 1 / (1 + i 2 pi f TAU); delta and ideal 1.
Complex responseTransform(const TimeResponse& r, double f);

// The frequencies as the CLI and the scene file write them (docs/user/phasor.md):
//   "F1,F2,..."                          cycles per m of OPL, each > 0;
//   "wl:WL1,WL2,..."                     wavelengths in m of OPL (f = 1 / WL);
//   "band:MEAN:SIGMA"                    mitransient's phasor film: the FFT frequencies k / (bins
//                                        binWidth) within MEAN's frequency +- 3 sigma_f,
//                                        sigma_f = 1 / (6 SIGMA) (MEAN and SIGMA wavelengths in m).
// Returns the sorted frequencies, or throws UserError with `what` (the flag or key) naming the
// fault and the fix: a frequency above the film's Nyquist-free limit is allowed (that is the
// point), but one above 1 / (1e-6 m) is refused (no transport is that fine), as are none, NaN and
// <= 0.
std::vector<double> parsePhasorFrequencies(const std::string& text, int bins, double binWidth, const std::string& what);

}  // namespace tpb
