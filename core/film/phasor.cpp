#include "film/phasor.h"

#include "base/error.h"

#include <algorithm>
#include <cstdlib>
#include <sstream>

namespace tpb {

namespace {

void addPlain(const PhasorSpec& spec, const Color& energy, const SegmentProfile& p, double a, double b, double* out) {
    if (isBlack(energy)) return;
    const int n = spec.count();
    for (int i = 0; i < n; ++i) {
        const double f = spec.frequencies[static_cast<size_t>(i)];
        double* o = out + static_cast<size_t>(i) * 6;
        const Complex cx = profilePhasor(p.x, a, b, f, spec.refOpl);
        const Complex cy = p.grey ? cx : profilePhasor(p.y, a, b, f, spec.refOpl);
        const Complex cz = p.grey ? cx : profilePhasor(p.z, a, b, f, spec.refOpl);
        o[0] += energy.x * cx.real();
        o[1] += energy.y * cy.real();
        o[2] += energy.z * cz.real();
        o[3] += energy.x * cx.imag();
        o[4] += energy.y * cy.imag();
        o[5] += energy.z * cz.imag();
    }
}

}  // namespace

// The floor's split is the bins' (time_splat.h flooredPieces); an instant is an interval of zero
// width (the transform needs no bin-relative threshold).
void addEstimatePhasor(const PhasorSpec& spec, const Color& energy, const SegmentProfile& p, double a, double b,
                       double floor, double* out) {
    flooredPieces(p, a, b, floor, 0.0, [&](const Color& share, const SegmentProfile& q, double qa, double qb) {
        addPlain(spec, energy * share, q, qa, qb, out);
    });
}

Complex responseTransform(const TimeResponse& r, double f) {
    const double w = 2.0 * kPi * f;
    const double fwhmToSigma = 1.0 / (2.0 * std::sqrt(2.0 * std::log(2.0)));
    Complex h(1.0, 0.0);
    if (r.pulse == PulseShape::Gaussian) {
        const double sigma = r.pulseWidth * fwhmToSigma;
        h *= std::exp(-0.5 * (w * sigma) * (w * sigma));
    } else if (r.pulse == PulseShape::Square) {
        h *= phasorPhi(0.0, w * r.pulseWidth);
    }
    if (r.sensor == SensorShape::Gaussian) {
        const double sigma = r.sensorWidth * fwhmToSigma;
        h *= std::exp(-0.5 * (w * sigma) * (w * sigma));
    } else if (r.sensor == SensorShape::Exponential) {
        h *= 1.0 / Complex(1.0, w * r.sensorWidth);
    }
    return h;
}

namespace {

std::vector<double> numberList(const std::string& text, const std::string& what) {
    std::vector<double> v;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        char* end = nullptr;
        const double x = std::strtod(item.c_str(), &end);
        if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(x))
            throw UserError(what + " \"" + text + "\": \"" + item +
                            "\" is not a number; write frequencies as F1,F2,... (cycles per m of OPL), "
                            "wavelengths as wl:WL1,WL2,... (m) or a band as band:MEAN:SIGMA (m)");
        v.push_back(x);
    }
    if (v.empty()) throw UserError(what + " \"" + text + "\": no frequency given");
    return v;
}

}  // namespace

std::vector<double> parsePhasorFrequencies(const std::string& text, int bins, double binWidth,
                                           const std::string& what) {
    constexpr double kMaxFrequency = 1e6;  // cycles per m: a 1 um period of OPL
    std::vector<double> f;
    if (text.rfind("band:", 0) == 0) {
        const std::string rest = text.substr(5);
        const size_t colon = rest.find(':');
        if (colon == std::string::npos)
            throw UserError(what + " \"" + text + "\": write the band as band:MEAN:SIGMA (wavelengths in m of OPL)");
        const std::vector<double> mean = numberList(rest.substr(0, colon), what);
        const std::vector<double> sigma = numberList(rest.substr(colon + 1), what);
        if (mean.size() != 1 || sigma.size() != 1 || !(mean[0] > 0.0) || !(sigma[0] > 0.0))
            throw UserError(what + " \"" + text + "\": MEAN and SIGMA must be one wavelength each, > 0 (m of OPL)");
        // mitransient's phasor_hdr_film: FFT indices within mean +- 3 sigma, in units of 1 / (N dt).
        const double range = static_cast<double>(bins) * binWidth;
        const double meanIdx = range / mean[0], sigmaIdx = range / (6.0 * sigma[0]);
        const long lo = std::max(0L, static_cast<long>(std::floor(meanIdx - 3.0 * sigmaIdx)));
        const long hi = std::min(static_cast<long>(bins / 2), static_cast<long>(std::ceil(meanIdx + 3.0 * sigmaIdx)));
        if (hi < lo)
            throw UserError(what + " \"" + text + "\": the band (around " + shortNumber(1.0 / mean[0]) +
                            " cycles/m) lies above the film's Nyquist frequency 1 / (2 bin width) = " +
                            shortNumber(0.5 / binWidth) +
                            " cycles/m, where its FFT grid ends; choose a longer MEAN wavelength, or list the "
                            "frequencies themselves (the phasor film takes any frequency exactly)");
        for (long k = lo; k <= hi; ++k) f.push_back(static_cast<double>(k) / range);
    } else if (text.rfind("wl:", 0) == 0) {
        for (double wl : numberList(text.substr(3), what)) {
            if (!(wl > 0.0))
                throw UserError(what + " \"" + text + "\": wavelength " + shortNumber(wl) +
                                " m must be > 0 (m of OPL)");
            f.push_back(1.0 / wl);
        }
    } else {
        f = numberList(text, what);
    }
    for (double x : f) {
        if (!(x >= 0.0))
            throw UserError(what + " \"" + text + "\": frequency " + shortNumber(x) +
                            " must be >= 0 cycles per m of OPL (P(-f) is the conjugate of P(f))");
        if (x > kMaxFrequency)
            throw UserError(what + " \"" + text + "\": frequency " + shortNumber(x) + " cycles/m (a period of " +
                            shortNumber(1.0 / x) +
                            " m of OPL) is finer than any transport tpb resolves (limit 1e6 cycles/m, 1 um)");
    }
    std::sort(f.begin(), f.end());
    f.erase(std::unique(f.begin(), f.end()), f.end());
    if (f.size() > 4096)
        throw UserError(what + " \"" + text + "\": " + std::to_string(f.size()) +
                        " frequencies; at most 4096 (each costs two bins' memory per pixel)");
    return f;
}

}  // namespace tpb
