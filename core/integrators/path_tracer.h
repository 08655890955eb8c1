// Unbiased transient volumetric path tracer: the independent reference for the photon-beam core.
// It shares only the scene, geometry, sampling, RNG and film code with the beam renderer (no photon
// map, no kernels), so the two estimators can be compared (they should agree up to kernel bias).
//
// Algorithm (one camera path per pixel sample, unidirectional):
//  - camera ray through a jittered raster position, RNG keyed by (seed, PathTracer, pass, pixel);
//  - in a scattering region: free-flight sampling with the average extinction sigma_bar (as
//    photon_tracer.cpp), per-channel weight sigma_s T(d) / (sigma_bar T_bar(d)) at a scattering
//    vertex and T / T_bar when the surface comes first; non-scattering absorbing regions just
//    attenuate by T;
//  - medium vertex: next-event estimation (NEE) to one light picked with Scene::pickLight, phase
//    function value; then Henyey-Greenstein sampling (weight 1). Point and spot lights are
//    connected instead from an equiangular point on every medium segment (settings.equiangular,
//    on by default): same expectation, bounded variance next to the light;
//  - diffuse surface: NEE with f = albedo / pi and the cosine at the vertex; cosine sampling;
//  - mirror, dielectric (Fresnel choice, total internal reflection, region stack push/pop) and null
//    boundaries (always crossed, no bending) continue the path; the region stack, ray epsilons and
//    the tint conventions are the beam core's (all in transport/interaction.h, the free flight in
//    transport/free_flight.h);
//  - an area light hit adds its emission only when NEE could not have produced that path: the
//    previous vertex is the camera or a mirror/dielectric (null crossings are transparent and do
//    not count). Emitters and shapes without material absorb (as in the beam core);
//  - Russian roulette on the throughput from the 3rd vertex on.
//
// NEE shadow rays never refract: mirrors, dielectrics, diffuse surfaces, emitters and shapes
// without material block them; null boundaries are crossed (region stack pushed/popped along the
// shadow ray), and the shadow segment's transmittance and OPL are accumulated per region. The
// direct-light paths through dielectrics are still found: by BSDF sampling an area light through
// the specular chain. Consequences (inherent to unidirectional path tracing, not bugs):
//  - lasers are delta in direction AND position-on-a-line: a camera path can neither connect to
//    them nor hit them. NEE connects to the laser's leg instead (a scan's laser aimed at the
//    pixel's laser point): to its spot, where the beam first meets a diffuse surface (a Lambertian
//    point of intensity Phi T_leg rho / pi cos), and, when the laser's region scatters, to a point of
//    the beam itself sampled equiangularly (a line light), each with probability 1/2. Not connected:
//    a beam meeting glass, a mirror or a null boundary first, light it scatters beyond its own
//    region (PathTracerStats::laserSamples), and the spot seen directly (a delta on the wall);
//  - point and spot lights seen through a specular chain (caustics from delta lights, e.g. a
//    point light behind glass or reflected by a mirror) are missed: the beam core's photon map and
//    beams do capture them, so compare with such scenes only with area lights;
//  - the camera path never adds direct emission from point/spot lights (delta), like the beam core.
//
// Time (optical path length, m, OPL = ior * distance per segment):
//  - real time t = light.emitOpl + OPL(light -> ... -> sensor), every segment included: the camera
//    path, the shadow (light connection) segment;
//  - camera-unwarped time = t minus the OPL of the camera path from the sensor to the FIRST
//    non-specular vertex (medium scattering point or diffuse surface point), specular bounces and
//    null crossings before it included; i.e. the time the light reaches that vertex. This is the
//    beam core's definition (camera_pass.cpp: beams at b.opl0 + eta s_b, photons at ph.opl). A path
//    without a non-specular vertex (an area light seen directly or through mirrors/glass) is at
//    light.emitOpl on the unwarped axis, as in the beam core.
// Each contribution goes, divided by the samples per pixel, to the bin of its time on each axis
// (PixelAccumulator::add) and to the steady-state image (addSteady); contributions outside the
// film's range are tallied in the stats (luminance, per axis), never lost silently; non-finite
// contributions are counted and dropped (not added to the steady state either).
//
// Depth: maxDepth bounds the number of scattering vertices on the camera path (medium scattering,
// diffuse, mirror and dielectric interactions; null crossings do not count). NEE is done at the
// last allowed vertex, so maxDepth = 1 gives exactly single scattering / direct lighting.
#pragma once
#include "film/transient_film.h"
#include "integrators/render_settings.h"
#include "scene/scene.h"

#include <atomic>
#include <cstdint>

namespace tpb {

struct PathTracerStats : FilmTally {  // rejected: non-finite contributions (or throughputs) dropped
    int64_t cameraPaths = 0;
    int64_t contributions = 0;       // finite contributions added (NEE + emitter hits)
    int64_t shadowRays = 0;          // NEE connections traced
    int64_t laserSamples = 0;        // NEE picked a laser without a spot to connect to (contributes nothing)
    int64_t equiangularSamples = 0;  // equiangular points placed towards point/spot lights
    int64_t depthLimited = 0;        // paths stopped by maxDepth (not by escape, absorption or RR)
    int64_t regionOverflows = 0;     // paths (or shadow rays) ended because their region stack was full (RegionStack)
    PathTracerStats& operator+=(const PathTracerStats& o);
};

// One pixel's estimate for this pass (mean of samplesPerPixel camera paths) added into `acc`
// with the bins of `time`; the caller clears `acc` (no film access; for tests and tools).
void pathTracePixel(const Scene& scene, const RenderSettings& s, uint64_t pass, const TimeBins& time, int x, int y,
                    PixelAccumulator& acc, PathTracerStats& stats);

// Whole passes run through the Driver (render/driver.h) with Method::PathTracer: the integrator is
// PathTracerIntegrator (integrators/path_tracer_integrator.h).

}  // namespace tpb
