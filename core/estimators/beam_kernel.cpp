#include "estimators/beam_kernel.h"

#include <algorithm>

namespace tpb {

bool rayBeamOverlap(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xb, const Vec3& wb,
                    double sbLo, double sbHi, double radius, RayBeamOverlap& out) {
    // Decompose the ray relative to the beam axis: parallel part (along w_b) and perpendicular part.
    const Vec3 d = xr - xb;
    const double c = glm::dot(wr, wb);
    const double sb0 = glm::dot(d, wb);
    const Vec3 w = d - sb0 * wb;   // perpendicular offset of x_r from the axis
    const Vec3 dp = wr - c * wb;   // perpendicular part of the ray direction, |dp|^2 = 1 - c^2
    const double a = glm::dot(dp, dp);
    const double r2 = radius * radius;
    const double w2 = glm::dot(w, w);

    double lo = 0.0, hi = sMax;
    // 1. Inside the infinite cylinder: a s^2 + 2 b s + (w2 - r2) <= 0.
    if (a < 1e-14) {
        // Ray parallel to the beam: inside everywhere or nowhere.
        if (w2 > r2) return false;
    } else {
        const double b = glm::dot(w, dp);
        const double disc = b * b - a * (w2 - r2);
        if (disc <= 0.0) return false;  // misses or grazes the kernel (zero-length overlap)
        const double sq = std::sqrt(disc);
        // Stable roots of a s^2 + 2 b s + cc: q = -(b + sign(b) sq); roots q/a and cc/q.
        const double q = -(b + std::copysign(sq, b));
        double s1 = q / a;
        double s2 = (q != 0.0) ? (w2 - r2) / q : s1;
        if (s1 > s2) std::swap(s1, s2);
        lo = std::max(lo, s1);
        hi = std::min(hi, s2);
    }
    // 2. Projection on the beam inside [sbLo, sbHi]: sbLo <= sb0 + c s <= sbHi.
    if (std::abs(c) < 1e-15) {
        if (sb0 < sbLo || sb0 > sbHi) return false;
    } else {
        double t1 = (sbLo - sb0) / c, t2 = (sbHi - sb0) / c;
        if (t1 > t2) std::swap(t1, t2);
        lo = std::max(lo, t1);
        hi = std::min(hi, t2);
    }
    if (!(hi > lo)) return false;
    out.sMinus = lo;
    out.sPlus = hi;
    out.sb0 = sb0;
    out.cosRB = c;
    return true;
}

bool rayBeamOverlap(const Vec3& xr, const Vec3& wr, double sMax, const Vec3& xb, const Vec3& wb,
                    double beamLength, double radius, RayBeamOverlap& out) {
    return rayBeamOverlap(xr, wr, sMax, xb, wb, 0.0, beamLength, radius, out);
}

double transmittanceIntegral(double sigma_t, double tau_b, const RayBeamOverlap& o) {
    const double kappa = sigma_t + tau_b * o.cosRB;
    const double len = o.sPlus - o.sMinus;
    // Optical depth E(s) = sigma_t s + tau_b s_b(s); start from the end where it is smallest.
    const double sRef = kappa >= 0.0 ? o.sMinus : o.sPlus;
    const double depth = sigma_t * sRef + tau_b * (o.sb0 + o.cosRB * sRef);
    return std::exp(-depth) * len * expRel(std::abs(kappa) * len);
}

}  // namespace tpb
