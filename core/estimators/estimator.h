// Density estimators of the photon-beams camera pass, as units (docs/developer/adding-an-estimator.md: how to add one,
// with a worked example). The camera pass (integrators/camera_pass.cpp) follows a camera path
// through specular surfaces and asks:
//   a VolumeEstimator, on every segment of the path inside a scattering medium, for the in-scattered
//     radiance the photon map's beams (or points) put along it;
//   a SurfaceEstimator, at the diffuse surface the path ends on, for the reflected radiance of the
//     surface photons around it.
// Each estimate goes to the pixel's accumulator spread over the time bins it covers (PixelSink,
// film/transient_film.h: splatSpread / splatInstant) on both time axes.
//
// An estimator owns what it needs to answer queries for one pass (an accelerator over the beams, a
// grid over the photons), built in prepare() from the pass's photon map and kernel radius. Its
// kernel's dimension (dim()) drives the progressive radius schedule (base/progressive.h): the
// kernel's measure r^dim shrinks by (i + alpha) / (i + 1) per pass, so the estimator's bias goes
// to zero while its variance stays bounded (Knaus & Zwicker 2011; Jarosz et al. 2011 for beams).
//
// Registration: estimators are created by name (estimators/registry.cpp; RenderSettings::
// volumeEstimator / surfaceEstimator): a new estimator is its own file, one line there, its tests.
#pragma once
#include "accel/beam_accel.h"
#include "estimators/estimator_names.h"
#include "estimators/segment_bundle.h"
#include "film/transient_film.h"
#include "photons/photon_tracer.h"
#include "scene/scene.h"

#include <memory>
#include <string>
#include <vector>

namespace tpb {

// The part of a camera path a volume estimate is taken along: x_r + s w_r, s in [0, sMax] (m; sMax
// may be infinite), inside `region` (its medium scatters).
struct CameraSegment {
    Ray ray;
    double sMax = kInf;
    int region = 0;
};

// What the camera path carries to the estimate: its throughput and the OPL from the sensor to the
// segment's start (the real time axis adds it; the unwarped axis does not).
struct PathState {
    Color beta{1.0};
    double oplCam = 0.0;  // m
};

// Where an estimate goes: the pixel's accumulator for this pass, on the film's time axis; tally
// counts what fell outside the film and non-finite estimates (dropped).
// Estimators write through spread() and instant() only, so what the film does with an estimate's
// time profile (the bins, a progressive time kernel) is decided here, not in every estimator.
// The sink also carries this pass's time kernel of the estimator writing into it (estimators/
// time_kernel.h; set by the photon-beams integrator per pass and per estimator, the camera pass
// gives each estimator its own): every estimate's time profile is convolved with it on both axes.
// None (the default) is the kernel-free code, bit for bit.
struct PixelSink {
    const TimeBins& time;
    PixelAccumulator& acc;
    FilmTally& tally;
    TimeKernel kernel{};
    // Energy L along s in [s0, s1] of the camera segment with density exp(-kappa s), arriving at
    // aReal + bReal s (real axis) and aUnwarped + bUnwarped s (unwarped axis), OPL in m; no part
    // earlier than `floor` (the earliest real path through the estimate's photon, causalFloor()).
    void spread(const Color& L, const Color& kappa, double s0, double s1, double aReal, double bReal, double aUnwarped,
                double bUnwarped, const ArrivalFloor& floor = {}) {
        splatSpread(time, acc, tally, L, kappa, s0, s1, aReal, bReal, aUnwarped, bUnwarped, kernel, floor);
    }
    // The same with the profile of exp(-kappa s) on [s0, s1] built by the estimator (SegmentProfile,
    // time_splat.h), which can hand it totals it has computed anyway (bit for bit the same values).
    void spread(const Color& L, const SegmentProfile& profile, double aReal, double bReal, double aUnwarped,
                double bUnwarped, const ArrivalFloor& floor = {}) {
        splatSpread(time, acc, tally, L, profile, aReal, bReal, aUnwarped, bUnwarped, kernel, floor);
    }
    // Energy L arriving at one instant on each axis (no earlier than `floor`).
    void instant(const Color& L, double tReal, double tUnwarped, const ArrivalFloor& floor = {}) {
        splatInstant(time, acc, tally, L, tReal, tUnwarped, kernel, floor);
    }
};

// The causal floor of an estimate (docs/developer/adding-an-estimator.md, "Causality"). Its
// photon's flight starts at x_start (OPL tStart; a beam's `from`, the event before a photon point);
// the camera segment starts at x_r (the path's OPL there: oplCam) in a region of index eta.
// Real: the earliest path leaves the flight at x_start straight for x_r (light -> x_start -> x_r ->
// sensor; s + |x(s) - x_r| only grows along the flight). Unwarped: light on the flight reaches a
// point within r of where the photon first is in the kernel (tEvent) no earlier than eta r before.
//   real:      oplCam + tStart + eta |x_start - x_r|,     unwarped:  tEvent - eta r.
inline ArrivalFloor causalFloor(double oplCam, double tStart, double eta, const Vec3& xStart, const Vec3& xr,
                                double tEvent, double r) {
    const double unwarped = tEvent - eta * r;
    if (!(tStart > -kInf)) return {-kInf, unwarped};  // the flight's start unknown: the unwarped floor only
    return {oplCam + tStart + eta * glm::length(xStart - xr), unwarped};
}

// Per-thread scratch space of the estimators (kept across pixels to avoid allocations).
struct EstimatorScratch {
    std::vector<BeamPiece> pieces;  // candidate beam pieces of the current segment
    std::vector<int> shapes;        // shapes near the current segment (visibility tests)
    SegmentBundle bundle;           // the block of pixels being rendered (segment_bundle.h)
    OverlapBatch overlaps;          // one segment against the block's pieces (overlap_batch.h)
    PieceAxes boxAxes;              // a shared query's box candidates, for its fat test
    std::vector<uint64_t> keys;     // the kept ones' (beam, piece) keys above their index, to sort them
};

// Per-pass parameters of an estimator.
struct EstimatorPass {
    double radius = 0.01;  // m, this pass's kernel radius
    TimeProfile profile = TimeProfile::Exact;
    BeamLength beamLength = BeamLength::Short;
    AccelBackend accel = AccelBackend::Bvh;
    int threads = 1;
    TimeKernel timeKernel;  // this pass's time kernel of the estimator (None: off); the sink applies it
    // m: how far a camera segment may lie from a block's shared query axis (segment_bundle.h); an
    // estimator that shares queries builds its accelerator with support radius + this. 0: off.
    double bundleSlack = 0.0;
};

class VolumeEstimator {
public:
    virtual ~VolumeEstimator() = default;
    virtual std::string name() const = 0;
    virtual int dim() const = 0;  // kernel dimension for the radius schedule
    // What the photon pass must store for this estimator (beams, points at scattering events, or both).
    struct Needs {
        bool beams = true;
        bool points = false;
    };
    virtual Needs needs() const { return {}; }
    // Builds what gather() needs from this pass's photon map (which must outlive the pass).
    virtual void prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) = 0;
    virtual bool empty() const = 0;              // nothing to gather this pass
    virtual size_t accelPrimitives() const = 0;  // beam pieces (or points) indexed, for the stats
    // Adds the estimate along `seg` to `sink`; returns the number of beams/points that contributed.
    virtual int64_t gather(const CameraSegment& seg, const PathState& path, PixelSink& sink,
                           EstimatorScratch& scratch) const = 0;
};

// The diffuse surface point a camera path ends on.
struct SurfaceQuery {
    const Ray& ray;  // the camera ray that hit it
    const SurfaceHit& hit;
    Vec3 ng;       // geometric normal facing the ray
    Color albedo;  // Lambertian albedo (f_r = albedo / pi)
};

class SurfaceEstimator {
public:
    virtual ~SurfaceEstimator() = default;
    virtual std::string name() const = 0;
    virtual int dim() const = 0;
    virtual void prepare(const Scene& scene, const PhotonMap& map, const EstimatorPass& pass) = 0;
    virtual bool empty() const = 0;
    virtual int64_t gather(const SurfaceQuery& q, const PathState& path, PixelSink& sink) const = 0;
};

// By name (estimators/estimator_names.h lists them, the default first): nullptr for an unknown name.
std::unique_ptr<VolumeEstimator> makeVolumeEstimator(const std::string& name);
std::unique_ptr<SurfaceEstimator> makeSurfaceEstimator(const std::string& name);

}  // namespace tpb
