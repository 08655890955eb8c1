// rayBeamOverlap (beam2d.cpp) over a structure of arrays of pieces, vectorised (overlap_batch.h).
// Built with -O3 -fno-math-errno -fno-trapping-math -ffp-contract=off (CMakeLists.txt): the first
// two let the compiler vectorise the loop (sqrt without errno, divisions of masked lanes done
// anyway), the last keeps a * b + c two roundings as in the scalar code. Each lane repeats the
// scalar test's operations in its order; its branches are selects. Keep the two in step: a change
// to rayBeamOverlap must be made here too (test_overlap_batch.cpp compares them bit for bit).
#include "estimators/overlap_batch.h"

#include <cmath>
#include <limits>

namespace tpb {

namespace {

// The camera segment as the kernel reads it: origin, unit direction, length, radius squared.
struct Ray1 {
    double rx, ry, rz, wx, wy, wz, sMax, r2;
};

}  // namespace

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__) && \
    !defined(__SANITIZE_THREAD__)
#define TPB_OVERLAP_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define TPB_OVERLAP_CLONES
#endif

TPB_OVERLAP_CLONES
static void overlapKernel(const Ray1 ray, size_t n, const double* __restrict ox, const double* __restrict oy,
                          const double* __restrict oz, const double* __restrict dx, const double* __restrict dy,
                          const double* __restrict dz, const double* __restrict pLo, const double* __restrict pHi,
                          double* __restrict sMinus, double* __restrict sPlus, double* __restrict sb0Out,
                          double* __restrict cOut) {
    const double rx = ray.rx, ry = ray.ry, rz = ray.rz, rwx = ray.wx, rwy = ray.wy, rwz = ray.wz;
    const double sMax = ray.sMax, r2 = ray.r2;
    for (size_t i = 0; i < n; ++i) {
        // d = x_r - x_b; c = dot(w_r, w_b); sb0 = dot(d, w_b) (glm's dot: (x + y) + z).
        const double ddx = rx - ox[i], ddy = ry - oy[i], ddz = rz - oz[i];
        const double bx = dx[i], by = dy[i], bz = dz[i];
        const double c = rwx * bx + rwy * by + rwz * bz;
        const double sb0 = ddx * bx + ddy * by + ddz * bz;
        // w = d - sb0 w_b (perpendicular offset), dp = w_r - c w_b (perpendicular direction).
        const double wx = ddx - sb0 * bx, wy = ddy - sb0 * by, wz = ddz - sb0 * bz;
        const double px = rwx - c * bx, py = rwy - c * by, pz = rwz - c * bz;
        const double a = px * px + py * py + pz * pz;
        const double w2 = wx * wx + wy * wy + wz * wz;
        const double b = wx * px + wy * py + wz * pz;
        const double cc = w2 - r2;
        const double disc = b * b - a * cc;
        const double sq = std::sqrt(disc > 0.0 ? disc : 0.0);
        const double q = -(b + std::copysign(sq, b));
        const double s1r = q / a;
        const double s2r = (q != 0.0) ? cc / q : s1r;
        const double s1 = s1r > s2r ? s2r : s1r, s2 = s1r > s2r ? s1r : s2r;
        const bool parallel = a < 1e-14;
        // A rejected lane gets hi = -inf, so the final test hi > lo rejects it (as the scalar's
        // early returns do); an accepted one has the scalar's lo and hi.
        const double kOut = -std::numeric_limits<double>::infinity();
        // 1. The infinite cylinder: lo = max(0, s1), hi = min(sMax, s2) (std::max / std::min's order);
        //    rejected when disc <= 0 (or, parallel, when the axis is farther than r).
        const double lo1 = parallel ? 0.0 : (0.0 < s1 ? s1 : 0.0);
        const double hi0 = parallel ? sMax : (s2 < sMax ? s2 : sMax);
        const double hi1 = (parallel ? w2 > r2 : disc <= 0.0) ? kOut : hi0;
        // 2. The projection on the beam inside [lo_b, hi_b] (perpendicular: sb0 must lie in it).
        const double t1r = (pLo[i] - sb0) / c, t2r = (pHi[i] - sb0) / c;
        const double t1 = t1r > t2r ? t2r : t1r, t2 = t1r > t2r ? t1r : t2r;
        const bool perpendicular = std::abs(c) < 1e-15;
        const double hiP = (sb0 < pLo[i] || sb0 > pHi[i]) ? kOut : hi1;
        sMinus[i] = perpendicular ? lo1 : (lo1 < t1 ? t1 : lo1);
        sPlus[i] = perpendicular ? hiP : (t2 < hi1 ? t2 : hi1);
        sb0Out[i] = sb0;
        cOut[i] = c;
    }
}

void rayBeamOverlaps(const Vec3& xr, const Vec3& wr, double sMax, const PieceAxes& p, double radius,
                     OverlapBatch& out) {
    const size_t n = p.size();
    out.sMinus.resize(n);
    out.sPlus.resize(n);
    out.sb0.resize(n);
    out.cosRB.resize(n);
    const Ray1 ray{xr.x, xr.y, xr.z, wr.x, wr.y, wr.z, sMax, radius * radius};
    overlapKernel(ray, n, p.ox.data(), p.oy.data(), p.oz.data(), p.dx.data(), p.dy.data(), p.dz.data(), p.lo.data(),
                  p.hi.data(), out.sMinus.data(), out.sPlus.data(), out.sb0.data(), out.cosRB.data());
    // The overlapping indices, without a branch per piece (about half of them overlap: unpredictable).
    out.hits.resize(n);
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {
        out.hits[k] = static_cast<uint32_t>(i);
        k += out.sPlus[i] > out.sMinus[i] ? 1 : 0;
    }
    out.hits.resize(k);
}

}  // namespace tpb
