#include "film/volume_export.h"

#include "base/math.h"
#include "film/film_view.h"
#include "io/npy.h"

#include "io/record_json.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace tpb {

namespace {

const char* axisName(TimeAxis a) { return a == TimeAxis::Real ? "real" : "unwarped"; }
const char* emissionName(EmissionMode m) { return m == EmissionMode::Delta ? "delta" : "continuous"; }

void sumImage(const std::vector<float>& img, double out[3]) {
    out[0] = out[1] = out[2] = 0.0;
    for (size_t i = 0; i + 2 < img.size(); i += 3)
        for (int c = 0; c < 3; ++c) out[c] += img[i + c];
}

// JSON has no Inf/NaN; the film holds none, but a number written here must never be null.
double finite(double v) { return std::isfinite(v) ? v : 0.0; }

}  // namespace

std::vector<std::string> volumeFileNames() {
    return {"steady.npy", "before.npy", "after.npy", "transient.npy", "transient.json"};
}

std::string volumeSideJson(const FilmSnapshot& film, const ExportOptions& opt, const VolumeProvenance& render,
                           const double beforeRgb[3], const double afterRgb[3], const double steadyRgb[3]) {
    using nlohmann::json;
    const TimeBins& t = film.time();
    const double lumSteady = luminance(Color(steadyRgb[0], steadyRgb[1], steadyRgb[2]));
    const double lumBefore = luminance(Color(beforeRgb[0], beforeRgb[1], beforeRgb[2]));
    const double lumAfter = luminance(Color(afterRgb[0], afterRgb[1], afterRgb[2]));
    const auto share = [&](double v) { return lumSteady > 0.0 ? finite(v / lumSteady) : 0.0; };
    json j;
    j["format"] = "tpb transient volume";
    j["version"] = 1;
    j["files"] = {
        {"volume", "transient.npy"}, {"steady", "steady.npy"}, {"before", "before.npy"}, {"after", "after.npy"}};
    j["shape"] = {film.height(), film.width(), film.bins(), 3};
    j["dtype"] = "float32";
    j["index"] = "volume[y, x, k, c]: row y from the top, column x, time bin k, colour c (r, g, b)";
    j["time"] = {{"axis", axisName(opt.axis)},
                 {"emission", emissionName(opt.mode)},
                 {"pulse", pulseName(opt.response)},  // film/time_response.h: widths in ns
                 {"sensor", sensorName(opt.response)},
                 {"time_response", describe(opt.response)},
                 {"counts", countingName(opt.response.counting)},  // film/photon_counting.h
                 {"units", opt.response.counting.enabled ? "photon counts per bin (r = g = b)" : "radiance"},
                 {"bins", t.bins},
                 {"start_opl_m", t.startOpl},
                 {"bin_width_opl_m", t.binWidth},
                 {"end_opl_m", t.endOpl()},
                 {"start_ns", t.startOpl / kC_m_per_ns},
                 {"bin_width_ns", t.binWidth / kC_m_per_ns},
                 {"end_ns", t.endOpl() / kC_m_per_ns},
                 {"bin_centre", "start + (k + 0.5) * bin_width"}};
    j["energy"] = {{"before_rgb", {finite(beforeRgb[0]), finite(beforeRgb[1]), finite(beforeRgb[2])}},
                   {"after_rgb", {finite(afterRgb[0]), finite(afterRgb[1]), finite(afterRgb[2])}},
                   {"steady_rgb", {finite(steadyRgb[0]), finite(steadyRgb[1]), finite(steadyRgb[2])}},
                   {"before_fraction", share(lumBefore)},
                   {"after_fraction", share(lumAfter)},
                   {"inside_fraction", lumSteady > 0.0 ? finite(1.0 - (lumBefore + lumAfter) / lumSteady) : 0.0},
                   {"note",
                    "sums over the pixels of before.npy / after.npy / steady.npy; fractions of the steady "
                    "image's luminance"}};
    j["render"] = {{"scene", render.scene},
                   {"passes", film.minPasses()},
                   {"passes_max", film.maxPasses()},
                   {"settings", recordJson(render.settings)},
                   {"beam_radius_m", render.beamRadius},
                   {"surface_radius_m", render.surfaceRadius}};
    return j.dump(2) + "\n";
}

std::vector<std::string> exportVolumeNpy(const FilmSnapshot& film, const std::string& dir, const ExportOptions& opt,
                                         const VolumeProvenance& render, const std::function<void(int, int)>& progress,
                                         const std::atomic<bool>* cancel) {
    ensureWritableDir(dir);
    const int W = film.width(), H = film.height(), B = film.bins();
    std::vector<std::string> written;
    double sums[3][3];
    {
        const std::vector<float> images[3] = {steadyImage(film), beforeImage(film, opt.axis),
                                              afterImage(film, opt.axis)};
        const char* names[3] = {"steady.npy", "before.npy", "after.npy"};
        for (int i = 0; i < 3; ++i) {
            writeNpy(dir + "/" + names[i], {H, W, 3}, images[i]);
            written.push_back(names[i]);
            sumImage(images[i], sums[i]);
        }
    }
    // Row by row: the streak image of row y is bins x W x 3; the volume's row is W x bins x 3.
    NpyWriter vol(dir + "/transient.npy", {H, W, B, 3});
    std::vector<float> row(static_cast<size_t>(W) * B * 3);
    for (int y = 0; y < H; ++y) {
        if (cancel && cancel->load()) return written;  // vol's destructor removes its temporary file
        const std::vector<float> streak = streakImage(film, y, opt.axis, opt.mode, opt.response);
        for (int k = 0; k < B; ++k)
            for (int x = 0; x < W; ++x)
                for (int c = 0; c < 3; ++c)
                    row[(static_cast<size_t>(x) * B + k) * 3 + c] = streak[(static_cast<size_t>(k) * W + x) * 3 + c];
        vol.write(row.data(), row.size());
        if (progress) progress(y + 1, H);
    }
    vol.commit();
    written.push_back("transient.npy");
    writeTextFile(dir + "/transient.json", volumeSideJson(film, opt, render, sums[1], sums[2], sums[0]));
    written.push_back("transient.json");
    return written;
}

std::vector<std::string> phasorFileNames() { return {"phasor.npy", "phasor_rgb.npy", "phasor.json"}; }

std::vector<std::string> exportPhasorNpy(const FilmSnapshot& film, const std::string& dir, const ExportOptions& opt,
                                         const VolumeProvenance& render) {
    const PhasorSpec& spec = film.phasor();
    if (!spec.active()) return {};
    ensureWritableDir(dir);
    const int W = film.width(), H = film.height(), F = spec.count();
    const std::vector<double> v = phasorVolume(film, opt.axis, opt.response);  // [y][x][f][re, im][rgb]
    std::vector<float> lum(static_cast<size_t>(W) * H * F * 2), rgb(v.size());
    for (size_t i = 0; i < v.size(); ++i) rgb[i] = static_cast<float>(v[i]);
    for (size_t i = 0; i < lum.size(); ++i)
        lum[i] = static_cast<float>(luminance(Color(v[i * 3], v[i * 3 + 1], v[i * 3 + 2])));
    writeNpy(dir + "/phasor.npy", {H, W, F, 2}, lum);
    writeNpy(dir + "/phasor_rgb.npy", {H, W, F, 2, 3}, rgb);
    using nlohmann::json;
    json j;
    j["format"] = "tpb phasor film";
    j["version"] = 1;
    j["files"] = {{"luminance", "phasor.npy"}, {"rgb", "phasor_rgb.npy"}};
    j["shape"] = {{"phasor.npy", {H, W, F, 2}}, {"phasor_rgb.npy", {H, W, F, 2, 3}}};
    j["index"] = "phasor[y, x, f, 0 = real | 1 = imaginary] (phasor_rgb: then colour r, g, b)";
    j["definition"] =
        "P(f) = Int L(t) exp(-i 2 pi f (t - reference_opl_m)) dt over every estimate's exact time profile (no bins); "
        "P(0) is the steady image";
    json freqs = json::array(), ghz = json::array(), wl = json::array();
    for (double f : spec.frequencies) {
        freqs.push_back(f);
        ghz.push_back(f * kC_m_per_ns);  // cycles per m x m per ns = cycles per ns
        wl.push_back(f > 0.0 ? 1.0 / f : 0.0);
    }
    j["frequencies_per_m"] = freqs;
    j["frequencies_ghz"] = ghz;
    j["wavelengths_m"] = wl;
    j["reference_opl_m"] = spec.refOpl;
    j["time"] = {{"axis", axisName(opt.axis)},
                 {"pulse", pulseName(opt.response)},
                 {"sensor", sensorName(opt.response)},
                 {"time_response", describe(opt.response)},
                 {"film_bin_width_opl_m", film.time().binWidth},
                 {"film_nyquist_per_m", 0.5 / film.time().binWidth}};
    j["render"] = {{"scene", render.scene}, {"passes", film.minPasses()}, {"settings", recordJson(render.settings)}};
    writeTextFile(dir + "/phasor.json", j.dump(2) + "\n");
    return phasorFileNames();
}

}  // namespace tpb
