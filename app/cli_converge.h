// `tpb converge` (error against run time), `tpb reference` (reference volumes, core/reference.h)
// and the path-tracer back end of `tpb render --method pt`.
#pragma once
#include "cli_common.h"
#include "film_export.h"

#include <string>

namespace tpb::app {

// What `tpb render` asks of the path tracer: the same outputs as the beam renderer.
struct PathTracedRenderRequest : RenderOutputs {
    int spp = 1;  // camera paths per pixel per pass
};

// Renders with the unbiased path tracer (core/path_tracer.h): passes = --passes (or the scene's),
// each `spp` paths per pixel, until --time if given; writes steady.exr/.png, frames/, strip.png and
// summary.json ("method": "pt") into req.out. First Ctrl-C: stop and write; second: quit.
void renderPathTraced(const Scene& scene, const RenderOverrides& ov, const PathTracedRenderRequest& req);

}  // namespace tpb::app
