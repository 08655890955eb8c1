// Photon counting (issue 36): the film read as a SPAD's time-correlated photon counts, applied when
// the film is read, after the pulse shape and sensor response (time_response.h): no re-render,
// instant in the viewer. The model and its limits: docs/theory/photon-counting.md.
//
// A SPAD counts photons of every colour alike: it sees the luminance Y of the film (base/math.h)
// and the counted film is grey, r = g = b = counts per bin.
//
// Per pixel and bin k (D the bin width in s, N the laser cycles of the acquisition):
//   signal      lam_sig,k = s Y_k,  s = efficiency * photons / Ybar,  Ybar the steady image's mean
//               luminance over the pixels: a pixel of mean brightness expects `photons` arriving
//               photons over the whole time axis (efficiency * photons detected)
//   background  lam_bg = (dark_hz + ambient_hz) D N          (both detected rates per pixel)
//   afterpulses lam_ap,k = p sum_m A_m lam_tot,(k-m): a detection triggers one more with probability
//               p after an exponential delay (afterpulse_ns); A_m its share in the m-th bin on,
//               cascades included in the mean (ideal mode only: with pile-up they fall in the dead time)
//   ideal       C_k ~ Poisson(lam_k), independent per bin (no dead time)
//   pileup      first photon per cycle (dead time longer than the histogram window, re-armed by the
//               next pulse): C_k ~ Binomial(N - sum_{j<k} C_j, 1 - exp(-lam_k / N)), the conditional
//               form of the multinomial over the bins and "no detection"
//   coates      the piled-up histogram corrected: lam^_k = -N ln(1 - C_k / (N - sum_{j<k} C_j)),
//               expected counts per bin without pile-up (signal + background)
// Random numbers are keyed on (seed, pixel, bin) (base/rng.h, Stream::Counts): a frame, profile or
// volume shows the same counts whoever reads it.
#pragma once
#include <cstdint>
#include <string>
#include <string_view>

namespace tpb {

class Rng;

struct PhotonCounting {
    bool enabled = false;
    double photons = 1e4;        // arriving signal photons at a mean pixel, whole time axis (> 0)
    double efficiency = 1.0;     // detection efficiency (0, 1]
    double darkHz = 0.0;         // dark count rate, Hz (>= 0)
    double ambientHz = 0.0;      // detected ambient photon rate, Hz (>= 0)
    double cycles = 1e6;         // laser cycles (pulses) in the acquisition (>= 1)
    double afterpulse = 0.0;     // afterpulse probability per detection [0, 1)
    double afterpulseNs = 10.0;  // afterpulse delay time constant, ns (> 0)
    bool pileup = false;         // first-photon TCSPC counting (else ideal, no dead time)
    bool coates = false;         // Coates-corrected output (needs pileup)
    uint64_t seed = 1;
    bool operator==(const PhotonCounting&) const = default;
};

// "off" | comma-separated "photons=P,efficiency=E,dark_hz=R,ambient_hz=R,cycles=N,afterpulse=P,
// afterpulse_ns=T,pileup,coates,seed=S" (any subset, the rest default). Throws UserError naming
// `what` (the flag or file:line:key), the bad item and the fix.
PhotonCounting parseCounting(std::string_view s, const std::string& what = "--counts");
// The inverse ("off", or every parameter), and for people ("Poisson counts, 1e4 photons/pixel, ...").
std::string countingName(const PhotonCounting& m);
std::string describeCounting(const PhotonCounting& m);

// What a read needs besides the pixel's series: counts per unit of luminance, background per bin.
struct CountScale {
    double perLuminance = 0.0;  // s above
    double background = 0.0;    // lam_bg, counts per bin
    double binSeconds = 0.0;    // D
};
// meanSteadyLuminance: Ybar; binWidthOpl: the film's bin width, m of OPL.
CountScale countScale(const PhotonCounting& m, double meanSteadyLuminance, double binWidthOpl);

// Counts of one pixel: y (bins luminance values, the noise-free film as read) -> out[first..last]
// (counts, or the Coates estimate). Bins before `first` are not written; pile-up still samples them.
// `pixel` keys the random numbers (the film's y * width + x).
void countPixel(const PhotonCounting& m, const CountScale& scale, uint64_t pixel, const double* y, int bins, int first,
                int last, double* out);
// The expected counts per bin before sampling (ideal: the Poisson means; pileup: the per-acquisition
// means lam_k whose hazards the binomials use). For the tests and the theory page.
void expectedCounts(const PhotonCounting& m, const CountScale& scale, const double* y, int bins, double* lam);
// Coates (1968): lam^ from a piled-up histogram of `cycles` cycles (a count equal to the cycles
// left gives -N ln(1 / (2 C)): half a cycle taken as unseen).
void coatesCorrection(const double* counts, int bins, double cycles, double* lamHat);

// Exact samplers (Knuth, TAOCP 3.4.1: Poisson and binomial reduced by gamma and beta variates to
// small cases), for any mean; exposed for the tests.
double samplePoisson(Rng& rng, double mean);
double sampleBinomial(Rng& rng, double n, double p);

}  // namespace tpb
