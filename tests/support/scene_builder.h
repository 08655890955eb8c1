// A fluent builder of SceneDesc for tests: the camera, the film's time bins, media, materials,
// lights and shapes in a few chained calls, without a JSON string or field-by-field filling:
//
//     SceneBuilder b;
//     b.camera(Vec3(0, 1, 3), Vec3(0, 1, 0), 40.0, 32, 32).film(0.0, 0.05, 100);
//     const int fog = b.medium(Color(0.3), Color(0.05), 0.3);
//     b.globalMedium(fog).quad(Vec3(-1, 0, -1), Vec3(0, 0, 2), Vec3(2, 0, 0), b.diffuse(Color(0.75)));
//     b.pointLight(Vec3(0, 1.7, 0), Color(20.0));
//     std::unique_ptr<const Scene> scene = Scene::build(b.desc(), analyzeStages);
//
// Media and materials return their index, to be given to shapes; shapes and lights return the
// builder (their index is shapeCount() / lightCount() - 1). Names are left empty (set them with
// edit() where a test needs them). Defaults are those of SceneDesc, except that kernel radii are
// absolute (render.radiusRelative = false), as tests usually want them.
#pragma once
#include "transport/stages.h"
#include "scene/scene_desc.h"

#include <utility>

namespace tpb::test {

class SceneBuilder {
public:
    SceneBuilder() { d_.render.radiusRelative = false; }

    SceneBuilder& camera(const Vec3& position, const Vec3& lookAt, double fovYDeg, int width, int height,
                         const Vec3& up = Vec3(0.0, 1.0, 0.0)) {
        d_.camera.position = position;
        d_.camera.lookAt = lookAt;
        d_.camera.up = up;
        d_.camera.fovYDeg = fovYDeg;
        d_.camera.width = width;
        d_.camera.height = height;
        return *this;
    }
    // A fixed time axis: `bins` bins of binWidthOpl (m of OPL) from startOpl.
    SceneBuilder& film(double startOpl, double binWidthOpl, int bins) {
        d_.film.autoRange = false;
        d_.film.startOpl = startOpl;
        d_.film.binWidthOpl = binWidthOpl;
        d_.film.bins = bins;
        return *this;
    }
    // The automatic time range with `bins` bins.
    SceneBuilder& autoFilm(int bins) {
        d_.film.autoRange = true;
        d_.film.bins = bins;
        return *this;
    }

    // ---- media and materials (return their index) ----
    int medium(const Color& sigma_s, const Color& sigma_a, double g = 0.0, double ior = 1.0) {
        MediumDesc m;
        m.sigma_s = sigma_s;
        m.sigma_a = sigma_a;
        m.g = g;
        m.ior = ior;
        d_.media.push_back(m);
        return static_cast<int>(d_.media.size()) - 1;
    }
    SceneBuilder& globalMedium(int medium) {
        d_.globalMedium = medium;
        return *this;
    }
    int material(MaterialType type, const Color& albedo = Color(0.8), const Color& specular = Color(1.0),
                 double ior = 1.5) {
        MaterialDesc m;
        m.type = type;
        m.albedo = albedo;
        m.specular = specular;
        m.ior = ior;
        d_.materials.push_back(m);
        return static_cast<int>(d_.materials.size()) - 1;
    }
    int diffuse(const Color& albedo) { return material(MaterialType::Diffuse, albedo); }
    int mirror(const Color& reflectance) { return material(MaterialType::Mirror, Color(0.8), reflectance); }
    int dielectric(double ior, const Color& tint = Color(1.0)) {
        return material(MaterialType::Dielectric, Color(0.8), tint, ior);
    }
    int nullMaterial() { return material(MaterialType::Null); }

    // ---- shapes (interiorMedium -1: none) ----
    SceneBuilder& sphere(const Vec3& center, double radius, int material, int interiorMedium = -1) {
        ShapeDesc s = shape(ShapeType::Sphere, material, interiorMedium);
        s.center = center;
        s.radius = radius;
        return add(std::move(s));
    }
    // corner + s edgeU + t edgeV, s, t in [0, 1]; normal along cross(edgeU, edgeV).
    SceneBuilder& quad(const Vec3& corner, const Vec3& edgeU, const Vec3& edgeV, int material) {
        ShapeDesc s = shape(ShapeType::Quad, material, -1);
        s.corner = corner;
        s.edgeU = edgeU;
        s.edgeV = edgeV;
        return add(std::move(s));
    }
    SceneBuilder& box(const Vec3& lo, const Vec3& hi, int material, int interiorMedium = -1, bool flipNormals = false) {
        ShapeDesc s = shape(ShapeType::Box, material, interiorMedium);
        s.boxMin = lo;
        s.boxMax = hi;
        s.flipNormals = flipNormals;
        return add(std::move(s));
    }

    // ---- lights (power in W, emitOpl in m of OPL) ----
    SceneBuilder& pointLight(const Vec3& position, const Color& power, double emitOpl = 0.0) {
        LightDesc l = light(LightType::Point, power, emitOpl);
        l.position = position;
        return add(std::move(l));
    }
    SceneBuilder& spotLight(const Vec3& position, const Vec3& direction, double cutoffDeg, double falloffDeg,
                            const Color& power, double emitOpl = 0.0) {
        LightDesc l = light(LightType::Spot, power, emitOpl);
        l.position = position;
        l.direction = direction;
        l.spotCutoffDeg = cutoffDeg;
        l.spotFalloffDeg = falloffDeg;
        return add(std::move(l));
    }
    // Emits along cross(edgeU, edgeV).
    SceneBuilder& areaLight(const Vec3& corner, const Vec3& edgeU, const Vec3& edgeV, const Color& power,
                            double emitOpl = 0.0) {
        LightDesc l = light(LightType::AreaQuad, power, emitOpl);
        l.corner = corner;
        l.edgeU = edgeU;
        l.edgeV = edgeV;
        return add(std::move(l));
    }
    SceneBuilder& laser(const Vec3& position, const Vec3& direction, const Color& power, double radius = 0.0,
                        double emitOpl = 0.0) {
        LightDesc l = light(LightType::Laser, power, emitOpl);
        l.position = position;
        l.direction = direction;
        l.laserRadius = radius;
        return add(std::move(l));
    }

    // Direct access for what the builder does not cover (render settings, transforms, ...).
    RenderDesc& render() { return d_.render; }
    SceneDesc& edit() { return d_; }
    int shapeCount() const { return static_cast<int>(d_.shapes.size()); }
    int lightCount() const { return static_cast<int>(d_.lights.size()); }
    const SceneDesc& desc() const { return d_; }

private:
    ShapeDesc shape(ShapeType type, int material, int interiorMedium) const {
        ShapeDesc s;
        s.type = type;
        s.material = material;
        s.interiorMedium = interiorMedium;
        return s;
    }
    LightDesc light(LightType type, const Color& power, double emitOpl) const {
        LightDesc l;
        l.type = type;
        l.power = power;
        l.emitOpl = emitOpl;
        return l;
    }
    SceneBuilder& add(ShapeDesc s) {
        d_.shapes.push_back(std::move(s));
        return *this;
    }
    SceneBuilder& add(LightDesc l) {
        d_.lights.push_back(std::move(l));
        return *this;
    }

    SceneDesc d_;
};

}  // namespace tpb::test
