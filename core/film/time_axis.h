// The film's time axis and the ways it is read: the bins (TimeBins, m of optical path length),
// delta or continuous emission, the exact or uniform profile of an estimate, and the optional
// progressive time kernel. The scene file's render block (scene/scene_desc.h) and the estimators
// name these; the film (transient_film.h) and the splat (time_splat.h, time_kernel.h) read them.
#pragma once
#include "base/math.h"

#include <cmath>
#include <optional>
#include <string>
#include <string_view>

namespace tpb {

struct TimeBins {
    double startOpl = 0.0;   // m
    double binWidth = 0.01;  // m
    int bins = 1;
    double endOpl() const { return startOpl + binWidth * bins; }
    // Bin of time t, or -1 before the film / bins after it (clamped, no integer overflow).
    TPB_HOT_INLINE int binOf(double t) const {
        const double k = std::floor((t - startOpl) / binWidth);
        if (!(k >= 0.0)) return -1;
        if (k >= static_cast<double>(bins)) return bins;
        return static_cast<int>(k);
    }
    // binOf(t) with a multiplication by invWidth = 1 / binWidth instead of the division (the splat
    // calls it four times per estimate), always the same answer: q = (t - start) invWidth is within
    // 3.4e-16 |q| of the division's quotient (three roundings), so when q lies farther than
    // 1e-15 (1 + |q|) from every integer both have the same floor; otherwise (q within rounding of
    // a bin boundary, huge, NaN or infinite) it divides (TimeSplat.BinByReciprocalIsTheBinByDivision in
    // tests/estimators/test_beam2d.cpp).
    TPB_HOT_INLINE int binOf(double t, double invWidth) const {
        const double q = (t - startOpl) * invWidth;
        const double k = std::floor(q);
        const double f = q - k, tol = 1e-15 * (1.0 + std::abs(q));
        if (!(f > tol && f < 1.0 - tol)) return binOf(t);
        if (k < 0.0) return -1;
        if (k >= static_cast<double>(bins)) return bins;
        return static_cast<int>(k);
    }
};

enum class EmissionMode { Delta, Continuous };
enum class TimeProfile { Exact, Uniform };

// The optional progressive time kernel of the photon-beams estimators (issue 14): every estimate's
// time profile is smoothed along time by a kernel whose width shrinks pass after pass with the
// spatial radius (docs/theory/derivations.md: the rates). Box: the only kind so far.
enum class TimeKernelKind { None, Box };
struct TimeKernelSettings {
    TimeKernelKind kind = TimeKernelKind::None;
    double width = 0.0;  // m of OPL, full width of pass 1's kernel; 0 = chosen from the scene
    bool operator==(const TimeKernelSettings&) const = default;
};

// The time kernel as the CLI and the viewer write it: "none" | "box" (width from the scene) |
// "box:WIDTH" (WIDTH m of OPL, > 0). nullopt for anything else.
std::optional<TimeKernelSettings> parseTimeKernel(std::string_view s);
std::string timeKernelName(const TimeKernelSettings& k);  // the inverse: "none", "box", "box:0.05"

}  // namespace tpb
