// The whole transient volume for Python/NumPy: .npy arrays (io/npy.h) and a JSON side file that
// says what they hold. In a folder:
//   transient.npy  float32 (H, W, bins, 3): the frames' values (film_view.h frameImage, bin k of
//                  pixel (x, y) at [y, x, k]), on the time axis and emission mode of ExportOptions
//   steady.npy     float32 (H, W, 3): the steady-state image (all time, also before/after the film)
//   before.npy     float32 (H, W, 3): light that arrived before the film's first bin, on that axis
//   after.npy      float32 (H, W, 3): light that arrived after its last bin, on that axis
//   transient.json the time axis (start, bin width in m of optical path and ns, axis, emission),
//                  the energy before/inside/after the film, the render that made it
//                  (docs/user/outputs.md lists every field)
// transient.npy is streamed row by row (one row of W x bins x 3 floats in memory, never a second
// copy of the film); each file is atomic (tmp + rename), the side file is written last.
#pragma once
#include "io/record.h"
#include "film/film_export.h"

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace tpb {

// The render a volume came from, as written in transient.json (the caller fills it from its
// settings; core/render/provenance.h does it from a Driver).
struct VolumeProvenance {
    std::string scene;                             // scene file
    Record settings;                               // settingsRecord (integrators/render_settings.h)
    double beamRadius = 0.0, surfaceRadius = 0.0;  // m, the last pass's (0: none yet)
};

// The file names a volume export writes, in the order it writes them (transient.json last).
std::vector<std::string> volumeFileNames();

// Writes the files above into `dir` (created if needed) from one snapshot. progress(rows, H)
// after each row of transient.npy; a set `cancel` stops between rows and leaves transient.npy and
// transient.json unwritten (the smaller images already written stay). Returns the names written.
std::vector<std::string> exportVolumeNpy(const FilmSnapshot& film, const std::string& dir, const ExportOptions& opt,
                                         const VolumeProvenance& render,
                                         const std::function<void(int, int)>& progress = {},
                                         const std::atomic<bool>* cancel = nullptr);

// The phasor film (film/phasor.h), when the film has one, on ExportOptions' time axis and with its
// pulse and sensor response (their transforms):
//   phasor.npy      float32 (H, W, F, 2): the luminance's phasor, [..., 0] real, [..., 1] imaginary
//                   (mitransient's phasor_hdr_film shape and sign, exp(-i 2 pi f (opl - start)))
//   phasor_rgb.npy  float32 (H, W, F, 2, 3): per colour channel
//   phasor.json     the frequencies (cycles per m of OPL, GHz, wavelengths), the reference OPL,
//                   the axis and response, the render (docs/user/phasor.md)
// Returns the names written (none without a phasor film).
std::vector<std::string> exportPhasorNpy(const FilmSnapshot& film, const std::string& dir, const ExportOptions& opt,
                                         const VolumeProvenance& render);
std::vector<std::string> phasorFileNames();

// The side file's JSON text (exposed for the tests): `beforeRgb`/`afterRgb`/`steadyRgb` are the
// images' sums over the pixels.
std::string volumeSideJson(const FilmSnapshot& film, const ExportOptions& opt, const VolumeProvenance& render,
                           const double beforeRgb[3], const double afterRgb[3], const double steadyRgb[3]);

}  // namespace tpb
