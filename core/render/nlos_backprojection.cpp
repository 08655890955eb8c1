#include "render/nlos_backprojection.h"

#include "base/error.h"
#include "base/parallel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tpb {

namespace {

// The laser points of the capture's pairs (confocal: the sensor points).
const std::vector<Vec3>& laserPoints(const NlosCapture& cap) { return cap.confocal ? cap.sensorGrid : cap.laserGrid; }

Vec3 unitOr(const Vec3& v, const Vec3& fallback) {
    const double len = glm::length(v);
    return len > 1e-12 ? v / len : fallback;
}

// The wall's frame, as tools/nlos_backproject's wall_frame: u along the sensor grid's first index,
// v along its second made orthogonal, n = u x v turned towards the normals' side. A grid of one
// row or column: n the mean normal, u across it.
void wallFrame(const NlosCapture& cap, BackprojectionGrid& g) {
    const std::vector<Vec3>& s = cap.sensorGrid;
    g.origin = Vec3(0.0);
    for (const Vec3& p : s) g.origin += p;
    g.origin /= static_cast<double>(s.size());
    Vec3 meanN(0.0);
    for (const Vec3& n : cap.sensorNormals) meanN += n;
    meanN = unitOr(meanN, Vec3(0.0, 0.0, 1.0));
    const int sy = cap.sensorY;
    if (cap.sensorX >= 2 && sy >= 2) {
        const Vec3 u = unitOr(s[static_cast<size_t>(cap.sensorX - 1) * sy] - s[0], Vec3(0.0));
        const Vec3 vRaw = s[static_cast<size_t>(sy - 1)] - s[0];
        const Vec3 v = unitOr(vRaw - glm::dot(vRaw, u) * u, Vec3(0.0));
        Vec3 n = glm::cross(u, v);
        if (glm::length(n) > 0.5) {
            if (glm::dot(meanN, n) < 0.0) n = -n;
            g.u = u;
            g.normal = n;
            g.v = glm::cross(n, u);
            return;
        }
    }
    g.normal = meanN;
    const Vec3 an = glm::abs(meanN);
    const Vec3 helper = an.x <= an.y && an.x <= an.z ? Vec3(1.0, 0.0, 0.0)
                        : an.y <= an.z               ? Vec3(0.0, 1.0, 0.0)
                                                     : Vec3(0.0, 0.0, 1.0);
    g.u = unitOr(glm::cross(meanN, helper), Vec3(1.0, 0.0, 0.0));
    g.v = glm::cross(meanN, g.u);
}

// numpy.linspace(lo, hi, n).
std::vector<double> linspace(double lo, double hi, int n) {
    std::vector<double> out(static_cast<size_t>(n));
    const double step = n > 1 ? (hi - lo) / (n - 1) : 0.0;
    for (int i = 0; i < n; ++i) out[static_cast<size_t>(i)] = lo + i * step;
    if (n > 1) out.back() = hi;
    return out;
}

}  // namespace

const char* backprojectionFilterName(BackprojectionFilter f) {
    return f == BackprojectionFilter::Laplacian ? "laplacian" : "none";
}

BackprojectionFilter parseBackprojectionFilter(const std::string& name, const std::string& flag) {
    if (name == "none") return BackprojectionFilter::None;
    if (name == "laplacian") return BackprojectionFilter::Laplacian;
    throw UserError(flag + " '" + name + "': expected none or laplacian");
}

double defaultDepthMaxM(const NlosCapture& cap) {
    const double tEnd = cap.tStart + cap.bins * cap.deltaT;
    double legs = 0.0;
    if (cap.tAccountsFirstAndLastBounces) {
        double first = std::numeric_limits<double>::infinity(), last = first;
        for (const Vec3& l : laserPoints(cap)) first = std::min(first, glm::length(l - cap.laserOrigin));
        for (const Vec3& s : cap.sensorGrid) last = std::min(last, glm::length(s - cap.sensorOrigin));
        legs = first + last;
    }
    return std::max((tEnd - legs) / 2.0, 0.0);
}

int64_t backprojectionPairs(const NlosCapture& cap) {
    const int64_t ns = static_cast<int64_t>(cap.sensorGrid.size());
    return cap.confocal ? ns : static_cast<int64_t>(cap.laserGrid.size()) * ns;
}

BackprojectionGrid backprojectionGrid(const NlosCapture& cap, const BackprojectionSettings& s) {
    const std::string& f = s.flag;
    TPB_CHECK(!cap.sensorGrid.empty() && cap.bins > 0);
    if (s.depths < 1 || s.depths > 4096)
        throw UserError(f + ": " + std::to_string(s.depths) + " depths; give 1 to 4096 (64 is the default)");
    const int nx = s.lateralX > 0 ? s.lateralX : cap.sensorX;
    const int ny = s.lateralY > 0 ? s.lateralY : cap.sensorY;
    if (s.lateralX < 0 || s.lateralY < 0 || nx > 4096 || ny > 4096)
        throw UserError(f + ": lateral voxels " + std::to_string(nx) + " x " + std::to_string(ny) +
                        "; give 1 to 4096 each way (0: one per sensor point)");
    const int64_t voxels = static_cast<int64_t>(nx) * ny * s.depths;
    if (voxels > kMaxBackprojectionVoxels)
        throw UserError(f + ": " + std::to_string(voxels) + " voxels is more than " +
                        std::to_string(kMaxBackprojectionVoxels) + "; give fewer depths or lateral voxels");
    const double dMax = s.depthMaxM > 0.0 ? s.depthMaxM : defaultDepthMaxM(cap);
    const double dMin = s.depthMinM > 0.0 ? s.depthMinM : dMax / s.depths;
    if (!std::isfinite(s.depthMinM) || !std::isfinite(s.depthMaxM) || s.depthMinM < 0.0 || s.depthMaxM < 0.0)
        throw UserError(f + ": the depth range must be finite and > 0 (m from the wall)");
    if (!(dMax > 0.0))
        throw UserError(f +
                        ": the film ends before any hidden depth (default depth range <= 0); give a depth "
                        "range in m, or a film that ends later");
    if (dMax < dMin || (dMax == dMin && s.depths > 1))
        throw UserError(f + ": the farthest depth (" + std::to_string(dMax) + " m) must be beyond the nearest (" +
                        std::to_string(dMin) + " m)");
    BackprojectionGrid g;
    wallFrame(cap, g);
    double aLo = std::numeric_limits<double>::infinity(), aHi = -aLo, bLo = aLo, bHi = -aLo;
    for (const Vec3& p : cap.sensorGrid) {
        const double pa = glm::dot(p - g.origin, g.u), pb = glm::dot(p - g.origin, g.v);
        aLo = std::min(aLo, pa);
        aHi = std::max(aHi, pa);
        bLo = std::min(bLo, pb);
        bHi = std::max(bHi, pb);
    }
    g.a = linspace(aLo, aHi, nx);
    g.b = linspace(bLo, bHi, ny);
    g.depthsM = linspace(dMin, dMax, s.depths);
    return g;
}

BackprojectionVolume backproject(const NlosCapture& cap, const BackprojectionSettings& s, int threads,
                                 const std::atomic<bool>* cancel) {
    BackprojectionVolume vol;
    vol.grid = backprojectionGrid(cap, s);
    vol.filter = s.filter;
    const BackprojectionGrid& g = vol.grid;
    const std::vector<Vec3>& lasers = laserPoints(cap);
    const std::vector<Vec3>& sensors = cap.sensorGrid;
    const size_t ns = sensors.size(), nl = cap.confocal ? 1 : lasers.size();
    TPB_CHECK(cap.H.size() == static_cast<size_t>(cap.bins) * nl * ns);

    // --- One row of bins per pair, time last, with the fixed legs of each laser and sensor point ---
    const int64_t pairs = backprojectionPairs(cap);
    const size_t nt = static_cast<size_t>(cap.bins), perBin = nl * ns;
    std::vector<float> rows(static_cast<size_t>(pairs) * nt);
    for (size_t k = 0; k < nt; ++k)
        for (size_t p = 0; p < perBin; ++p) rows[p * nt + k] = cap.H[k * perBin + p];
    std::vector<double> dFirst(lasers.size(), 0.0), dLast(ns, 0.0);
    if (cap.tAccountsFirstAndLastBounces) {
        for (size_t l = 0; l < lasers.size(); ++l) dFirst[l] = glm::length(lasers[l] - cap.laserOrigin);
        for (size_t j = 0; j < ns; ++j) dLast[j] = glm::length(sensors[j] - cap.sensorOrigin);
    }

    // --- Sum over pairs, one voxel column (i, j) per work item ---
    const int nx = g.nx(), ny = g.ny(), nz = g.nz();
    std::vector<double> sums(static_cast<size_t>(g.voxels()), 0.0);
    const double invDt = 1.0 / cap.deltaT;
    const int64_t ntI = static_cast<int64_t>(nt);
    auto read = [&](const float* row, double t) {
        // Fractional bin index, bin centres at integers; bins outside [0, nt) read as zero.
        const double pos = (t - cap.tStart) * invDt - 0.5;
        if (!(pos > -1.0 && pos < static_cast<double>(nt))) return 0.0;
        const double f0 = std::floor(pos);
        const int64_t i0 = static_cast<int64_t>(f0);
        const double w = pos - f0;
        const double v0 = i0 >= 0 ? row[i0] : 0.0;
        const double v1 = i0 + 1 < ntI ? row[i0 + 1] : 0.0;
        return v0 * (1.0 - w) + v1 * w;
    };
    std::atomic<bool> stopped{false};
    parallelFor(
        static_cast<int64_t>(nx) * ny, resolveThreads(threads),
        [&](int64_t col, int) {
            if (cancel && cancel->load(std::memory_order_relaxed)) {
                stopped = true;
                return;
            }
            const int i = static_cast<int>(col / ny), j = static_cast<int>(col % ny);
            double* out = &sums[static_cast<size_t>(col) * nz];
            for (int k = 0; k < nz; ++k) {
                const Vec3 x = g.voxel(i, j, k);
                double acc = 0.0;
                if (cap.confocal) {
                    for (size_t p = 0; p < ns; ++p) {
                        const double d = glm::length(x - sensors[p]);
                        acc += read(&rows[p * nt], dFirst[p] + 2.0 * d + dLast[p]);
                    }
                } else {
                    for (size_t l = 0; l < nl; ++l) {
                        const double tl = dFirst[l] + glm::length(lasers[l] - x);
                        const float* base = &rows[l * ns * nt];
                        for (size_t p = 0; p < ns; ++p)
                            acc += read(base + p * nt, tl + glm::length(x - sensors[p]) + dLast[p]);
                    }
                }
                out[k] = acc;
            }
        },
        cancel);
    vol.complete = !stopped && !(cancel && cancel->load());

    // --- Filter along depth, then the peak ---
    vol.values.resize(sums.size());
    for (size_t c = 0; c < sums.size(); c += static_cast<size_t>(nz)) {
        const double* v = &sums[c];
        for (int k = 0; k < nz; ++k) {
            double out = v[k];
            if (s.filter == BackprojectionFilter::Laplacian)
                out = 2.0 * v[k] - v[std::max(k - 1, 0)] - v[std::min(k + 1, nz - 1)];
            vol.values[c + static_cast<size_t>(k)] = static_cast<float>(out);
        }
    }
    const auto peak = std::max_element(vol.values.begin(), vol.values.end());
    const int64_t idx = peak - vol.values.begin();
    vol.peakValue = *peak;
    vol.peakK = static_cast<int>(idx % nz);
    vol.peakJ = static_cast<int>((idx / nz) % ny);
    vol.peakI = static_cast<int>(idx / (static_cast<int64_t>(nz) * ny));
    return vol;
}

BackprojectionImages backprojectionImages(const BackprojectionVolume& vol) {
    const int nx = vol.grid.nx(), ny = vol.grid.ny(), nz = vol.grid.nz();
    BackprojectionImages im;
    const float lowest = -std::numeric_limits<float>::infinity();
    im.front.assign(static_cast<size_t>(nx) * ny, lowest);
    im.frontDepthM.assign(im.front.size(), 0.0f);
    im.top.assign(static_cast<size_t>(nz) * nx, lowest);
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j)
            for (int k = 0; k < nz; ++k) {
                const float v = vol.at(i, j, k);
                const size_t f = static_cast<size_t>(j) * nx + i, t = static_cast<size_t>(k) * nx + i;
                if (v > im.front[f]) {
                    im.front[f] = v;
                    im.frontDepthM[f] = static_cast<float>(vol.grid.depthsM[static_cast<size_t>(k)]);
                }
                im.top[t] = std::max(im.top[t], v);
            }
    return im;
}

}  // namespace tpb
