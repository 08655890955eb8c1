// Back-projection of an NLOS capture onto a voxel grid in front of the relay wall: the C++ twin of
// tools/nlos_backproject (same grid, same sums; tests/tools/test_backprojection_twin.py compares
// them). For every voxel x it sums, over the capture's (laser point l, sensor point s) pairs,
//
//     H(t(x), l, s),   t(x) = |l - x| + |x - s|   (+ |laser - l| + |s - sensor| when the capture's
//                                                    time counts the first and last legs),
//
// H read between bin centres by linear interpolation (zero outside the bins). One channel: the
// capture's H, the luminance of each bin (render/nlos_capture.h). Cost: voxels x pairs reads of H
// (confocal: pairs = sensor points; single: sensor points; exhaustive: laser x sensor points).
#pragma once
#include "base/math.h"
#include "io/nlos_hdf5.h"

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace tpb {

enum class BackprojectionFilter {
    None,
    Laplacian,  // minus the second difference along depth, edges repeated (tools/nlos_backproject)
};
const char* backprojectionFilterName(BackprojectionFilter f);
// "none" | "laplacian"; throws UserError naming `flag` otherwise.
BackprojectionFilter parseBackprojectionFilter(const std::string& name, const std::string& flag);

// What the caller chooses; 0 means the default. `flag` names the option in error messages.
struct BackprojectionSettings {
    double depthMinM = 0.0;          // nearest depth from the wall, m (0: one depth step, depthMaxM / depths)
    double depthMaxM = 0.0;          // farthest, m (0: the deepest the last bin sees, defaultDepthMaxM)
    int depths = 64;                 // voxels along the wall's normal
    int lateralX = 0, lateralY = 0;  // voxels across the wall (0: the sensor grid's shape)
    BackprojectionFilter filter = BackprojectionFilter::None;
    std::string flag = "--backproject";  // the option the settings came from, for errors
};

// Voxel (i, j, k) = origin + a[i] u + b[j] v + depths[k] normal; u along the sensor grid's first
// index (the wall's edge_u), v along its second, normal towards the hidden side (the sensor's).
struct BackprojectionGrid {
    Vec3 origin{0.0}, u{1.0, 0.0, 0.0}, v{0.0, 1.0, 0.0}, normal{0.0, 0.0, 1.0};
    std::vector<double> a, b, depthsM;
    int nx() const { return static_cast<int>(a.size()); }
    int ny() const { return static_cast<int>(b.size()); }
    int nz() const { return static_cast<int>(depthsM.size()); }
    int64_t voxels() const { return static_cast<int64_t>(nx()) * ny() * nz(); }
    Vec3 voxel(int i, int j, int k) const { return origin + a[i] * u + b[j] * v + depthsM[k] * normal; }
};

// Voxels above this are refused (4 bytes each, plus a double per voxel while summing).
inline constexpr int64_t kMaxBackprojectionVoxels = int64_t{64} << 20;

// The deepest depth any bin can see: a voxel at depth d has t(x) >= 2 d + the fixed legs.
double defaultDepthMaxM(const NlosCapture& cap);
// The grid for `cap`; throws UserError naming s.flag for a depth range <= 0, inverted, or absurd
// voxel counts, with the fix.
BackprojectionGrid backprojectionGrid(const NlosCapture& cap, const BackprojectionSettings& s);
// (laser, sensor) pairs the sums run over.
int64_t backprojectionPairs(const NlosCapture& cap);

struct BackprojectionVolume {
    BackprojectionGrid grid;
    BackprojectionFilter filter = BackprojectionFilter::None;
    std::vector<float> values;            // (nx, ny, nz), C order: index (i ny + j) nz + k
    int peakI = 0, peakJ = 0, peakK = 0;  // the first maximum in C order (numpy's argmax)
    float peakValue = 0.0f;
    bool complete = true;  // false: cancelled, values partial
    float at(int i, int j, int k) const { return values[(static_cast<size_t>(i) * grid.ny() + j) * grid.nz() + k]; }
};

// The back-projected (and filtered) volume, on `threads` threads (0: all cores). `cancel` set
// stops it between voxel columns (complete = false).
BackprojectionVolume backproject(const NlosCapture& cap, const BackprojectionSettings& s, int threads = 0,
                                 const std::atomic<bool>* cancel = nullptr);

// Images of a volume. front, frontDepthM: (ny rows, nx columns), row j column i: the maximum over
// depth of voxel column (i, j) and the depth (m) it is at; top: (nz rows, nx columns), row k
// column i: the maximum over j.
struct BackprojectionImages {
    std::vector<float> front, frontDepthM, top;
};
BackprojectionImages backprojectionImages(const BackprojectionVolume& vol);

// The names `tpb render --backproject` writes it under: the volume (nx, ny, nz float32) and its grid.
inline constexpr const char* kBackprojectionNpyName = "backprojection.npy";
inline constexpr const char* kBackprojectionJsonName = "backprojection.json";

}  // namespace tpb
