#include "transport/stages.h"

#include "transport/interaction.h"

namespace tpb {

namespace {

// Does a camera ray through (px, py), followed through mirrors and both branches of dielectric and
// null boundaries, reach a diffuse surface?
bool reachesDiffuse(const Scene& s, Ray ray, int depth) {
    for (; depth < 8; ++depth) {
        const auto hit = s.geometry.intersect(ray);
        if (!hit) return false;
        const SurfaceInteraction si = interact(s, ray, *hit);
        switch (si.kind) {
            case SurfaceKind::Emitter:
            case SurfaceKind::Absorber: return false;
            case SurfaceKind::Diffuse: return true;
            case SurfaceKind::Mirror: ray = offsetReflection(s, ray, *hit, si.ng); continue;
            case SurfaceKind::Dielectric:
            case SurfaceKind::Null:
                // The straight-through branch, then the reflection.
                if (reachesDiffuse(s, offsetStraightThrough(s, ray, *hit, si.ng), depth + 1)) return true;
                if (si.kind == SurfaceKind::Null) return false;
                ray = offsetReflection(s, ray, *hit, si.ng);
                continue;
        }
    }
    return false;
}

bool cameraSeesDiffuse(const Scene& s) {
    for (int y = 0; y < s.camera.height; ++y)
        for (int x = 0; x < s.camera.width; ++x)
            if (reachesDiffuse(s, s.camera.generate(x + 0.5, y + 0.5), 0)) return true;
    return false;
}

}  // namespace

Stages analyzeStages(const Scene& s) {
    Stages st;
    for (size_t r = 0; r < s.regions.size(); ++r)
        if (s.regions[r].hasMedium && s.regions[r].medium.scattering) st.beams = true;
    bool anyDiffuse = false;
    for (size_t i = 0; i < s.shapes.size(); ++i) {
        const int m = s.shapes[i].material;
        if (m < 0) continue;
        const MaterialType t = s.materials[m].type;
        if (t == MaterialType::Diffuse) anyDiffuse = true;
        if (t == MaterialType::Mirror || t == MaterialType::Dielectric) st.specularChains = true;
    }
    // Surface photons only when the camera can see a diffuse surface (directly or through mirrors
    // and glass: glass is followed both ways); photons still bounce off unseen diffuse surfaces.
    st.surfacePhotons = anyDiffuse && cameraSeesDiffuse(s);
    for (const Light& l : s.lights)
        if (l.type == LightType::AreaQuad) st.visibleEmitters = true;
    st.reasons.push_back(st.beams ? "photon beams: a region holds a scattering medium"
                                  : "no photon beams: no scattering medium");
    st.reasons.push_back(st.surfacePhotons ? "surface photon map: the camera sees diffuse surfaces"
                         : anyDiffuse      ? "no surface photon map: no diffuse surface is visible to the camera"
                                           : "no surface photon map: no diffuse surface");
    st.reasons.push_back(st.specularChains ? "specular chains: mirrors or dielectrics present"
                                           : "no specular chains: no mirror or dielectric");
    st.reasons.push_back(st.visibleEmitters ? "visible emitters: area lights"
                                            : "no visible emitters (delta lights only)");
    return st;
}

}  // namespace tpb
