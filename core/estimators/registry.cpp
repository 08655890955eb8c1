// The estimators by name (estimators/estimator.h). Adding one: include its header, add a line here
// and its name in estimators/estimator_names.h.
#include "estimators/beam1d.h"
#include "estimators/beam2d.h"
#include "estimators/estimator.h"
#include "estimators/point2d.h"
#include "estimators/point3d.h"
#include "estimators/surface_ppm.h"

namespace tpb {

std::unique_ptr<VolumeEstimator> makeVolumeEstimator(const std::string& name) {
    if (name == "beam2d") return std::make_unique<Beam2DEstimator>();
    if (name == "beam1d") return std::make_unique<Beam1DEstimator>();
    if (name == "point2d") return std::make_unique<Point2DEstimator>();
    if (name == "point3d") return std::make_unique<Point3DEstimator>();
    return nullptr;
}

std::unique_ptr<SurfaceEstimator> makeSurfaceEstimator(const std::string& name) {
    if (name == "ppm") return std::make_unique<SurfacePpmEstimator>();
    return nullptr;
}

}  // namespace tpb
