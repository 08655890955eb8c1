// Pictures of the transient film for people: an MP4 of the frames and a PNG contact sheet of a
// few frames in a grid, each labelled with its time. Both are tone-mapped on the CPU
// (tone_map.h: exposure, sRGB, false colour, the viewer's mapping) from one snapshot; the MP4 is
// encoded by ffmpeg (io/video_encoder.h). Used by `tpb render --mp4 / --contact-sheet` and the
// viewer's export buttons.
#pragma once
#include "film/film_export.h"
#include "film/tone_map.h"

#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace tpb {

// The one exposure rule of every picture tpb writes (docs/user/commands.md "Pictures and their exposure"): the
// automatic exposure fitExposure (the 99th percentile of the lit pixels' luminance maps to 1) of
// the picture's reference image, plus the user's extra EV (`base.exposureEv`). The reference image
// of a single picture (steady.png, preview.png) is the picture itself; of a set of frames
// (strip.png, contact_sheet.png, transient.mp4) the film's brightest frame, so that every frame of
// the set has one exposure (no flicker, frames comparable). A black image gets the extra EV only.

// `base` with its exposure raised by the automatic exposure (fitExposure) of the film's brightest
// frame on opt's axis and emission: the delta frame of peak energy, or the last continuous frame
// (the running sum only grows).
ToneMap autoExposedToneMap(const FilmSnapshot& film, const ExportOptions& opt, ToneMap base);
// Writes one image (3 floats per pixel) as a PNG auto-exposed by the rule above; returns the EV
// applied (the fit plus base.exposureEv).
float writeAutoExposedPng(const std::string& path, int width, int height, const std::vector<float>& rgb, ToneMap base);

// Encodes the frames exportFrames would write (opt's bins, axis, emission) at `fps` into `path`.
// progress(done, total) after each frame; a set `cancel` stops, kills ffmpeg and leaves no file
// (returns 0). Returns the frames encoded. Throws UserError (ffmpeg missing or failing).
int exportMp4(const FilmSnapshot& film, const std::string& path, const ExportOptions& opt, const ToneMap& tone,
              double fps, const std::function<void(int, int)>& progress = {},
              const std::atomic<bool>* cancel = nullptr);

// The contact sheet: `count` frames (clamped to the bins) over the part of the time axis that
// carries the energy (energeticBins, as strip.png), in a grid of ceil(sqrt(count)) columns, each
// with its bin centre's time in ns below it. Cells are separated and framed by kSheetGap pixels.
struct ContactSheet {
    static constexpr int kSheetGap = 2;
    int width = 0, height = 0, columns = 0, rows = 0;
    int cellWidth = 0, cellHeight = 0;  // frame (or label, if wider) x frame + label bar
    std::vector<unsigned char> rgb;     // width*height*3, top row first
    std::vector<int> bins;              // the frames, in reading order
    std::vector<int> frameX, frameY;    // where each frame's top-left pixel is
    std::vector<std::string> labels;
};
ContactSheet makeContactSheet(const FilmSnapshot& film, int count, const ExportOptions& opt, const ToneMap& tone);
// Writes makeContactSheet(...) as a PNG; returns the bins shown.
std::vector<int> exportContactSheet(const FilmSnapshot& film, const std::string& path, int count,
                                    const ExportOptions& opt, const ToneMap& tone);

}  // namespace tpb
