// summary.json (nlohmann): the fields every summary starts with, the film's time axis, the writer of
// a render's outputs (steady images, summary, frames, strip).
#pragma once
#include "cli/common.h"

#include <nlohmann/json.hpp>

#include <functional>

namespace tpb::app {

// The film's time axis as written in summary.json and reference headers.
nlohmann::json filmJson(const TimeBins& time);
// Fields every summary.json starts with (scene, method, passes, wall time, resolution, film, frames,
// film_energy: the shares of the energy before / inside / after the film per axis, rejected
// samples and overflowed pixel sums).
nlohmann::json summaryHeader(const PreparedRender& p, const char* method, size_t passes, double wallSec,
                             const TransientFilm& film, const ExportOptions& opt);

// Replaces every non-finite number in `j` by the string "inf", "-inf" or "nan" (JSON has no such
// numbers and nlohmann would write null, which reads as "unknown"); returns how many it replaced.
int64_t replaceNonFiniteNumbers(nlohmann::json& j);

// Writes steady.exr and steady.png, summary.json, frames/ and strip.png, in that order (small and
// most valuable first), then summary.json again with the final "outputs" record. `summary()` gives
// summary.json's content; "outputs" (frames expected/written, kept files, error) is added here.
// A failure writing frames or the strip (full disk...) keeps every complete file, records it in
// summary.json if it still fits, prints the error and what was kept, and sets the exit code to 2.
// A failure writing steady.exr/.png or the first summary.json is thrown as UserError. A first
// Ctrl-C/SIGTERM during the frame export stops it after the frame in progress (recorded the same
// way; exit code 128 + the signal).
OutputReport writeRenderOutputs(const TransientFilm& film, const RenderOutputs& r,
                                const std::function<nlohmann::json()>& summary);

}  // namespace tpb::app
