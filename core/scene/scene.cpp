#include "scene/scene.h"

#include "base/error.h"
#include "scene/mesh.h"

#include <algorithm>
#include <cstdio>
#include <map>

namespace tpb {

namespace {

// A mesh that holds a medium (a dielectric or null shape with an interior medium) must be closed
// and consistently oriented: a ray that enters it pushes its region and must meet it again to pop
// it, else the medium leaks out to everything the ray reaches after (openEdges, mesh.h). Shapes
// other than meshes are closed by construction (quads, rectangles and disks cannot hold a medium).
void checkClosedContainer(const SceneDesc& d, const std::string& key, const ShapeDesc& sd, const std::string& name,
                          const TriangleMesh& m, size_t droppedDegenerate) {
    const OpenEdges open = openEdges(m);
    if (open.closed()) return;
    const std::string mediumKey = d.locs.count(key + ".interior_medium") ? key + ".interior_medium" : key;
    std::string what;
    if (open.holes > 0) what += std::to_string(open.holes) + " edges of one triangle only (holes)";
    if (open.misfits > 0)
        what += std::string(what.empty() ? "" : " and ") + std::to_string(open.misfits) +
                " edges shared by triangles facing opposite ways (or by more than two)";
    const std::string mesh = "the mesh \"" + name + "\"" + (sd.meshPath.empty() ? "" : " (" + sd.meshPath + ")");
    throw UserError(d.where(mediumKey) + mediumKey + ": " + mesh + " holds a medium but is not closed: " + what +
                    (droppedDegenerate > 0
                         ? " (" + std::to_string(droppedDegenerate) + " zero-area triangles were dropped on loading)"
                         : "") +
                    "; the medium would leak out through them. Close the mesh and orient its faces consistently "
                    "(e.g. Blender: Select > All by Trait > Non Manifold, then Face > Fill; Mesh > Normals > "
                    "Recalculate Outside), or remove the interior medium");
}

Region makeRegion(const MediumDesc* m, double iorOverride) {
    Region r;
    if (m) {
        r.medium.sigma_s = m->sigma_s;
        r.medium.sigma_a = m->sigma_a;
        r.medium.sigma_t = m->sigma_s + m->sigma_a;
        r.medium.ior = m->ior;
        r.medium.phase.g = m->g;
        r.medium.scattering = maxComponent(m->sigma_s) > 0.0;
        r.hasMedium = maxComponent(r.medium.sigma_t) > 0.0;
        r.ior = m->ior;
    }
    if (iorOverride > 0.0) r.ior = iorOverride;
    r.medium.ior = r.ior;
    return r;
}

struct SurfaceProbe {
    int shape;
    Vec3 p, n;  // a point of the surface and its unit normal there
};

// Refuses dielectric/null shapes nested deeper than a RegionStack holds, naming the chain. A
// point just inside each shape's surface finds the shapes around it (the deepest point of a
// properly nested scene lies inside its innermost shape).
void checkNesting(const Scene& s, const SceneDesc& desc, const std::vector<SurfaceProbe>& probes) {
    for (const SurfaceProbe& pr : probes) {
        const std::vector<int> around = s.shapesAround(pr.p - 4.0 * s.rayEps * pr.n);
        if (static_cast<int>(around.size()) < RegionStack::kCapacity) continue;
        std::string chain;
        for (int sh : around) chain += (chain.empty() ? "\"" : " > \"") + s.shapes[sh].name + "\"";
        const std::string key = "shapes[" + std::to_string(pr.shape) + "]";
        throw UserError(desc.where(key) + key + ": \"" + s.shapes[pr.shape].name + "\" is the innermost of " +
                        std::to_string(around.size()) + " nested dielectric/null shapes (outermost first: " + chain +
                        "); at most " + std::to_string(RegionStack::kCapacity - 1) +
                        " can nest (the region stack holds the outside and " +
                        std::to_string(RegionStack::kCapacity - 1) +
                        " shapes); take shapes out of the nesting or merge nested shells into one shape");
    }
}

// The region stack where a light's photons start and whether it holds over all of the light:
// true unless a dielectric/null shape's bounds come near the points it emits from (a surface
// that changes the region must pass through those bounds).
LightPlacement placeLight(const Scene& s, const Light& l) {
    LightPlacement pl;
    Bounds3 footprint;
    pl.anchor = l.position;
    footprint.expand(l.position);
    if (l.type == LightType::AreaQuad) {
        const Vec3 lift = s.rayEps * l.normal;  // photons start rayEps in front of the quad
        // Not the centre: scenes put boundaries through round coordinates (a light centred on a
        // container's face), and a stack found at a point on a surface would be a coin toss.
        pl.anchor = l.corner + 0.6180339887 * l.edgeU + 0.4142135624 * l.edgeV + lift;
        footprint = Bounds3{};
        for (const Vec3& c : {l.corner, l.corner + l.edgeU, l.corner + l.edgeV, l.corner + l.edgeU + l.edgeV})
            footprint.expand(c + lift);
    } else if (l.type == LightType::Laser && l.laserRadius > 0.0) {
        footprint.expand(l.position - Vec3(l.laserRadius));
        footprint.expand(l.position + Vec3(l.laserRadius));
    }
    pl.regions = s.regionsAt(pl.anchor);
    const double pad = 8.0 * s.rayEps;
    for (const ShapeInfo& sh : s.shapes) {
        if (sh.interiorRegion <= 0 || !sh.bounds.valid()) continue;
        const bool apart = glm::any(glm::lessThan(sh.bounds.hi + pad, footprint.lo)) ||
                           glm::any(glm::greaterThan(sh.bounds.lo - pad, footprint.hi));
        if (!apart) pl.uniform = false;
    }
    return pl;
}

// Every laser point of a scan must be lit: the laser's ray towards it meets the relay wall there
// first (not another shape, not the wall's back). Checked for every point, before any pass runs.
void checkScanLaser(const Scene& s, const SceneDesc& d) {
    const Camera& c = s.camera;
    const Light& laser = s.lights.at(static_cast<size_t>(c.scanLaser));
    const std::string key = "camera.scan.laser";
    const std::string name = d.lights.at(static_cast<size_t>(c.scanLaser)).name;
    const double side = glm::dot(laser.position - c.wallCorner, c.wallN);
    const double size = std::max(glm::length(c.wallU), glm::length(c.wallV));
    if (!(std::abs(side) > 1e-9 * size) || side * glm::dot(c.position - c.wallCorner, c.wallN) < 0.0)
        throw UserError(d.where(key) + key + ": the laser \"" + name +
                        "\" is not on the sensor's side of the relay wall: it cannot light the points the sensor "
                        "sees; move its position in front of the wall, on the sensor's side");
    const int wall = d.camera.wallShape;
    for (int64_t l = 0; l < c.laserPoints(); ++l) {
        const Vec3 target = c.laserTarget(l), v = target - laser.position;
        const double dist = glm::length(v);
        const std::optional<SurfaceHit> hit = s.geometry.intersect({laser.position, v / dist});
        if (!hit || hit->shape != wall || std::abs(hit->t - dist) > 1e-6 * std::max(1.0, dist)) {
            char at[96];
            std::snprintf(at, sizeof at, "(%.4g, %.4g, %.4g)", target.x, target.y, target.z);
            throw UserError(d.where(key) + key + ": the laser \"" + name + "\" cannot reach laser point " +
                            std::to_string(l) + " at " + at + " on the relay wall: " +
                            (hit ? "shape \"" + d.shapes.at(static_cast<size_t>(hit->shape)).name + "\" is in the way"
                                 : std::string("its ray misses every shape")) +
                            "; move the laser, or the shape, so that it sees the wall");
        }
    }
}

}  // namespace

std::unique_ptr<const Scene> Scene::build(const SceneDesc& d, StageAnalysis analyzeStages) {
    auto s = std::make_unique<Scene>();

    for (const MaterialDesc& m : d.materials) s->materials.push_back({m.type, m.albedo, m.specular, m.ior});

    // Region 0: the outside, filled by the global medium (or vacuum).
    s->regions.push_back(makeRegion(d.globalMedium >= 0 ? &d.media[d.globalMedium] : nullptr, 0.0));

    std::vector<ShapeDesc> shapes = d.shapes;
    // Each area light gets a visible, one-sided emitting quad (black otherwise).
    for (size_t i = 0; i < d.lights.size(); ++i) {
        const LightDesc& l = d.lights[i];
        if (l.type != LightType::AreaQuad) continue;
        ShapeDesc q;
        q.name = l.name.empty() ? "area light " + std::to_string(i) : l.name;
        q.type = ShapeType::Quad;
        q.corner = l.corner;
        q.edgeU = l.edgeU;
        q.edgeV = l.edgeV;
        q.areaLight = static_cast<int>(i);
        shapes.push_back(q);
    }

    // A point on each dielectric/null shape's surface and its normal (the interior lies against
    // it), to measure how deep the shapes nest (checkNesting).
    std::vector<SurfaceProbe> probes;
    for (size_t i = 0; i < shapes.size(); ++i) {
        const ShapeDesc& sd = shapes[i];
        const std::string key = "shapes[" + std::to_string(i) + "]";
        ShapeInfo info;
        info.name = sd.name.empty() ? key : sd.name;
        info.material = sd.material;
        info.areaLight = sd.areaLight;
        const Material* mat = sd.material >= 0 ? &s->materials[sd.material] : nullptr;
        const bool isInterface = mat && (mat->type == MaterialType::Dielectric || mat->type == MaterialType::Null);
        if (isInterface) {
            const MediumDesc* inner = sd.interiorMedium >= 0 ? &d.media[sd.interiorMedium] : nullptr;
            // A dielectric's index is its material's; a null boundary takes its medium's.
            const double ior = mat->type == MaterialType::Dielectric ? mat->ior : (inner ? inner->ior : 1.0);
            s->regions.push_back(makeRegion(inner, ior));
            info.interiorRegion = static_cast<int>(s->regions.size() - 1);
        }
        const int id = static_cast<int>(i);
        const auto addMesh = [&](const TriangleMesh& m) {
            s->geometry.addMesh(m, id);
            for (const Vec3& v : m.positions) info.bounds.expand(v);
            if (isInterface && !m.triangles.empty()) {
                const glm::uvec3 t = m.triangles[0];
                const Vec3 a = m.positions[t.x], b = m.positions[t.y], c = m.positions[t.z];
                const Vec3 n = glm::cross(b - a, c - a);
                if (glm::length(n) > 0.0) probes.push_back({id, (a + b + c) / 3.0, glm::normalize(n)});
            }
        };
        switch (sd.type) {
            case ShapeType::Mesh: {
                TriangleMesh m;
                size_t dropped = 0;
                if (sd.meshPath.empty()) {
                    m.positions = sd.inlinePositions;
                    m.triangles = sd.inlineTriangles;
                } else
                    try {
                        m = loadMeshFile(sd.meshPath, &dropped);
                    } catch (
                        const UserError& e) {  // name the scene's key too: "scene.json:8: shapes[0].file: x.obj:4: ..."
                        throw UserError(d.where(key + ".file") + key + ".file: " + e.what());
                    }
                try {
                    m.transform(sd.transform);
                } catch (const UserError& e) {  // a vertex beyond the coordinate limit
                    const std::string k = d.locs.count(key + ".transform") ? key + ".transform" : key + ".file";
                    throw UserError(d.where(k) + k + ": " + sd.meshPath + ": " + e.what());
                }
                if (sd.flipNormals) m.flip();
                if (isInterface && sd.interiorMedium >= 0) checkClosedContainer(d, key, sd, info.name, m, dropped);
                addMesh(m);
                break;
            }
            case ShapeType::Sphere:
                s->geometry.addSphere(sd.center, sd.radius, id);
                info.bounds.expand(sd.center - Vec3(sd.radius));
                info.bounds.expand(sd.center + Vec3(sd.radius));
                if (isInterface) probes.push_back({id, sd.center + Vec3(0.0, sd.radius, 0.0), Vec3(0.0, 1.0, 0.0)});
                break;
            case ShapeType::Quad: {
                TriangleMesh m = makeQuad(sd.corner, sd.edgeU, sd.edgeV);
                if (sd.flipNormals) m.flip();
                addMesh(m);
                break;
            }
            case ShapeType::Box: {
                TriangleMesh m = makeBox(sd.boxMin, sd.boxMax);
                m.transform(sd.transform);
                if (sd.flipNormals) m.flip();
                addMesh(m);
                break;
            }
        }
        s->shapes.push_back(info);
    }
    s->geometry.commit();

    for (const LightDesc& l : d.lights) s->lights.push_back(Light::fromDesc(l));
    double total = 0.0;
    for (const Light& l : s->lights) {
        total += std::max(0.0, luminance(l.power));
        s->lightCdf.push_back(total);
    }
    if (total > 0.0)
        for (double& c : s->lightCdf) c /= total;

    s->camera = Camera::fromDesc(d.camera);
    if (d.camera.type == CameraType::RelayWall) {
        // The relay wall: the grid on its quad; the sensor must see the wall's plane.
        const ShapeDesc& w = d.shapes.at(static_cast<size_t>(d.camera.wallShape));
        Camera& c = s->camera;
        c.relayWall = true;
        c.timeFromWall = d.camera.timeOrigin == WallTimeOrigin::Wall;
        c.wallCorner = w.corner;
        c.wallU = w.edgeU;
        c.wallV = w.edgeV;
        c.wallN = glm::normalize(glm::cross(w.edgeU, w.edgeV));
        const double size = std::max(glm::length(w.edgeU), glm::length(w.edgeV));
        if (!(std::abs(glm::dot(c.position - c.wallCorner, c.wallN)) > 1e-9 * size))
            throw UserError(d.where("camera.position") +
                            "camera.position: the sensor's origin lies in the plane of the "
                            "relay wall \"" +
                            w.name + "\": it cannot see the wall; move it in front of the wall");
        if (c.scan != ScanMode::None) checkScanLaser(*s, d);
    }

    s->bounds = s->geometry.bounds();
    for (const Light& l : s->lights) {
        s->bounds.expand(l.position);
        if (l.type == LightType::AreaQuad) s->bounds.expand(l.corner + l.edgeU + l.edgeV);
    }
    s->bounds.expand(s->camera.position);
    // Ray offsets scale with the geometry, so that a millimetre scene keeps its light: 1e-5 of its
    // size, the larger of its diagonal and its farthest coordinate (float triangles resolve
    // coordinates relative to the origin). A floor of 1 m made the offset 1% of a 1 mm scene.
    const Bounds3 gb = s->geometry.bounds();
    const Vec3 farthest = gb.valid() ? glm::max(glm::abs(gb.lo), glm::abs(gb.hi)) : Vec3(0.0);
    const double size = gb.valid() ? std::max({gb.diagonal(), farthest.x, farthest.y, farthest.z}) : 1.0;
    s->rayEps = 1e-5 * (size > 0.0 ? size : 1.0);

    // Where the camera and the lights sit (inside glass or a medium container, or outside).
    checkNesting(*s, d, probes);
    s->cameraRegions = s->regionsAt(s->camera.position);
    s->camera.legIor = s->regions[static_cast<size_t>(s->cameraRegions.top())].ior;
    for (const Light& l : s->lights) s->lightPlacement.push_back(placeLight(*s, l));

    // Stages this scene needs (decided by the floor that traces rays: transport/stages.h).
    s->stages = analyzeStages(*s);
    return s;
}

double scanEmitOpl(const Scene& scene, const Vec3& target) {
    const int li = scene.camera.scanLaser;
    const Light& laser = scene.lights.at(static_cast<size_t>(li));
    if (!scene.camera.timeFromWall) return laser.emitOpl;
    const double ior =
        scene.regions[static_cast<size_t>(scene.lightPlacement[static_cast<size_t>(li)].regions.top())].ior;
    return laser.emitOpl - ior * glm::length(target - laser.position);
}

Ray Scene::leaveSurface(const Vec3& p, const Vec3& w, const Vec3& n) const {
    const double cosW = glm::dot(w, n);
    if (!(cosW > 1e-2)) return {p + rayEps * n, w};
    Ray r{p, w};
    r.tmin = rayEps / cosW;
    return r;
}

Vec3 Scene::bounceOrigin(const Ray& ray, const SurfaceHit& hit, const Vec3& ng) const {
    const double back = std::min(rayEps, 0.5 * (hit.t - std::max(ray.tmin, 0.0)));
    return hit.p + rayEps * ng - std::max(back, 0.0) * ray.d;
}

bool Scene::segmentClear(const Vec3& a, const Vec3& b) const {
    const Vec3 v = b - a;
    const double len = glm::length(v);
    if (!(len > 0.0)) return true;
    return !geometry.occluded({a, v / len, 0.0, len});
}

bool Scene::surfacePointsSeeEachOther(const Vec3& a, const Vec3& na, const Vec3& b, const Vec3& nb) const {
    const Vec3 v = b - a;
    Vec3 up = na + nb;
    const double upLen = glm::length(up);
    if (!(upLen > 0.0)) return false;
    up /= upLen;
    // Heights along `up`, from the chord's midpoint, of the planes through a and b normal to na
    // and nb (the tangent planes lifted to the anchors); positive on a convex surface.
    const double ha = -0.5 * glm::dot(v, na) / glm::dot(up, na);
    const double hb = 0.5 * glm::dot(v, nb) / glm::dot(up, nb);
    const double h = std::max(ha, hb);
    // Anchors are at least rayEps off their surfaces: a dip of less than that does not reach them.
    if (!(h > rayEps)) return segmentClear(a, b);
    const Vec3 apex = a + 0.5 * v + h * up;
    return segmentClear(a, apex) && segmentClear(apex, b);
}

std::vector<int> Scene::shapesAround(const Vec3& p) const {
    // Walk outwards along a fixed, non-axis-aligned direction; record the shapes we leave.
    std::vector<int> leaving;
    std::map<int, int> entered;  // shapes entered further out along the ray (and not left yet)
    Ray ray{p, glm::normalize(Vec3(0.5773, 0.5774, 0.5775))};
    for (int guard = 0; guard < 256; ++guard) {
        const auto hit = geometry.intersect(ray);
        if (!hit) break;
        const ShapeInfo& sh = shapes[hit->shape];
        const bool exiting = glm::dot(ray.d, hit->ng) > 0.0;
        if (sh.interiorRegion > 0) {
            int& n = entered[hit->shape];
            if (!exiting)
                ++n;
            else if (n > 0)
                --n;  // left a shape entered on the way
            else
                leaving.push_back(hit->shape);  // left a shape that holds p
        }
        ray = {hit->p + ray.d * rayEps * 4.0, ray.d};
    }
    std::reverse(leaving.begin(), leaving.end());  // innermost was left first
    return leaving;
}

RegionStack Scene::regionsAt(const Vec3& p) const {
    RegionStack st;
    for (int sh : shapesAround(p))
        if (!st.push(shapes[sh].interiorRegion)) break;  // deeper than build() allows: keep the outermost
    return st;
}

bool Scene::walkRegions(RegionStack& stack, const Vec3& from, const Vec3& to) const {
    const Vec3 v = to - from;
    const double len = glm::length(v);
    if (!(len > 0.0)) return true;
    Ray ray{from, v / len, 0.0, len};
    for (int guard = 0; guard < 256; ++guard) {
        const auto hit = geometry.intersect(ray);
        if (!hit) break;
        const ShapeInfo& sh = shapes[hit->shape];
        if (sh.interiorRegion > 0) {
            if (glm::dot(ray.d, hit->ng) > 0.0)
                stack.pop();
            else if (!stack.push(sh.interiorRegion))
                return false;
        }
        ray.tmin = hit->t + 4.0 * rayEps;
    }
    return true;
}

std::optional<RegionStack> Scene::emissionRegions(int li, const Vec3& start) const {
    const LightPlacement& pl = lightPlacement[li];
    if (pl.uniform) return pl.regions;
    RegionStack st = pl.regions;
    if (!walkRegions(st, pl.anchor, start)) return std::nullopt;
    return st;
}

int Scene::pickLight(double u, double& pdf) const {
    if (lights.empty() || lightCdf.back() <= 0.0) {
        pdf = 0.0;
        return -1;
    }
    const auto it = std::upper_bound(lightCdf.begin(), lightCdf.end(), u);
    const int i = std::min<int>(static_cast<int>(it - lightCdf.begin()), static_cast<int>(lights.size()) - 1);
    pdf = lightCdf[i] - (i > 0 ? lightCdf[i - 1] : 0.0);
    return i;
}

}  // namespace tpb
