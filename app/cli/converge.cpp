// `tpb converge`: error of the photon-beam renderer and/or the path tracer against a reference as
// a function of render time: convergence.csv, convergence.json, a log-log plot (gnuplot), the
// fitted slope, and an equal-time strip of frames (the paper's Figure 4 layout).
#include "cli/common.h"
#include "cli/reference.h"
#include "film/picture_export.h"
#include "render/provenance.h"

#include "cli/flags.h"
#include "cli/summary.h"

#include "cli/interrupt.h"
#include "cli/commands.h"
#include "base/error.h"
#include "estimators/estimator_names.h"
#include "eval/error_metrics.h"
#include "io/image_io.h"
#include "integrators/path_tracer.h"
#include "photons/photon_tracer.h"
#include "eval/reference.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <ctime>
#include <unistd.h>

namespace tpb::app {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// CPU seconds of the whole process (all threads).
double cpuSec() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

std::string fmt(const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}
// Number for CSV/JSON text: empty / null when not finite.
std::string csvNum(double v) { return std::isfinite(v) ? fmt("%.6g", v) : std::string(); }
json jnum(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// The path tracer's settings: the prepared ones (seed, max depth, threads, --pt-free-flight), `spp`
// camera paths per pixel.
RenderSettings ptSettings(const PreparedRender& p, int spp) {
    RenderSettings ps = p.settings;
    ps.samplesPerPixel = std::max(1, spp);
    return ps;
}

std::string shellQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// `count` evenly spaced bins (centred in equal slices, as exportStripPng) of the part of the time
// axis where the reference has light: from the first to the last bin holding at least 1e-3 of
// the brightest bin's energy (on `axis`).
std::vector<int> stripBins(const ReferenceVolume& ref, TimeAxis axis, int count) {
    const ReferenceInfo& i = ref.info;
    const std::vector<float>& v = ref.volume(axis);
    std::vector<double> energy(static_cast<size_t>(i.bins), 0.0);
    for (size_t p = 0; p < i.pixels(); ++p)
        for (int k = 0; k < i.bins; ++k)
            for (int c = 0; c < 3; ++c) energy[k] += v[(p * i.bins + k) * 3 + c];
    const double peak = *std::max_element(energy.begin(), energy.end());
    int lo = 0, hi = i.bins - 1;
    if (peak > 0.0) {
        while (lo < hi && energy[lo] < 1e-3 * peak) ++lo;
        while (hi > lo && energy[hi] < 1e-3 * peak) --hi;
    }
    const int span = hi - lo + 1;
    count = std::clamp(count, 1, span);
    std::vector<int> out;
    for (int j = 0; j < count; ++j) out.push_back(lo + std::min(span - 1, static_cast<int>((j + 0.5) * span / count)));
    return out;
}

void referenceFrame(const ReferenceVolume& ref, TimeAxis axis, int k, std::vector<float>& img) {
    const ReferenceInfo& i = ref.info;
    const std::vector<float>& v = ref.volume(axis);
    img.resize(i.pixels() * 3);
    for (size_t p = 0; p < i.pixels(); ++p)
        for (int c = 0; c < 3; ++c) img[p * 3 + c] = v[(p * i.bins + k) * 3 + c];
}

}  // namespace

namespace {

// ============================================================================================
// tpb converge
// ============================================================================================

struct ConvergeCmd {
    std::string scene, reference, out = "out/converge", method = "beams", axis = "real", clock = "wall";
    RenderOverrides ov;
    int checkpoints = 24;
    double firstCheckpoint = 0.25;
    std::vector<double> at;
    int everyPass = 3;
    bool perFrame = false;
    int frames = 0;
    double stripEv = 0.0;
    bool stripReference = false;
    int spp = 1;
    double maskLights = 0.0;
    std::vector<double> targets{0.5, 0.3, 0.2, 0.1, 0.05};
    bool noPlot = false, quiet = false;
};

struct Row {
    std::string method;
    int checkpoint = 0;
    double elapsed = 0.0;          // on the chosen clock
    double wall = 0.0, cpu = 0.0;  // both clocks
    int64_t passes = 0, spp = 0;
    double radius = kNaN;
    FilmError err;
    double corrVolume = kNaN, corrSteady = kNaN;
};

struct MethodResult {
    std::string method;
    std::vector<Row> rows;
    PowerLawFit fitVolume, fitSteady, fitVolumeCorr, fitVolumeL1, fitSteadyL1;
    std::vector<double> finalPerFrame;
    // The largest photon map of a pass (beams, volume photons, surface photons; bytes of the stored
    // records, without the acceleration structures): the memory an estimator costs beyond the film.
    uint64_t peakMapBytes = 0;
    std::unique_ptr<Driver> driver;  // runs the method's integrator
    const TransientFilm& film() const { return driver->film(); }
    std::vector<double> times() const {
        std::vector<double> t;
        for (const Row& r : rows) t.push_back(r.elapsed);
        return t;
    }
    enum Which { Volume, Steady, VolumeCorrected, VolumeL1, SteadyL1 };
    std::vector<double> errors(Which w) const {
        std::vector<double> e;
        for (const Row& r : rows)
            e.push_back(w == Volume            ? r.err.volume
                        : w == Steady          ? r.err.steady
                        : w == VolumeCorrected ? r.corrVolume
                        : w == VolumeL1        ? r.err.volumeL1
                                               : r.err.steadyL1);
        return e;
    }
};

struct ConvergeContext {
    const ConvergeCmd& cmd;
    const Scene& scene;
    const ReferenceVolume& ref;
    TimeAxis axis;
    std::vector<uint8_t> mask;
    double floorVolume, floorSteady;  // the reference's own error (-1 unknown)
    double budget;                    // s per method, 0 = none
    int64_t passes;                   // per method, 0 = none
    const PreparedRender& prepared;   // the settings and the film's time axis
};

// The photon-beams settings of a converge method: "beams" (the settings as they are) or
// "<estimator>[+<time kernel>]" (estimator_names.h; parseTimeKernel), checked by the settings' own
// validate() / validateAgainstFilm() against the film's time range, their message prefixed with the
// method.
RenderSettings beamsVariant(const PreparedRender& prepared, const std::string& method) {
    RenderSettings s = prepared.settings;
    s.method = Method::Beams;
    if (method == "beams") return s;
    const size_t plus = method.find('+');
    SettingsOverrides o;
    o.volumeEstimator = method.substr(0, plus);
    o.timeKernel = TimeKernelSettings{};
    if (plus != std::string::npos) {
        o.timeKernel = parseTimeKernel(method.substr(plus + 1));
        if (!o.timeKernel)
            throw UserError("--method " + method + ": unknown time kernel \"" + method.substr(plus + 1) +
                            "\"; allowed: none, box, box:WIDTH (m of optical path, > 0)");
    }
    s.apply(o);
    try {
        const double diag = prepared.scene->bounds.diagonal() > 0.0 ? prepared.scene->bounds.diagonal() : 1.0;
        s.validate({nullptr, &o, diag});  // (its warnings were given for the shared settings already)
        s.validateAgainstFilm(prepared.time.binWidth * prepared.time.bins, {nullptr, &o, diag});
    } catch (const UserError& e) {
        throw UserError("--method " + method + ": " + e.what() + " (a --method entry is beams, pt, both or " +
                        volumeEstimatorNames().front() + "[+box[:WIDTH]])");
    }
    return s;
}

// The --method list, expanded ("both" = beams,pt) and checked before anything runs.
std::vector<std::string> convergeMethods(const std::string& list, const PreparedRender& prepared) {
    std::vector<std::string> out;
    size_t from = 0;
    while (from <= list.size()) {
        const size_t comma = list.find(',', from);
        const std::string m = list.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
        if (m == "both") {
            out.push_back("beams");
            out.push_back("pt");
        } else if (!m.empty()) {
            if (m != "pt") beamsVariant(prepared, m);  // throws for an unknown estimator or kernel
            if (std::find(out.begin(), out.end(), m) != out.end())
                throw UserError("--method " + list + ": \"" + m + "\" is listed twice");
            out.push_back(m);
        }
        if (comma == std::string::npos) break;
        from = comma + 1;
    }
    if (out.empty()) throw UserError("--method is empty: give beams, pt, both or estimators such as beam2d,point3d");
    return out;
}

// Runs one method, recording checkpoints; rendering time only (measuring is not counted).
MethodResult runMethod(const ConvergeContext& cx, const std::string& method) {
    const ConvergeCmd& c = cx.cmd;
    MethodResult res;
    res.method = method;
    RenderSettings ps = ptSettings(cx.prepared, c.spp);
    if (method != "pt") {
        res.driver = std::make_unique<Driver>(cx.scene, beamsVariant(cx.prepared, method), cx.prepared.time);
    } else {
        if (cx.ref.info.method == "pt" && ps.seed == cx.ref.info.seed) {
            ps.seed = cx.ref.info.seed + 1;
            if (!c.quiet)
                std::printf(
                    "note: the reference was path traced with seed %llu; this run uses seed %llu so the two "
                    "are independent\n",
                    static_cast<unsigned long long>(cx.ref.info.seed), static_cast<unsigned long long>(ps.seed));
        }
        ps.method = Method::PathTracer;
        res.driver = std::make_unique<Driver>(cx.scene, ps, cx.prepared.time);
    }
    // Checkpoints: geometric in render time (or in passes without a time budget), plus --at, plus
    // the first --every-pass passes, plus the last pass.
    const bool byTime = cx.budget > 0.0;
    std::vector<double> marks =
        byTime ? geometricCheckpoints(std::min(c.firstCheckpoint, 0.5 * cx.budget), cx.budget, c.checkpoints, c.at)
               : geometricCheckpoints(1.0, static_cast<double>(cx.passes), c.checkpoints, c.at);
    size_t next = 0;
    double elapsed = 0.0, wall = 0.0, cpu = 0.0;
    const bool cpuClock = c.clock == "cpu";
    int64_t done = 0;
    auto record = [&]() {
        Row r;
        r.method = method;
        r.checkpoint = static_cast<int>(res.rows.size());
        r.elapsed = elapsed;
        r.wall = wall;
        r.cpu = cpu;
        r.passes = done;
        r.spp = method == "pt" ? done * ps.samplesPerPixel : done;
        if (method != "pt") r.radius = res.driver->lastPass().beamRadius;
        r.err = compareWithReference(res.film(), cx.ref, cx.axis, c.perFrame, cx.mask.empty() ? nullptr : &cx.mask);
        r.corrVolume = noiseCorrected(r.err.volume, cx.floorVolume);
        r.corrSteady = noiseCorrected(r.err.steady, cx.floorSteady);
        if (!c.quiet)
            std::printf("%-5s %8.2f s %7lld passes  volume %.4g  steady %.4g  total %+.3f%%\n", method.c_str(), elapsed,
                        static_cast<long long>(done), r.err.volume, r.err.steady, 100.0 * r.err.steadyTotalDiff);
        std::fflush(stdout);
        res.rows.push_back(std::move(r));
    };
    for (uint64_t pass = 1;; ++pass) {
        if (interrupted()) break;
        if (cx.passes > 0 && static_cast<int64_t>(pass) > cx.passes) break;
        if (byTime && elapsed >= cx.budget) break;
        const double t0 = nowSec(), c0 = cpuSec();
        if (!res.driver->runPass(pass)) break;  // any method: the integrator of its settings
        wall += nowSec() - t0;
        cpu += cpuSec() - c0;
        elapsed = cpuClock ? cpu : wall;
        done = static_cast<int64_t>(pass);
        bool take = static_cast<int64_t>(pass) <= c.everyPass;
        const double progress = byTime ? elapsed : static_cast<double>(pass);
        while (next < marks.size() && progress >= marks[next] * (1.0 - 1e-12)) {
            take = true;
            ++next;
        }
        const bool last =
            (byTime && elapsed >= cx.budget) || (cx.passes > 0 && static_cast<int64_t>(pass) == cx.passes);
        if (take || last) record();
    }
    if (done > 0 && (res.rows.empty() || res.rows.back().passes != done)) record();
    for (const PassStats& p : res.driver->history())
        res.peakMapBytes =
            std::max<uint64_t>(res.peakMapBytes, static_cast<uint64_t>(p.beams) * sizeof(Beam) +
                                                     static_cast<uint64_t>(p.points) * sizeof(VolumePhoton) +
                                                     static_cast<uint64_t>(p.surfacePhotons) * sizeof(SurfacePhoton));
    if (!res.rows.empty()) {
        const std::vector<double> t = res.times();
        res.fitVolume = fitPowerLawSecondHalf(t, res.errors(MethodResult::Volume));
        res.fitSteady = fitPowerLawSecondHalf(t, res.errors(MethodResult::Steady));
        res.fitVolumeCorr = fitPowerLawSecondHalf(t, res.errors(MethodResult::VolumeCorrected));
        res.fitVolumeL1 = fitPowerLawSecondHalf(t, res.errors(MethodResult::VolumeL1));
        res.fitSteadyL1 = fitPowerLawSecondHalf(t, res.errors(MethodResult::SteadyL1));
        res.finalPerFrame =
            compareWithReference(res.film(), cx.ref, cx.axis, true, cx.mask.empty() ? nullptr : &cx.mask).perFrame;
    }
    return res;
}

std::string methodLabel(const std::string& m) {
    if (m == "pt") return "path tracing";
    if (m == "beams") return "photon beams";
    return "photon beams " + m;
}

// The columns of convergence.csv, in order, for one row; convergence.json's "rows" holds the same
// values under the same names (null where the CSV cell is empty: not measured or not finite).
std::vector<std::pair<const char*, json>> rowColumns(const Row& r) {
    return {{"method", r.method},
            {"checkpoint", r.checkpoint},
            {"elapsed_s", jnum(r.elapsed)},
            {"passes", r.passes},
            {"samples_per_pixel", r.spp},
            {"kernel_radius_m", jnum(r.radius)},
            {"rel_rmse_volume", jnum(r.err.volume)},
            {"rel_rmse_steady", jnum(r.err.steady)},
            {"steady_total_diff", jnum(r.err.steadyTotalDiff)},
            {"rel_rmse_volume_corrected", jnum(r.corrVolume)},
            {"rel_rmse_steady_corrected", jnum(r.corrSteady)},
            {"wall_s", jnum(r.wall)},
            {"cpu_s", jnum(r.cpu)},
            {"rel_l1_volume", jnum(r.err.volumeL1)},
            {"rel_l1_steady", jnum(r.err.steadyL1)}};
}

void writeCsv(const std::string& path, const std::vector<MethodResult>& results) {
    std::ostringstream os;
    const auto header = rowColumns(Row{});
    for (size_t i = 0; i < header.size(); ++i) os << (i ? "," : "") << header[i].first;
    os << '\n';
    for (const MethodResult& m : results)
        for (const Row& r : m.rows) {
            const auto cols = rowColumns(r);
            for (size_t i = 0; i < cols.size(); ++i) {
                const json& v = cols[i].second;
                os << (i ? "," : "");
                if (v.is_string())
                    os << v.get<std::string>();
                else if (v.is_number_integer())
                    os << v.get<int64_t>();
                else if (v.is_number())
                    os << csvNum(v.get<double>());
            }
            os << '\n';
        }
    writeTextFile(path, os.str());
}

json rowsJson(const std::vector<MethodResult>& results) {
    json rows = json::array();
    for (const MethodResult& m : results)
        for (const Row& r : m.rows) {
            json o = json::object();
            for (auto& [name, v] : rowColumns(r)) o[name] = v;
            rows.push_back(o);
        }
    return rows;
}

void writePerFrameCsv(const std::string& path, const std::vector<MethodResult>& results, const TimeBins& tb) {
    std::ostringstream os;
    os << "method,checkpoint,elapsed_s,passes,bin,t_ns,rel_rmse\n";
    for (const MethodResult& m : results)
        for (const Row& r : m.rows)
            for (size_t k = 0; k < r.err.perFrame.size(); ++k)
                os << r.method << ',' << r.checkpoint << ',' << csvNum(r.elapsed) << ',' << r.passes << ',' << k << ','
                   << csvNum((tb.startOpl + (k + 0.5) * tb.binWidth) / kC_m_per_ns) << ',' << csvNum(r.err.perFrame[k])
                   << '\n';
    writeTextFile(path, os.str());
}

// The gnuplot script: both terminals (SVG, PNG via cairo), run in the output folder.
std::string gnuplotScript(const ConvergeContext& cx, const std::vector<MethodResult>& results) {
    std::ostringstream g;
    const std::string axisName = cx.axis == TimeAxis::Real ? "real" : "unwarped";
    g << "# Written by `tpb converge`; re-plot with `gnuplot convergence.gp` in this folder\n"
         "# (or tools/plot_convergence <folder>). Data: convergence.csv.\n"
         "set datafile separator ','\n"
         "set logscale xy\n"
         "set format x '%g'\nset format y '%g'\n"
         "set xlabel '"
      << (cx.cmd.clock == "cpu" ? "CPU time per method, all threads (s)" : "render time per method (s)")
      << "'\n"
         "set ylabel 'relative RMSE against the reference'\n"
         "set grid xtics ytics mxtics mytics lc rgb '#dddddd'\n"
         "set key outside below\n";
    std::string sceneName = fs::path(cx.prepared.source.path).filename().string();
    g << "set title \"" << sceneName << ", " << cx.scene.camera.width << "x" << cx.scene.camera.height << "x"
      << cx.prepared.time.bins << " bins, " << axisName << " time, delta emission"
      << (cx.mask.empty() ? "" : ", light pixels masked") << "\" noenhanced\n";
    std::vector<std::string> curves, curvesL1;
    auto color = [&results](const std::string& m) {
        if (m == "pt") return std::string("#2471a3");
        // The photon-beams variants in the order they ran.
        static const char* palette[] = {"#c0392b", "#27ae60", "#8e44ad", "#d68910",
                                        "#16a085", "#7f8c8d", "#e84393", "#2c3e50"};
        int k = 0;
        for (const MethodResult& r : results) {
            if (r.method == m) break;
            if (r.method != "pt") ++k;
        }
        return std::string(palette[k % 8]);
    };
    auto curve = [&](const MethodResult& m, int column, bool steady, double slope) {
        const std::string sel = "(strcol(1) eq '" + m.method + "' ? $3 : NaN)";
        return "'convergence.csv' using " + sel + ":" + std::to_string(column) + " with linespoints " +
               (steady ? "lw 1.5 dt 2 pt 6" : "lw 2 pt 7") + " ps 0.5 lc rgb '" + color(m.method) + "' title '" +
               methodLabel(m.method) + (steady ? ", steady image" : ", transient volume") + " (slope " +
               fmt("%.2f", slope) + ")'";
    };
    for (const MethodResult& m : results) {
        curves.push_back(curve(m, 7, false, m.fitVolume.slope));
        curves.push_back(curve(m, 8, true, m.fitSteady.slope));
        curvesL1.push_back(curve(m, 14, false, m.fitVolumeL1.slope));
        curvesL1.push_back(curve(m, 15, true, m.fitSteadyL1.slope));
    }
    if (cx.floorVolume > 0.0)
        curves.push_back(fmt("%.6g", cx.floorVolume) +
                         " with lines dt 3 lw 1.5 lc rgb '#555555' title "
                         "'own error of the reference (transient volume)'");
    if (cx.floorSteady > 0.0)
        curves.push_back(fmt("%.6g", cx.floorSteady) +
                         " with lines dt 4 lw 1 lc rgb '#999999' title "
                         "'own error of the reference (steady image)'");
    auto plotCmd = [](const std::vector<std::string>& cs) {
        std::string plot = "plot ";
        for (size_t i = 0; i < cs.size(); ++i) plot += (i ? ", \\\n     " : "") + cs[i];
        return plot;
    };
    auto both = [&](const std::string& name, const std::string& plot) {
        g << "set terminal svg size 900,640 dynamic font 'Helvetica,13' background rgb 'white'\n"
             "set output '"
          << name << ".svg'\n"
          << plot << "\n"
          << "set terminal pngcairo size 900,640 font 'Helvetica,11' background rgb 'white'\n"
             "set output '"
          << name << ".png'\nreplot\nset output\n";
    };
    both("convergence", plotCmd(curves));
    // The same against the relative mean absolute error sum |x - ref| / sum ref: robust to the rare
    // huge samples that dominate the RMSE of a heavy-tailed estimator.
    g << "set ylabel 'relative mean absolute error against the reference'\n";
    both("convergence_l1", plotCmd(curvesL1));
    return g.str();
}

// Rows of frames (one row per film/reference), the same bins and the same exposure: 2^ev times the
// normalisation that maps the 99.5th percentile of the reference's luminance in these frames to 1.
void writeEqualTimeStrip(const std::string& path, const ConvergeContext& cx, const std::vector<MethodResult>& results,
                         const std::vector<int>& bins) {
    const int W = cx.scene.camera.width, H = cx.scene.camera.height, K = static_cast<int>(bins.size());
    constexpr int kGap = 2;
    std::vector<const TransientFilm*> rows;
    for (const MethodResult& m : results) rows.push_back(&m.film());
    const int R = static_cast<int>(rows.size()) + (cx.cmd.stripReference ? 1 : 0);
    const int SW = K * W + (K - 1) * kGap, SH = R * H + (R - 1) * kGap;
    std::vector<float> strip(static_cast<size_t>(SW) * SH * 3, 0.08f), img, lum;
    for (int i = 0; i < K; ++i) {
        referenceFrame(cx.ref, cx.axis, bins[i], img);
        for (size_t p = 0; p < img.size(); p += 3)
            lum.push_back(static_cast<float>(luminance(Color(img[p], img[p + 1], img[p + 2]))));
    }
    std::sort(lum.begin(), lum.end());
    const float white = lum.empty() ? 0.0f : lum[static_cast<size_t>(0.995 * (lum.size() - 1))];
    const double norm = white > 0.0f ? std::log2(1.0 / white) : 0.0;
    // The linear background is scaled by the exposure too: pre-divide it so separators stay grey.
    const float bg = static_cast<float>(0.08 / std::exp2(norm + cx.cmd.stripEv));
    std::fill(strip.begin(), strip.end(), bg);
    for (int r = 0; r < R; ++r)
        for (int i = 0; i < K; ++i) {
            if (r < static_cast<int>(rows.size()))
                rows[r]->frame(bins[i], cx.axis, EmissionMode::Delta, img);
            else
                referenceFrame(cx.ref, cx.axis, bins[i], img);
            const int ox = i * (W + kGap), oy = r * (H + kGap);
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x)
                    for (int c = 0; c < 3; ++c)
                        strip[((static_cast<size_t>(oy + y) * SW) + ox + x) * 3 + c] =
                            img[(static_cast<size_t>(y) * W + x) * 3 + c];
        }
    writePngPreview(path, SW, SH, strip, norm + cx.cmd.stripEv);
}

void runConverge(ConvergeCmd& c) {
    InterruptScope interrupts;  // Ctrl-C and SIGTERM: what was measured is written
    if (c.reference.empty()) throw UserError("--reference FILE is required (make one with `tpb reference`)");
    if (!c.ov.timeBudget && !c.ov.passes)
        throw UserError("converge needs a budget per method: --time SECONDS (or --passes N)");
    if (c.ov.timeBudget && !(*c.ov.timeBudget > 0.0)) throw UserError("--time must be > 0");
    if (c.ov.passes && *c.ov.passes < 1) throw UserError("--passes must be >= 1");
    const ReferenceVolume ref = readReference(c.reference);
    // What is not given on the command line is taken from the reference (resolution, bins, depth).
    std::string adopted;
    auto adopt = [&](std::optional<int>& o, int v, const char* flag) {
        if (o) return;
        o = v;
        adopted += std::string(adopted.empty() ? "" : " ") + flag + " " + std::to_string(v);
    };
    adopt(c.ov.width, ref.info.width, "--width");
    adopt(c.ov.height, ref.info.height, "--height");
    adopt(c.ov.bins, ref.info.bins, "--bins");
    adopt(c.ov.maxDepth, ref.info.maxDepth, "--max-depth");
    if (!adopted.empty() && !c.quiet) std::printf("from the reference: %s\n", adopted.c_str());
    PreparedRender prepared = loadAndBuild(c.scene, c.ov, LoadOptions{c.quiet});
    const Scene* scene = prepared.scene.get();
    // An automatic film range is fitted by a pilot pass: take the reference's (same bins) so that
    // tiny differences of the fit do not make it incompatible (the axis is decided here, before
    // any film exists).
    if (prepared.film.autoRange && prepared.time.bins == ref.info.bins) {
        prepared.time.startOpl = ref.info.startOpl;
        prepared.time.binWidth = ref.info.binWidth;
    }
    ReferenceInfo want = describeScene(*scene, prepared.time, prepared.source.path, prepared.settings);
    requireCompatible(c.reference, ref.info, want);
    if (!c.quiet) {
        std::printf("reference ");
        printReference(c.reference, ref.info);
    }

    ConvergeContext cx{c,
                       *scene,
                       ref,
                       c.axis == "unwarped" ? TimeAxis::Unwarped : TimeAxis::Real,
                       {},
                       -1.0,
                       -1.0,
                       c.ov.timeBudget.value_or(0.0),
                       c.ov.passes.value_or(0),
                       prepared};
    cx.mask = lightPixelMask(*scene, c.maskLights);
    const std::vector<uint8_t>* maskPtr = cx.mask.empty() ? nullptr : &cx.mask;
    cx.floorVolume = referenceSelfError(ref, cx.axis, false, maskPtr);
    cx.floorSteady = referenceSelfError(ref, cx.axis, true, maskPtr);
    if (!cx.mask.empty() && !c.quiet) {
        const auto n = std::count(cx.mask.begin(), cx.mask.end(), uint8_t(1));
        std::printf("masking %lld pixels within %.3g px of the point/spot lights' images\n", static_cast<long long>(n),
                    c.maskLights);
    }
    // Every method's settings were checked (prepareRender, convergeMethods) before the folder is touched.
    const std::vector<std::string> methods = convergeMethods(c.method, cx.prepared);
    OutputFiles files;
    files.files = {"convergence.csv", "convergence.json", "convergence.gp"};
    if (c.perFrame) files.files.push_back("convergence_frames.csv");
    if (c.frames > 0) files.files.insert(files.files.end(), {"equal_time.png", "equal_time.csv"});
    if (!c.noPlot)
        files.files.insert(files.files.end(),
                           {"convergence.svg", "convergence.png", "convergence_l1.svg", "convergence_l1.png"});
    const OutputFolder folder(c.out, "converge", files);
    std::vector<MethodResult> results;
    {
        for (const std::string& m : methods) {
            if (interrupted()) break;
            if (!c.quiet)
                std::printf("-- %s: %s\n", methodLabel(m).c_str(),
                            cx.budget > 0 ? fmt("%g s of rendering", cx.budget).c_str()
                                          : (std::to_string(cx.passes) + " passes").c_str());
            results.push_back(runMethod(cx, m));
        }
        if (interrupted())
            std::fprintf(stderr, "interrupted by %s: writing what was measured\n", interruptName().c_str());
    }
    if (results.empty() || results.front().rows.empty()) {
        throwIfInterrupted("before the first pass finished");
        throw UserError("no pass completed: nothing to write");
    }

    // ---- files
    writeCsv(c.out + "/convergence.csv", results);
    if (c.perFrame) writePerFrameCsv(c.out + "/convergence_frames.csv", results, prepared.time);
    json j;
    j["scene"] = prepared.source.path;
    j["reference"] = {{"path", c.reference},
                      {"method", ref.info.method},
                      {"passes", ref.info.passes},
                      {"samples_per_pixel", ref.info.samplesPerPixel},
                      {"wall_seconds", ref.info.wallSeconds},
                      {"own_error_volume", jnum(cx.floorVolume)},
                      {"own_error_steady", jnum(cx.floorSteady)},
                      {"own_error_estimate", ref.info.selfErrorEstimate}};
    j["resolution"] = {scene->camera.width, scene->camera.height};
    j["film"] = filmJson(prepared.time);
    j["axis"] = c.axis;
    j["emission"] = "delta";
    j["metric"] = "relative RMSE sqrt(sum (x - ref)^2 / sum ref^2) over pixels, RGB and (volume) bins";
    j["masked_pixels"] = std::count(cx.mask.begin(), cx.mask.end(), uint8_t(1));
    j["clock"] = c.clock == "cpu" ? "cpu: process CPU seconds, all threads" : "wall: seconds of rendering";
    j["budget_s"] = cx.budget;
    j["budget_passes"] = cx.passes;
    json jm = json::object();
    for (const MethodResult& m : results) {
        const std::vector<double> t = m.times(), ev = m.errors(MethodResult::Volume),
                                  es = m.errors(MethodResult::Steady), ec = m.errors(MethodResult::VolumeCorrected),
                                  el = m.errors(MethodResult::VolumeL1), esl = m.errors(MethodResult::SteadyL1);
        json e;
        e["passes"] = m.rows.back().passes;
        e["elapsed_s"] = m.rows.back().elapsed;
        e["photon_map_bytes"] = m.peakMapBytes;
        e["final"] = {{"volume", jnum(m.rows.back().err.volume)},
                      {"steady", jnum(m.rows.back().err.steady)},
                      {"steady_total_diff", jnum(m.rows.back().err.steadyTotalDiff)},
                      {"volume_corrected", jnum(m.rows.back().corrVolume)},
                      {"volume_l1", jnum(m.rows.back().err.volumeL1)},
                      {"steady_l1", jnum(m.rows.back().err.steadyL1)}};
        e["slope"] = {{"volume", jnum(m.fitVolume.slope)},
                      {"steady", jnum(m.fitSteady.slope)},
                      {"volume_corrected", jnum(m.fitVolumeCorr.slope)},
                      {"volume_l1", jnum(m.fitVolumeL1.slope)},
                      {"steady_l1", jnum(m.fitSteadyL1.slope)},
                      {"points", m.fitVolume.points}};
        json atj = json::array();
        for (double T : c.at)
            atj.push_back({{"time_s", T},
                           {"volume", jnum(interpolateLogLog(t, ev, T))},
                           {"steady", jnum(interpolateLogLog(t, es, T))},
                           {"volume_corrected", jnum(interpolateLogLog(t, ec, T))},
                           {"volume_l1", jnum(interpolateLogLog(t, el, T))},
                           {"steady_l1", jnum(interpolateLogLog(t, esl, T))}});
        e["at"] = atj;
        json tt = json::array();
        for (double target : c.targets)
            tt.push_back({{"target", target},
                          {"volume_s", jnum(timeToReach(t, ev, target))},
                          {"steady_s", jnum(timeToReach(t, es, target))},
                          {"volume_l1_s", jnum(timeToReach(t, el, target))},
                          {"volume_s_extrapolated", jnum(m.fitVolume.timeFor(target))}});
        e["time_to_reach"] = tt;
        jm[m.method] = e;
    }
    j["methods"] = jm;
    j["rows"] = rowsJson(results);  // convergence.csv's rows, same names

    std::vector<int> stripK;
    if (c.frames > 0) {
        stripK = stripBins(ref, cx.axis, c.frames);
        writeEqualTimeStrip(c.out + "/equal_time.png", cx, results, stripK);
        std::ostringstream os;
        os << "bin,t_ns";
        for (const MethodResult& m : results) os << ',' << m.method << "_rel_rmse";
        os << '\n';
        json fj = json::array();
        for (int k : stripK) {
            const double tns = (prepared.time.startOpl + (k + 0.5) * prepared.time.binWidth) / kC_m_per_ns;
            os << k << ',' << csvNum(tns);
            json row = {{"bin", k}, {"t_ns", tns}};
            for (const MethodResult& m : results) {
                os << ',' << csvNum(m.finalPerFrame[k]);
                row[m.method] = jnum(m.finalPerFrame[k]);
            }
            os << '\n';
            fj.push_back(row);
        }
        writeTextFile(c.out + "/equal_time.csv", os.str());
        j["equal_time_frames"] = fj;
    }
    writeTextFile(c.out + "/convergence.json", j.dump(2) + "\n");
    const std::string gp = gnuplotScript(cx, results);
    writeTextFile(c.out + "/convergence.gp", gp);
    bool plotted = false;
    if (!c.noPlot) {
        const std::string cmd = "cd " + shellQuote(c.out) + " && gnuplot convergence.gp";
        const int rc = std::system(cmd.c_str());
        plotted = rc == 0;
        if (!plotted)
            std::fprintf(stderr,
                         "warning: gnuplot failed or is not installed (exit %d): no plot; install gnuplot-nox and "
                         "run tools/plot_convergence %s\n",
                         rc, c.out.c_str());
    }

    // ---- report
    const std::string axisName = c.axis;
    std::printf("\nrelative RMSE against %s (%s axis, delta emission%s):\n", c.reference.c_str(), axisName.c_str(),
                cx.mask.empty() ? "" : ", light pixels masked");
    if (cx.floorVolume >= 0.0)
        std::printf(
            "  the reference's own error (%s): volume %.4g, steady %.4g: smaller errors cannot be resolved; "
            "'corrected' = sqrt(err^2 - own^2)\n",
            ref.info.selfErrorEstimate.c_str(), cx.floorVolume, cx.floorSteady);
    std::printf("  %-13s %8s %9s %11s %11s %11s %12s %10s\n", "method", "passes", "time_s", "volume", "corrected",
                "steady", "steady_total", "map_MiB");
    for (const MethodResult& m : results) {
        const Row& r = m.rows.back();
        std::printf("  %-13s %8lld %9.2f %11.4g %11.4g %11.4g %+11.3f%% %10.2f\n", methodLabel(m.method).c_str(),
                    static_cast<long long>(r.passes), r.elapsed, r.err.volume, r.corrVolume, r.err.steady,
                    100.0 * r.err.steadyTotalDiff, m.peakMapBytes / 1048576.0);
    }
    std::printf("fitted convergence slope (least squares of log error vs log time, second half of the checkpoints):\n");
    for (const MethodResult& m : results)
        std::printf(
            "  %-13s volume %.3f, steady %.3f, volume corrected for the reference's error %.3f; relative L1: "
            "volume %.3f, steady %.3f  (%d points)\n",
            methodLabel(m.method).c_str(), m.fitVolume.slope, m.fitSteady.slope, m.fitVolumeCorr.slope,
            m.fitVolumeL1.slope, m.fitSteadyL1.slope, m.fitVolume.points);
    if (!c.at.empty()) {
        std::printf(
            "error at given times (log-log interpolation between checkpoints; RMSE volume / steady, "
            "relative L1 volume / steady):\n");
        for (const MethodResult& m : results) {
            std::printf("  %-13s", methodLabel(m.method).c_str());
            const std::vector<double> t = m.times();
            for (double T : c.at)
                std::printf("  %g s: %.4g / %.4g, L1 %.4g / %.4g", T,
                            interpolateLogLog(t, m.errors(MethodResult::Volume), T),
                            interpolateLogLog(t, m.errors(MethodResult::Steady), T),
                            interpolateLogLog(t, m.errors(MethodResult::VolumeL1), T),
                            interpolateLogLog(t, m.errors(MethodResult::SteadyL1), T));
            std::printf("\n");
        }
    }
    if (!c.targets.empty()) {
        std::printf(
            "time to reach a relative RMSE of the transient volume (interpolated; [extrapolated from the fit]):\n");
        for (double target : c.targets) {
            std::printf("  %-8g", target);
            for (const MethodResult& m : results) {
                const double tr = timeToReach(m.times(), m.errors(MethodResult::Volume), target);
                if (std::isfinite(tr))
                    std::printf("  %s %9.3g s  ", m.method.c_str(), tr);
                else
                    std::printf("  %s [%9.3g s]", m.method.c_str(), m.fitVolume.timeFor(target));
            }
            std::printf("\n");
        }
        std::printf("time to reach a relative L1 error of the transient volume (interpolated):\n");
        for (double target : c.targets) {
            std::printf("  %-8g", target);
            for (const MethodResult& m : results) {
                const double tr = timeToReach(m.times(), m.errors(MethodResult::VolumeL1), target);
                if (std::isfinite(tr))
                    std::printf("  %s %9.3g s  ", m.method.c_str(), tr);
                else
                    std::printf("  %s  not reached", m.method.c_str());
            }
            std::printf("\n");
        }
    }
    if (!stripK.empty()) {
        std::printf("equal-time frames (%s): relative RMSE per frame at the end of each run\n", "equal_time.png");
        for (int k : stripK) {
            std::printf("  bin %4d (%.3f ns)", k,
                        (prepared.time.startOpl + (k + 0.5) * prepared.time.binWidth) / kC_m_per_ns);
            for (const MethodResult& m : results) std::printf("  %s %.4g", m.method.c_str(), m.finalPerFrame[k]);
            std::printf("\n");
        }
    }
    std::printf("wrote %s/convergence.csv, convergence.json, convergence.gp%s%s%s\n", c.out.c_str(),
                plotted ? ", convergence{,_l1}.svg, convergence{,_l1}.png" : "",
                c.perFrame ? ", convergence_frames.csv" : "", stripK.empty() ? "" : ", equal_time.png, equal_time.csv");
    if (interrupted() && exitCode() == 0) exitCode() = exitCodeAfterInterrupt();
}

}  // namespace

void registerConverge(CLI::App& app) {
    {
        auto c = std::make_shared<ConvergeCmd>();
        CLI::App* cmd = app.add_subcommand(
            "converge",
            "Error against a reference as a function of render time: convergence.csv, a log-log plot, "
            "the fitted slope, an equal-time strip");
        cmd->add_option("scene", c->scene, "Scene file (JSON or Mitsuba 3 XML)")->required();
        cmd->add_option("--reference", c->reference,
                        "Reference file made by `tpb reference` (--width, --height, "
                        "--bins and --max-depth default to its values)")
            ->required();
        cmd->add_option("-o,--out", c->out, "Output folder (created if needed)");
        cmd->add_option("--method", c->method,
                        "What to measure, one after the other with the same budget each, comma-separated: beams (the "
                        "scene's estimator, with --estimator/--time-kernel) | pt | both (= beams,pt) | an estimator "
                        "with an optional time kernel, e.g. beam1d,beam2d,point2d+box,point3d+box:0.05");
        cmd->add_option("--clock", c->clock,
                        "Time axis: wall (seconds of rendering) | cpu (process CPU seconds, "
                        "all threads; steadier on a shared machine)")
            ->check(CLI::IsMember({"wall", "cpu"}));
        cmd->add_option("--axis", c->axis, "Time axis of the volume error: real | unwarped")
            ->check(CLI::IsMember({"real", "unwarped"}));
        cmd->add_option("--checkpoints", c->checkpoints, "Geometric checkpoints from --first-checkpoint to the budget")
            ->transform(flags::integer(1, 100000, "checkpoints per method"));
        cmd->add_option("--first-checkpoint", c->firstCheckpoint, "First geometric checkpoint, s")
            ->check(flags::number(0.0, std::numeric_limits<double>::infinity(), true, "seconds"));
        cmd->add_option("--at", c->at, "Extra checkpoint times, s (reported by interpolation too), e.g. 10,60,300")
            ->delimiter(',')
            ->check(flags::number(0.0, std::numeric_limits<double>::infinity(), true, "seconds"));
        cmd->add_option("--every-pass", c->everyPass, "Also record each of the first N passes")
            ->transform(flags::integer(0, INT_MAX, "passes"));
        cmd->add_flag("--per-frame", c->perFrame,
                      "Also write the error of every frame at every checkpoint "
                      "(convergence_frames.csv)");
        cmd->add_option("--frames", c->frames, "Write equal_time.png: K frames per method (rows), same exposure")
            ->transform(flags::integer(0, 4096, "frames per row; 0 = no equal_time.png"));
        cmd->add_option("--strip-ev", c->stripEv, "Extra exposure of equal_time.png, EV")
            ->check(flags::number(-64.0, 64.0, false, "EV"));
        cmd->add_flag("--strip-reference", c->stripReference, "Add the reference as the last row of equal_time.png");
        cmd->add_option("--spp", c->spp, "Path tracer: camera paths per pixel per pass")
            ->transform(flags::integer(1, 1 << 20, "camera paths per pixel per pass"));
        cmd->add_option("--mask-lights", c->maskLights,
                        "Leave out pixels within R pixels of a point/spot light's image from the errors")
            ->check(flags::number(0.0, 1e6, false, "pixels"));
        cmd->add_option("--targets", c->targets, "Errors for the time-to-reach report")
            ->delimiter(',')
            ->check(flags::number(0.0, std::numeric_limits<double>::infinity(), true, "relative errors"));
        cmd->add_flag("--no-plot", c->noPlot, "Do not run gnuplot (convergence.gp is still written)");
        cmd->add_flag("-q,--quiet", c->quiet, "Only the final report");
        c->ov.add(cmd);
        cmd->callback([c] { runConverge(*c); });
    }
}

}  // namespace tpb::app
