// Writing the transient film to disk: frames (one EXR per time bin), the steady-state image, the
// streak image of a row, and a pixel's time profile as CSV. Each file is written atomically
// (image_io.h). Used by `tpb render` and by the viewer's export buttons. Everything is read from
// one snapshot (film_snapshot.h), so the files of one export show the same passes while the render
// goes on (the snapshot keeps the blocks it shows alive until the export returns).
#pragma once
#include "film/film_snapshot.h"
#include "film/tone_map.h"
#include "film/time_response.h"
#include "film/time_axis.h"
#include "io/image_io.h"

#include <atomic>
#include <functional>
#include <string>

namespace tpb {

struct ExportOptions {
    TimeAxis axis = TimeAxis::Real;
    EmissionMode mode = EmissionMode::Delta;
    TimeResponse response;  // pulse shape and sensor response (time_response.h); default: delta, ideal
    ExrPixel pixel = ExrPixel::Float;
    int firstBin = 0, lastBin = -1, step = 1;  // lastBin -1 = last bin of the film
};

// Writes <dir>/frame_<bin>.exr for the selected bins; progress(done, total) after each file.
// Returns the number of frames written (stops early if `cancel` is set).
int exportFrames(const FilmSnapshot& film, const std::string& dir, const ExportOptions& opt,
                 const std::function<void(int, int)>& progress = {}, const std::atomic<bool>* cancel = nullptr);
void exportFrame(const FilmSnapshot& film, int bin, const std::string& path, const ExportOptions& opt);
void exportSteady(const FilmSnapshot& film, const std::string& path, ExrPixel pixel = ExrPixel::Float);
// Streak image: x horizontally, time (bins) vertically, for image row `row`.
void exportStreak(const FilmSnapshot& film, int row, const std::string& path, const ExportOptions& opt);
// "bin,t_opl_m,t_ns,r,g,b" rows.
void exportProfileCsv(const FilmSnapshot& film, int x, int y, const std::string& path, const ExportOptions& opt);

// How many frames exportFrames writes for a film of `bins` bins with these options.
int exportFrameCount(int bins, const ExportOptions& opt);

// `count` bins (clamped to [1, bins]) evenly spaced over the part of the time axis that carries the
// energy: from the 0.5% to the 90% quantile of the delta arrival times summed over the image (the
// whole film when it is black). strip.png and the contact sheet (picture_export.h) show these.
std::vector<int> energeticBins(const FilmSnapshot& film, int count, TimeAxis axis);

// A PNG strip of `count` frames side by side, for a quick look or a README: evenly spaced over the
// part of the time axis that carries the energy (0.5% to 90% of the arrival times), mapped by
// `tone` (tone_map.h; tpb render passes picture_export.h's autoExposedToneMap, the exposure rule of
// every picture). Returns the bins used.
std::vector<int> exportStripPng(const FilmSnapshot& film, const std::string& path, int count, const ExportOptions& opt,
                                const ToneMap& tone);

}  // namespace tpb
