// Pulse shapes and sensor responses (issue 16). Real sources are not delta pulses and real sensors
// (SPADs, streak cameras) blur time. Transport is linear and time-invariant, so the film for a
// pulse p(t) seen by a sensor of impulse response s(t) is the delta-pulse film convolved along
// time with h = p * s. It is computed when the film is read (film_view.h), like continuous
// emission: no re-render, changed instantly in the viewer.
//
// Shapes (t = 0 is the instant the scene's lights emit; widths in m of OPL here, ns on the CLI and
// in the viewer):
//   pulse  delta                 p = delta(t)
//          gaussian FWHM         p = N(0, sigma^2), sigma = FWHM / (2 sqrt(2 ln 2)): centred on t = 0
//          square WIDTH          p = 1/WIDTH on [0, WIDTH): the light on for WIDTH from t = 0
//   sensor ideal                 s = delta(t)
//          gaussian FWHM         s = N(0, sigma^2): timing jitter, centred
//          exponential TAU       s = exp(-t/TAU)/TAU for t >= 0: a detector's decay
//
// On the film's bins. Bin k holds X_k, the delta response integrated over [kD, (k+1)D) (D the bin
// width). Within a bin the response is taken as uniform (the film knows no finer time). Then the
// blurred film's bin k is Y_k = sum_m W_m X_(k-m), with
//   W_m = (1/D) [G((m+1)D) - 2 G(mD) + G((m-1)D)],   G(t) = integral_{-inf}^{t} H(u) du,
// where H is h's cumulative distribution. W is h smoothed by the triangle of half-width D, so
// sum_m W_m = 1: the energy is kept, except the part moved past the film's ends. The sensor's G has
// a closed form: ideal max(t, 0); gaussian t Phi(t/sigma) + sigma phi(t/sigma); exponential
// t - TAU (1 - exp(-t/TAU)) for t >= 0, else 0. The pulse is integrated numerically,
// G_h(t) = integral p(u) G_s(t - u) du: composite 5-point Gauss-Legendre with the kinks on panel
// edges. Tests check it against the closed forms, and a blurred single-scattering film against
// quadrature renders of the emission times the pulse spreads over (tests/film/test_time_response.cpp).
//
// Continuous emission (the step response) blurred: Y_k = sum_m W_m C_(k-m), C the running sum. C
// is taken as the light that arrived before the film for k < 0, and as its last value past the end.
//
// The photon-counting detector (photon_counting.h) rides along: it is applied after the kernel.
#pragma once
#include "film/photon_counting.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tpb {

enum class PulseShape { Delta, Gaussian, Square };
enum class SensorShape { Ideal, Gaussian, Exponential };

struct TimeResponse {
    PulseShape pulse = PulseShape::Delta;
    double pulseWidth = 0.0;  // m of OPL: Gaussian FWHM, square width
    SensorShape sensor = SensorShape::Ideal;
    double sensorWidth = 0.0;  // m of OPL: Gaussian FWHM, exponential decay time
    PhotonCounting counting;   // the film read as counts (photon_counting.h); off by default
    // The kernel is the identity (delta pulse, ideal sensor); identity(): and no counting either.
    bool kernelIdentity() const { return pulse == PulseShape::Delta && sensor == SensorShape::Ideal; }
    bool identity() const { return kernelIdentity() && !counting.enabled; }
    bool operator==(const TimeResponse&) const = default;
};

// "delta" | "gaussian:FWHM_NS" | "square:WIDTH_NS" (ns, > 0); nullopt otherwise.
std::optional<TimeResponse> parsePulse(std::string_view s, TimeResponse base = {});
// "ideal" | "gaussian:FWHM_NS" | "exp:TAU_NS" (ns, > 0); nullopt otherwise.
std::optional<TimeResponse> parseSensor(std::string_view s, TimeResponse base = {});
std::string pulseName(const TimeResponse& r);   // the inverse: "gaussian:0.1" (ns)
std::string sensorName(const TimeResponse& r);  // "exp:0.05" (ns)
// For people: "gaussian pulse, FWHM 0.1 ns; ideal sensor" (+ "; Poisson counts, ..." when counting).
std::string describe(const TimeResponse& r);

// The weights of Y_k = sum_{i} w[i] X_(k - (lo + i)) + before * X_(before the film) + after * X_(past
// the end). A film of B bins reads only the weights W_m with |m| < B: a longer kernel is cut to
// them, and the weights of the light that lies before (m >= B) or past (m <= -B) the film for every
// bin are summed into `before` and `after` (from G in closed form: sum_{m>=M} W_m = 1 - F(M),
// sum_{m<M} W_m = F(M), F(M) = [G(MD) - G((M-1)D)] / D). They multiply the extensions (0 for delta
// emission), so a cut kernel reads the film as the whole one does, in O(B) per value.
struct BinKernel {
    int lo = 0;
    std::vector<double> w{1.0};
    double before = 0.0, after = 0.0;
    bool identity() const { return lo == 0 && w.size() == 1 && w[0] == 1.0 && before == 0.0 && after == 0.0; }
};
// Why a limit: each weight is a second difference of G, which grows like the response's width w
// while W_m ~ D/w, so G's rounding (1e-16 relative) costs each weight about 1e-16 (w/D)^2: up to
// ~1e-6 at a span of 2^20 bins, the whole weight beyond ~2^30 (and the kernel's time and memory
// grow with w/D).
// binKernel refuses a wider span (std::invalid_argument); `tpb render` and `tpb view` check it with
// responseSpanBins once the film's time axis is known, before any pass.
inline constexpr double kMaxResponseBins = 1 << 20;
// The span of h = p * s that the kernel covers (both shapes' reach), in bins of width binWidth.
double responseSpanBins(const TimeResponse& r, double binWidth);
// The kernel for bins of width binWidth, cut to a film of filmBins bins (0: the whole support).
BinKernel binKernel(const TimeResponse& r, double binWidth, int filmBins = 0);
// binKernel, computed once per (response, bin width, film bins) and shared: the film readers
// (film_view.h) ask for it on every frame, profile and streak (an export of N frames, the viewer's
// every step), and each weight of a pulse costs a quadrature of G (up to 1280 evaluations).
// Thread-safe; keeps the last few kernels.
std::shared_ptr<const BinKernel> sharedBinKernel(const TimeResponse& r, double binWidth, int filmBins);
// How many kernels binKernel has computed in this process (for the tests of the cache).
uint64_t binKernelComputations();
// G of the combined h at t (m of OPL), as above; exposed for the tests.
double responseG(const TimeResponse& r, double t);

// Applies the kernel to one RGB series of `bins` values (x[k*3 + c]); `left`/`right` (3 values
// each) extend it before the first and after the last bin (0 for delta emission; before-film and
// last value for continuous). out may not alias x.
void applyKernel(const BinKernel& k, const double* x, int bins, const double* left, const double* right, double* out);

}  // namespace tpb
