// Free flight and segment transport through a region (see free_flight.h).
#include "transport/free_flight.h"

namespace tpb {

FreeFlight sampleFreeFlight(const Region& region, const Ray& ray, double tMax, Rng& rng) {
    const MediumSample ms = region.medium.sampleFreeFlight(ray, tMax, rng);
    FreeFlight ff;
    ff.distance = ms.distance;
    ff.scattered = ms.scattered;
    ff.weight = ms.weight;
    if (std::isfinite(ms.distance)) ff.opl = region.ior * ms.distance;
    return ff;
}

SegmentTransport crossSegment(const Region& region, const Ray& ray, double length) {
    SegmentTransport st;
    // No medium: the transmittance stays exactly 1 (and an unbounded segment gives no 0 * inf).
    if (region.hasMedium) st.transmittance = region.medium.transmittance(ray, length);
    st.opl = region.ior * length;
    return st;
}

}  // namespace tpb
