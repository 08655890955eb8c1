// The names of the files an export writes: one place for `tpb render` and the viewer. `tpb render`
// writes one time axis and emission per folder, so its names carry no tag ("transient.mp4"); the
// viewer exports any mix into one folder, so each of its names carries outputTag()
// ("transient_real_delta.mp4"). Every name is relative to the export's folder.
#pragma once
#include "film/film_snapshot.h"
#include "film/time_axis.h"
#include "film/time_response.h"

#include <string>

namespace tpb {

// "real_delta", "unwarped_continuous", ...; a pulse shape or sensor response other than
// delta/ideal adds e.g. "_pulse-gaussian0.5_sensor-exp0.1" (ns); photon counts add "_counts".
std::string outputTag(TimeAxis axis, EmissionMode mode, const TimeResponse& r = {});

// With an empty tag: the untagged name (in brackets below).
std::string frameName(int bin, const std::string& tag = "");         // frame_00012[_TAG].exr
std::string framesDirName(const std::string& tag);                   // frames_TAG
std::string streakName(int row, const std::string& tag = "");        // streak_row0031[_TAG].exr
std::string profileName(int x, int y, const std::string& tag = "");  // profile_x12_y40[_TAG].csv
std::string volumeDirName(const std::string& tag);                   // volume_TAG
std::string mp4Name(const std::string& tag = "");                    // transient[_TAG].mp4
std::string contactSheetName(const std::string& tag = "");           // contact_sheet[_TAG].png

// The untagged files of `tpb render`'s folder (and the viewer's steady export).
inline constexpr const char* kSteadyExrName = "steady.exr";
inline constexpr const char* kSteadyPngName = "steady.png";
inline constexpr const char* kPreviewExrName = "preview.exr";
inline constexpr const char* kPreviewPngName = "preview.png";
inline constexpr const char* kStripName = "strip.png";
inline constexpr const char* kSummaryName = "summary.json";

}  // namespace tpb
