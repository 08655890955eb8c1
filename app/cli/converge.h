// `tpb converge` (error against run time), `tpb reference` (reference volumes, core/eval/reference.h)
// and the path-tracer back end of `tpb render --method pt`.
#pragma once
#include "cli/common.h"
#include "film/film_export.h"

#include <string>

namespace tpb::app {

// What `tpb render` asks of the path tracer: the same outputs as the beam renderer.
struct PathTracedRenderRequest : RenderOutputs {
    int spp = 1;  // camera paths per pixel per pass
};

// Checks what renderPathTraced will check, before anything is written (UserError).
void checkPathTracedRequest(const PreparedRender& prepared, const PathTracedRenderRequest& req);

// Renders with the unbiased path tracer (core/integrators/path_tracer.h): passes and time budget from prepared.settings,
// each `spp` paths per pixel, until --time if given; writes steady.exr/.png, frames/, strip.png and
// summary.json ("method": "pt") into req.out. The first Ctrl-C or SIGTERM abandons the pass in
// progress and writes the finished ones; a second quits (cli_interrupt.h). The caller holds an
// InterruptScope and has claimed req.out (OutputFolder).
void renderPathTraced(const PreparedRender& prepared, const PathTracedRenderRequest& req);

}  // namespace tpb::app
