#include "scene/light.h"

#include "base/sampling.h"

namespace tpb {

double Light::spotProfile(double cosTheta) const {
    if (cosTheta >= cosFalloff) return 1.0;
    if (cosTheta <= cosCutoff) return 0.0;
    const double x = (cosTheta - cosCutoff) / (cosFalloff - cosCutoff);
    return x * x * (3.0 - 2.0 * x);  // smoothstep
}

Vec3 Light::laserOrigin(double u1, double u2, const Vec3& dir) const {
    if (!(laserRadius > 0.0)) return position;
    const double r = laserRadius * std::sqrt(u1), phi = 2.0 * kPi * u2;
    return position + toWorld(Vec3(r * std::cos(phi), r * std::sin(phi), 0.0), dir);
}

Light Light::fromDesc(const LightDesc& d) {
    Light l;
    l.type = d.type;
    l.power = d.power;
    l.emitOpl = d.emitOpl;
    l.position = d.position;
    l.direction = glm::length(d.direction) > 0.0 ? glm::normalize(d.direction) : Vec3(0.0, -1.0, 0.0);
    l.cosCutoff = std::cos(d.spotCutoffDeg * kPi / 180.0);
    l.cosFalloff = std::cos(std::min(d.spotFalloffDeg, d.spotCutoffDeg) * kPi / 180.0);
    if (d.type == LightType::Spot) {
        // int_{cone} f dw = 2 pi int_{cosCutoff}^{1} f(mu) dmu (midpoint rule, 4096 steps)
        const int n = 4096;
        double s = 0.0;
        const double h = (1.0 - l.cosCutoff) / n;
        for (int i = 0; i < n; ++i) s += l.spotProfile(l.cosCutoff + (i + 0.5) * h);
        l.spotIntegral = 2.0 * kPi * s * h;
    }
    l.corner = d.corner;
    l.edgeU = d.edgeU;
    l.edgeV = d.edgeV;
    const Vec3 cr = glm::cross(d.edgeU, d.edgeV);
    l.area = glm::length(cr);
    if (l.area > 0.0) l.normal = cr / l.area;
    l.laserRadius = d.laserRadius;
    return l;
}

Vec3 Light::offsetAreaPoint(double u, double v, double offset) const {
    const Vec3 p = corner + u * edgeU + v * edgeV;
    const Vec3 toCentre = corner + 0.5 * (edgeU + edgeV) - p;
    const double lenToCentre = glm::length(toCentre);
    const double inwards = lenToCentre > 0.0 ? std::min(offset, lenToCentre) / lenToCentre : 0.0;
    return p + offset * normal + inwards * toCentre;
}

EmissionSample Light::sampleEmission(Rng& rng, double offset) const {
    EmissionSample e;
    const double u1 = rng.uniform(), u2 = rng.uniform();
    switch (type) {
        case LightType::Point:
            e.ray = {position, sampleUniformSphere(u1, u2)};
            e.power = power;
            break;
        case LightType::Spot: {
            // Uniform in the cutoff cone, weighted by the profile: w = Phi f / (int f dw * pdf).
            const Vec3 local = sampleUniformCone(u1, u2, cosCutoff);
            const double pdf = 1.0 / (2.0 * kPi * (1.0 - cosCutoff));
            e.ray = {position, glm::normalize(toWorld(local, direction))};
            e.power = spotIntegral > 0.0 ? power * (spotProfile(local.z) / (spotIntegral * pdf)) : Color(0.0);
            break;
        }
        case LightType::AreaQuad: {
            // Uniform position, cosine direction: exactly the Lambertian emission, weight = Phi.
            const double u3 = rng.uniform(), u4 = rng.uniform();
            const Vec3 d = glm::normalize(toWorld(sampleCosineHemisphere(u3, u4), normal));
            e.ray = {offsetAreaPoint(u1, u2, offset), d};
            e.power = power;
            break;
        }
        case LightType::Laser: {
            e.ray = {laserOrigin(u1, u2, direction), direction};
            e.power = power;
            break;
        }
    }
    return e;
}

}  // namespace tpb
