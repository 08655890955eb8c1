// A relay-wall scan's film as an NLOS capture in the NLOS toolkit's layout (io/nlos_hdf5.h,
// docs/user/nlos.md): H time-first from the film's real time axis, pulse response (delta
// emission), the luminance of each bin (a bin holds the response integrated over it, so the bins
// of a wall point sum to its steady value); the wall grids, normals and devices' positions from the
// camera; the time origin from the camera's (wall: t_accounts_first_and_last_bounces false); and
// scene_info with the scene file, the scan and the hidden geometry's ground truth as the wall sees
// it (per sensor point, the distance along the wall's normal to the first surface, and its normal).
#pragma once
#include "film/film_snapshot.h"
#include "film/time_response.h"
#include "io/nlos_hdf5.h"
#include "scene/scene.h"

#include <string>

namespace tpb {

// The capture of `film`, rendered from `scene` (a relay-wall camera with a scan) loaded from
// `scenePath`, seen through `response` (pulse, sensor, photon counts: film/time_response.h; with
// counts, H holds counts per bin). Throws UserError when the camera has no scan.
NlosCapture nlosCapture(const FilmSnapshot& film, const Scene& scene, const std::string& scenePath,
                        const TimeResponse& response = {});

// The capture without scene_info (the viewer's back-projection: no rays cast).
NlosCapture nlosCaptureData(const FilmSnapshot& film, const Scene& scene, const TimeResponse& response = {});
// The capture without H and scene_info: the grids, devices and time axis `tb` (what a
// back-projection's grid needs before the render). Throws UserError when the camera has no scan.
NlosCapture nlosCaptureGeometry(const Scene& scene, const TimeBins& tb);

// The name `tpb render` writes it under, beside the frames.
inline constexpr const char* kCaptureH5Name = "capture.h5";

}  // namespace tpb
