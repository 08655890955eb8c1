// Progressive kernel-radius schedule (Knaus & Zwicker 2011; Jarosz et al. 2011 for beams).
// The kernel's measure (r^dim: area for the 2D beam kernel and the surface kernel, volume for a 3D
// point kernel, length for a 1D beam kernel) shrinks as
//   r_{i+1}^dim = r_i^dim (i + alpha) / (i + 1)      =>  r_i^dim = r_1^dim Gamma(i+alpha) / (Gamma(1+alpha) Gamma(i+1)),
// evaluated with lgamma so it neither underflows nor overflows after millions of passes.
#pragma once
#include <cmath>
#include <cstdint>

namespace tpb {

// Radius of pass `pass` (1-based) of a `dim`-dimensional kernel starting at r1.
inline double progressiveRadius(double r1, double alpha, uint64_t pass, int dim) {
    if (pass <= 1) return r1;
    const double i = static_cast<double>(pass);
    const double logScale = std::lgamma(i + alpha) - std::lgamma(1.0 + alpha) - std::lgamma(i + 1.0);
    return r1 * std::exp(logScale / dim);
}

// With a progressive time kernel (film/time_kernel.h) the estimate's kernel has dim + 1
// dimensions, space and time: its measure r^dim tau shrinks by (i + alpha) / (i + 1) per pass with r
// and tau at the same rate, so both follow progressiveRadius(., alpha, pass, dim + 1), ~ i^{-(1 -
// alpha) / (dim + 1)} (docs/theory/derivations.md "Progressive time kernel").
inline int scheduleDimension(int spatialDim, bool timeKernel) { return spatialDim + (timeKernel ? 1 : 0); }
inline double progressiveTimeHalfWidth(double tau1, double alpha, uint64_t pass, int scheduleDim) {
    return progressiveRadius(tau1, alpha, pass, scheduleDim);
}

}  // namespace tpb
