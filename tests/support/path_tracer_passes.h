// Path-tracer passes into a test's own film, run through the Driver (Method::PathTracer) as every
// render is: the Driver's film of those passes is merged into `film` (TransientFilm::merge), and
// the passes' PathTracerStats are summed into `stats`.
#pragma once
#include "integrators/path_tracer.h"
#include "render/driver.h"

namespace tpb::test {

inline int64_t renderPathTracer(const Scene& scene, RenderSettings s, uint64_t firstPass, int64_t passes,
                                TransientFilm& film, PathTracerStats* stats = nullptr) {
    s.method = Method::PathTracer;
    Driver drv(scene, s, film.time());
    int64_t done = 0;
    for (int64_t i = 0; i < passes; ++i, ++done)
        if (!drv.runPass(firstPass + static_cast<uint64_t>(i))) break;
    film.merge(drv.film());
    if (stats)
        for (const PassStats& p : drv.history()) *stats += p.paths;
    return done;
}

inline void renderPathTracerPass(const Scene& scene, const RenderSettings& s, uint64_t pass, TransientFilm& film,
                                 PathTracerStats* stats = nullptr) {
    renderPathTracer(scene, s, pass, 1, film, stats);
}

}  // namespace tpb::test
