#include "integrators/integrator.h"

#include "integrators/path_tracer_integrator.h"
#include "integrators/photon_beams.h"
#include "integrators/preview_integrator.h"

namespace tpb {

// ---- the registry -----------------------------------------------------------------------------

std::unique_ptr<Integrator> makeIntegrator(const Scene& scene, const RenderSettings& settings) {
    switch (settings.method) {
        case Method::Beams: return std::make_unique<PhotonBeamsIntegrator>(scene, settings);
        case Method::PathTracer: return std::make_unique<PathTracerIntegrator>(scene, settings);
        case Method::Preview: return std::make_unique<PreviewIntegrator>(scene, settings);
    }
    return nullptr;
}

}  // namespace tpb
