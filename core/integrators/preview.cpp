#include "integrators/preview.h"

#include "scene/bsdf.h"
#include "base/parallel.h"

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
                const ShapeInfo& sh = scene.shapes[hit->shape];
                const double cosv = std::abs(glm::dot(hit->ns, ray.d));
                if (sh.areaLight >= 0) { c = beta; break; }
                if (sh.material < 0) { c = beta * 0.5 * cosv; break; }
                const Material& m = scene.materials[sh.material];
                if (m.type == MaterialType::Diffuse) { c = beta * m.albedo * cosv; break; }
                const Vec3 n = glm::dot(ray.d, hit->ng) < 0.0 ? hit->ns : -hit->ns;
                if (m.type == MaterialType::Mirror) {
                    beta *= m.specular;
                    ray = {hit->p + scene.rayEps * n, glm::normalize(reflect(ray.d, n))};
                } else {  // glass and null boundaries: look straight through, slightly tinted
                    beta *= m.type == MaterialType::Dielectric ? 0.9 * m.specular : Color(1.0);
                    ray = {hit->p - scene.rayEps * n, ray.d};
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
