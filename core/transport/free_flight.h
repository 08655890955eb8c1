// Free flight through the region a path is in: the one place tracers (photon tracer, camera pass,
// path tracer and its shadow rays) sample a distance to the next scattering event and take the
// transmittance and optical path length of a straight segment.
//
// Convention (photon_tracer.h, path_tracer.h): distances are sampled with the average extinction
// sigma_bar = average(sigma_t), pdf sigma_bar exp(-sigma_bar d); the per-channel weight is
// sigma_s T(d) / (sigma_bar T_bar(d)) at a scattering event and T / T_bar when the surface comes
// first (1 for grey media). T(d) = exp(-sigma_t d) per channel. OPL = ior * distance (eq. 11).
// The media themselves answer through core/scene/medium.h (Medium::sampleFreeFlight,
// Medium::transmittance), so a heterogeneous medium changes only that file.
#pragma once
#include "scene/scene.h"

namespace tpb {

// A free flight sampled in `region` along `ray` up to the surface at tMax (kInf: none).
// Only for regions whose medium scatters (Region::hasMedium && medium.scattering): one random
// number from rng.
struct FreeFlight {
    double distance = kInf;  // m: to the scattering event, or tMax
    bool scattered = false;  // the event lies before tMax
    Color weight{0.0};       // per channel (MediumSample::weight); 0 when distance is infinite
    double opl = 0.0;        // m: ior * distance (0 when distance is infinite)
};
FreeFlight sampleFreeFlight(const Region& region, const Ray& ray, double tMax, Rng& rng);

// A straight segment [0, length) of `ray` crossed inside `region` without an event.
struct SegmentTransport {
    Color transmittance{1.0};  // exactly 1 in vacuum (no medium), so multiplying by it changes nothing
    double opl = 0.0;          // m: ior * length
};
SegmentTransport crossSegment(const Region& region, const Ray& ray, double length);

}  // namespace tpb
