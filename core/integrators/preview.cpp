// Geometry preview (see preview.h): the material switch of transport/interaction.h, no Fresnel, no region stack.
#include "integrators/preview.h"

#include "base/parallel.h"
#include "transport/interaction.h"

namespace tpb {

std::vector<float> renderPreview(const Scene& scene, int threads) {
    const Camera& cam = scene.camera;
    std::vector<float> img(static_cast<size_t>(cam.width) * cam.height * 3, 0.0f);
    parallelFor(cam.height, resolveThreads(threads), [&](int64_t y, int) {
        for (int x = 0; x < cam.width; ++x) {
            Ray ray = cam.generate(x + 0.5, y + 0.5);
            Color beta(1.0), c(0.0);
            for (int depth = 0; depth < 8; ++depth) {
                const auto hit = scene.geometry.intersect(ray);
                if (!hit) break;
                const SurfaceInteraction si = interact(scene, ray, *hit);
                const double cosv = std::abs(glm::dot(hit->ns, ray.d));
                if (si.kind == SurfaceKind::Emitter) {
                    c = beta;
                    break;
                }
                if (si.kind == SurfaceKind::Absorber) {
                    c = beta * 0.5 * cosv;
                    break;
                }
                const Material& m = *si.material;
                if (si.kind == SurfaceKind::Diffuse) {
                    c = beta * m.albedo * cosv;
                    break;
                }
                // The shading normal as given, turned to the incoming side (not replaced by ng).
                const Vec3 n = si.front ? hit->ns : -hit->ns;
                if (si.kind == SurfaceKind::Mirror) {
                    beta *= m.specular;
                    ray = offsetReflection(scene, ray, *hit, n);
                } else {  // glass and null boundaries: look straight through, slightly tinted
                    beta *= si.kind == SurfaceKind::Dielectric ? 0.9 * m.specular : Color(1.0);
                    ray = offsetStraightThrough(scene, ray, *hit, n);
                }
            }
            float* p = &img[(static_cast<size_t>(y) * cam.width + x) * 3];
            p[0] = static_cast<float>(c.x);
            p[1] = static_cast<float>(c.y);
            p[2] = static_cast<float>(c.z);
        }
    });
    return img;
}

}  // namespace tpb
