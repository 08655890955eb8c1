// The images read from a film snapshot (film_snapshot.h): a time bin's frame (delta or continuous
// emission), the steady-state image, the light that arrived before / after the film, a pixel's time
// profile, a row's streak image, the whole volume, and the energy per bin. Every value is an
// average: a tile's sums divided by the passes that tile has completed (0 for a tile with none).
//
// Continuous emission (light on from the pulse instant) is the step response, see transient_film.h:
// frame k = before + bins 0..k. frame() reads it from the block's prefix sums
// (TileBlock::cumulative): one read per pixel, plus O(bins x pixels) once per tile block and axis
// on the first continuous read of that block. pixelProfile, streak and volume read every bin anyway
// and keep a running sum (the same additions in the same order, so the same values).
#pragma once
#include "film/film_snapshot.h"
#include "film/time_response.h"
#include "film/time_axis.h"

#include <vector>

namespace tpb {

// `response` (time_response.h): the pulse shape and sensor response the film is seen with; the
// default (delta pulse, ideal sensor) reads the sums as they are, bit for bit as before. With
// response.counting on, every read is the counted film (photon_counting.h): r = g = b = counts per
// bin, the scale from the steady image's mean luminance; the steady, before and after images stay
// noise-free (they are not time-resolved counts).
//
// W*H*3, row-major. `bin` is clamped to the film.
std::vector<float> frameImage(const FilmSnapshot& s, int bin, TimeAxis axis, EmissionMode mode,
                              const TimeResponse& response = {});
std::vector<float> steadyImage(const FilmSnapshot& s);
std::vector<float> beforeImage(const FilmSnapshot& s, TimeAxis axis);
std::vector<float> afterImage(const FilmSnapshot& s, TimeAxis axis);
// bins*3; zeros for a pixel outside the film.
std::vector<float> pixelProfile(const FilmSnapshot& s, int x, int y, TimeAxis axis, EmissionMode mode,
                                const TimeResponse& response = {});
// Streak image of image row `row`: bins rows x W columns x 3; zeros for a row outside the film.
std::vector<float> streakImage(const FilmSnapshot& s, int row, TimeAxis axis, EmissionMode mode,
                               const TimeResponse& response = {});
// Whole volume (W*H*bins*3, pixel-major: ((y*W + x)*bins + k)*3), in double.
std::vector<double> volume(const FilmSnapshot& s, TimeAxis axis, EmissionMode mode, const TimeResponse& response = {});
// Luminance (base/math.h) summed over the image, per bin of the delta frames (bins values).
// stride > 1: over the pixels (x, y) with x and y multiples of stride only (1 / stride^2 of the
// film's memory read: the viewer's choice of the brightest bin, which runs while the film renders
// and holds a snapshot as long as it reads).
std::vector<double> binEnergy(const FilmSnapshot& s, TimeAxis axis, int stride = 1);
// The phasor film's average (film/phasor.h), W*H*F*2*3: [y][x][frequency][Re, Im][rgb], in double;
// empty when the film has none. The pulse and sensor response multiply it by their transforms
// (TimeResponse::transform); the default leaves it as it is.
std::vector<double> phasorVolume(const FilmSnapshot& s, TimeAxis axis, const TimeResponse& response = {});

}  // namespace tpb
