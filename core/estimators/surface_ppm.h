// Transient progressive photon mapping on surfaces ("ppm"): the reflected radiance at a diffuse
// camera-path vertex from the surface photons within the kernel radius rs (Hachisuka et al. 2008,
// Knaus & Zwicker 2011; transient: Jarabo et al. 2014, and Marco et al. 2017 Sec. 4 for surfaces),
//   L(x, t) = f_r sum_p Phi_p / (pi rs^2) delta(t - t_cam - t_p),     f_r = albedo / pi,
// each photon arriving at its own time: t_p (its OPL at landing) on the unwarped axis, plus the
// camera path's OPL t_cam on the real axis. Kernel dimension 2 (a disc on the surface).
// Only photons that landed on the same side of the same surface, in sight of x, contribute: not
// the other side of a thin wall, not the inside of a closed box seen from outside, not a surface
// across a gap narrower than the radius (Scene::surfacePointsSeeEachOther).
#pragma once
#include "accel/photon_grid.h"
#include "estimators/estimator.h"

#include <memory>

namespace tpb {

class SurfacePpmEstimator final : public SurfaceEstimator {
public:
    static constexpr int kDim = 2;
    std::string name() const override { return "ppm"; }
    int dim() const override { return kDim; }
    void prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) override;
    bool empty() const override { return !grid_; }
    int64_t gather(const SurfaceQuery& q, const PathState& path, PixelSink& sink) const override;

private:
    const Scene* scene_ = nullptr;
    double radius_ = 0.02;
    std::unique_ptr<PhotonGrid> grid_;
};

}  // namespace tpb
