// Composite 5-point Gauss-Legendre quadrature on n equal panels: the tests' oracle for smooth 1D
// integrands (exact for polynomials of degree 9 per panel).
#pragma once
#include <functional>

namespace tpb::test {

inline double gaussLegendre5(const std::function<double(double)>& f, double a, double b, int n) {
    static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
    static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                0.2369268850561891};
    const double h = (b - a) / n;
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
        const double m = a + (i + 0.5) * h;
        for (int j = 0; j < 5; ++j) s += w[j] * f(m + 0.5 * h * x[j]);
    }
    return s * 0.5 * h;
}

}  // namespace tpb::test
