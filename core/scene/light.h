// Light sources and photon emission: point (uniform sphere), spot (uniform in the cutoff cone,
// weighted by its smoothstep profile), area quad (uniform position, cosine-distributed direction:
// Lambertian, one-sided, visible to the camera through areaRadiance) and laser (a collimated beam,
// optionally of a radius). Power is radiant flux (W, RGB); emitOpl the pulse instant as optical
// path length (m). The region a photon starts in is the scene's business (Scene::emissionRegions:
// where the emitting point lies, found from the light's LightPlacement).
#pragma once
#include "base/math.h"
#include "base/rng.h"
#include "scene/scene_desc.h"

namespace tpb {

struct EmissionSample {
    Ray ray;
    Color power;  // flux carried by this photon before dividing by the photon count (W)
};

struct Light {
    LightType type = LightType::Point;
    Color power{0.0};
    double emitOpl = 0.0;
    Vec3 position{0.0}, direction{0.0, -1.0, 0.0};
    double cosCutoff = 0.0, cosFalloff = 1.0, spotIntegral = 0.0;  // spot: int f(w) dw (sr)
    Vec3 corner{0.0}, edgeU{0.0}, edgeV{0.0}, normal{0.0, 1.0, 0.0};
    double area = 0.0;
    double laserRadius = 0.0;

    static Light fromDesc(const LightDesc& d);
    // An area light's photon starts `offset` (Scene::rayEps) in front of its quad and up to
    // `offset` in from its edges: off the quad, off a wall the quad lies on, and off a side wall
    // at its edge (a light filling the ceiling of a closed box must not emit through the walls).
    EmissionSample sampleEmission(Rng& rng, double offset) const;
    // The point of an area light at (u, v) in [0, 1]^2 moved `offset` in front of the quad and up
    // to `offset` in from its edges: where its photons start, and where shadow rays end.
    Vec3 offsetAreaPoint(double u, double v, double offset) const;
    // A laser photon's start for (u1, u2) in [0, 1)^2: a point of the beam's disc (laserRadius)
    // around `position`, across `dir` (the light's direction, or a scan's aim).
    Vec3 laserOrigin(double u1, double u2, const Vec3& dir) const;
    // Spot profile f(cos) in [0, 1]: 1 inside the falloff cone, smooth to 0 at the cutoff.
    double spotProfile(double cosTheta) const;
    // Radiance leaving the front side of an area light (W / (m^2 sr)).
    Color areaRadiance() const { return area > 0.0 ? power / (kPi * area) : Color(0.0); }
};

}  // namespace tpb
