// The names of the density estimators (estimators/registry.cpp makes them), in one list the settings
// check (integrators/render_settings.cpp) reads without linking the estimators. A new estimator adds its
// name here and its line in registry.cpp; tests/estimators/test_registry.cpp checks the two agree.
#pragma once
#include <string>
#include <vector>

namespace tpb {

// Volume estimators (along camera segments in media), the default first.
inline const std::vector<std::string>& volumeEstimatorNames() {
    static const std::vector<std::string> names = {"beam2d", "beam1d", "point2d", "point3d"};
    return names;
}
// Surface estimators (at the diffuse end of a camera path), the default first.
inline const std::vector<std::string>& surfaceEstimatorNames() {
    static const std::vector<std::string> names = {"ppm"};
    return names;
}

}  // namespace tpb
