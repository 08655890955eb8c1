// Transient progressive photon mapping on surfaces ("ppm"): the reflected radiance at a diffuse
// camera-path vertex from the surface photons within the kernel radius rs (Hachisuka et al. 2008,
// Knaus & Zwicker 2011; transient: Jarabo et al. 2014, and Marco et al. 2017 Sec. 4 for surfaces),
//   L(x, t) = f_r sum_p Phi_p / A(x) delta(t - t_cam - t_p),     f_r = albedo / pi,
// each photon arriving at its own time: t_p (its OPL at landing) on the unwarped axis, plus the
// camera path's OPL t_cam on the real axis. Kernel dimension 2 (a disc on the surface). A(x) is the
// area of the disc that lies on the surface: pi rs^2 inside it, less past its edges (kernelArea;
// docs/developer/adding-an-estimator.md, "The surface kernel at edges").
// Only photons that landed on the same side of the same surface, in sight of x, contribute: not
// the other side of a thin wall, not the inside of a closed box seen from outside, not a surface
// across a gap narrower than the radius (Scene::surfacePointsSeeEachOther).
#pragma once
#include "accel/photon_grid.h"
#include "estimators/estimator.h"

#include <memory>
#include <vector>

namespace tpb {

class SurfacePpmEstimator final : public SurfaceEstimator {
public:
    static constexpr int kDim = 2;
    std::string name() const override { return "ppm"; }
    int dim() const override { return kDim; }
    void prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) override;
    bool empty() const override { return !grid_; }
    int64_t gather(const SurfaceQuery& q, const PathState& path, PixelSink& sink) const override;

    // The area of the kernel's support on the surface around x (facing normal ng; on triangle
    // `prim` of shape `shape`, -1 if unknown): pi r^2 where the disc lies wholly on the surface,
    // less where it reaches past an edge (docs/developer/adding-an-estimator.md, "The surface
    // kernel at edges").
    double kernelArea(const Vec3& x, const Vec3& ng, int shape = -1, int prim = -1) const;

private:
    const Scene* scene_ = nullptr;
    std::vector<char> photonSurface_;  // per shape: photons land on it (diffuse, not a light)
    double radius_ = 0.02;
    std::unique_ptr<PhotonGrid> grid_;
};

}  // namespace tpb
