// `tpb bench`: throughput of the progressive core on a scene, for several bin counts in one run
// (medians over passes; the machines are shared and noisy, so compare ratios measured together).
#include "cli/common.h"
#include "cli/flags.h"
#include "cli/interrupt.h"
#include "cli/commands.h"
#include "base/error.h"
#include "io/atomic_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <climits>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <thread>

namespace tpb::app {

namespace {

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct BenchCmd {
    std::string scene = "scenes/cornell_medium.json";
    std::vector<int> binsList{1, 256, 1024};
    std::vector<int> threadsList;  // --threads-list: thread counts measured per bin count (empty: --threads)
    int passes = 5;
    std::string json;  // --json FILE: the measurements, with the command, for before/after tables
    RenderOverrides ov;
};

// The command line as the process received it (/proc/self/cmdline, NUL-separated), for the record.
std::string commandLine() {
    std::ifstream in("/proc/self/cmdline", std::ios::binary);
    std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()), out;
    for (char ch : raw) out += ch == '\0' ? ' ' : ch;
    while (!out.empty() && out.back() == ' ') out.pop_back();
    return out;
}

void run(BenchCmd& c) {
    InterruptScope interrupts;  // Ctrl-C/SIGTERM: stop after the pass in progress, print what was measured
    if (c.binsList.empty()) throw UserError("--bins-list needs at least one bin count, e.g. 1,256,1024");
    std::printf("%8s %8s %12s %12s %12s %14s %16s %12s %10s\n", "bins", "threads", "pass_s(med)", "photon_s",
                "camera_s", "beams/s", "estimates/s", "film", "peak_rss");
    if (!c.threadsList.empty() && c.ov.threads)
        throw UserError("--threads-list and --threads both set the thread count: keep one (e.g. --threads-list 1,2)");
    // One configuration per (bins, threads); without --threads-list, one thread count (--threads).
    std::vector<std::optional<int>> threadCounts;
    for (int t : c.threadsList) threadCounts.emplace_back(t);
    if (threadCounts.empty()) threadCounts.push_back(c.ov.threads);
    struct Result {
        int bins, threads;
        double median;
    };
    std::vector<Result> results;
    nlohmann::json configs = nlohmann::json::array();
    for (int bins : c.binsList)
        for (const std::optional<int>& tc : threadCounts) {
            if (interrupted()) break;
            RenderOverrides ov = c.ov;
            ov.bins = bins;
            ov.threads = tc;
            const PreparedRender prepared = loadAndBuild(c.scene, ov);
            Driver drv(*prepared.scene, prepared.settings, prepared.time);
            std::vector<double> passSec, photonSec, buildSec, cameraSec, beamsPerSec, estPerSec;
            // Camera-pass thread-nanoseconds (camera_s x threads) per unit of work: per camera ray, per
            // estimate (volume + surface), per bin written. Each divides the whole camera pass by one
            // count, so they are costs per unit of that work, not exclusive shares.
            std::vector<double> nsPerRay, nsPerEstimate, nsPerBin, rays, estimates, bins1;
            const int threads = prepared.settings.threads > 0
                                    ? prepared.settings.threads
                                    : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
            for (int p = 1; p <= c.passes; ++p) {
                if (interrupted() || !drv.runPass(p)) break;
                const PassStats s = drv.lastPass();
                passSec.push_back(s.passSec);
                photonSec.push_back(s.photonSec);
                buildSec.push_back(s.buildSec);
                cameraSec.push_back(s.cameraSec);
                beamsPerSec.push_back(s.beams / std::max(s.photonSec, 1e-9));
                estPerSec.push_back(s.camera.beamEstimates / std::max(s.cameraSec, 1e-9));
                const double threadNs = s.cameraSec * threads * 1e9;
                const double est = static_cast<double>(s.camera.beamEstimates + s.camera.photonEstimates);
                rays.push_back(static_cast<double>(s.camera.cameraRays));
                estimates.push_back(est);
                bins1.push_back(static_cast<double>(s.camera.binsSplatted));
                nsPerRay.push_back(threadNs / std::max<double>(1.0, static_cast<double>(s.camera.cameraRays)));
                nsPerEstimate.push_back(threadNs / std::max(1.0, est));
                nsPerBin.push_back(threadNs / std::max(1.0, static_cast<double>(s.camera.binsSplatted)));
            }
            if (passSec.empty()) break;  // interrupted before a pass of this configuration finished
            const double med = median(passSec);
            results.push_back({bins, threads, med});
            std::printf("%8d %8d %12.3f %12.3f %12.3f %14.4g %16.4g %12s %10s\n", bins, threads, med, median(photonSec),
                        median(cameraSec), median(beamsPerSec), median(estPerSec),
                        humanBytes(drv.film().bytes()).c_str(), humanBytes(peakRssBytes()).c_str());
            const double pixelBins =
                static_cast<double>(prepared.scene->camera.width) * prepared.scene->camera.height * prepared.time.bins;
            configs.push_back(
                {{"bins", bins},
                 {"passes", passSec.size()},
                 {"threads", threads},
                 {"volume_estimator", prepared.settings.volumeEstimator},
                 {"median_s",
                  {{"pass", med},
                   {"photon", median(photonSec)},
                   {"build", median(buildSec)},
                   {"camera", median(cameraSec)}}},
                 {"share_of_pass",
                  {{"photon", median(photonSec) / std::max(med, 1e-12)},
                   {"build", median(buildSec) / std::max(med, 1e-12)},
                   {"camera", median(cameraSec) / std::max(med, 1e-12)}}},
                 {"per_pass",
                  {{"camera_rays", median(rays)}, {"estimates", median(estimates)}, {"bins_splatted", median(bins1)}}},
                 {"camera_thread_ns",
                  {{"per_camera_ray", median(nsPerRay)},
                   {"per_estimate", median(nsPerEstimate)},
                   {"per_splatted_bin", median(nsPerBin)}}},
                 {"beams_per_photon_s", median(beamsPerSec)},
                 {"film_bytes", drv.film().bytes()},
                 {"film_bytes_per_pixel_bin", static_cast<double>(drv.film().bytes()) / std::max(1.0, pixelBins)},
                 {"peak_rss_bytes", peakRssBytes()}});
        }
    if (!c.json.empty()) {
        nlohmann::json j;
        j["command"] = commandLine();
        j["scene"] = c.scene;
        j["note"] =
            "medians over passes; camera_thread_ns = camera-pass seconds x threads per unit of work "
            "(not exclusive shares); peak_rss_bytes is the process's high-water mark so far";
        j["configs"] = configs;
        writeFileAtomic(c.json, j.dump(2) + "\n");
        std::printf("wrote %s\n", c.json.c_str());
    }
    if (interrupted()) {
        std::fprintf(stderr, "interrupted by %s: %zu of %zu configurations measured\n", interruptName().c_str(),
                     results.size(), c.binsList.size() * threadCounts.size());
        exitCode() = 128 + interruptSignal();
    }
    // Ratios within this run: each bin count against the first one at the same thread count, and
    // each thread count's speed-up over the first one at the same bin count.
    const auto find = [&](int bins, int threads) -> const Result* {
        for (const Result& r : results)
            if (r.bins == bins && r.threads == threads) return &r;
        return nullptr;
    };
    for (const Result& r : results)
        if (const Result* b = find(c.binsList.front(), r.threads); b && b->median > 0)
            std::printf("ratio time/pass %d bins : %d bins = %.3f%s\n", r.bins, c.binsList.front(),
                        r.median / b->median,
                        threadCounts.size() > 1 ? (" (" + std::to_string(r.threads) + " threads)").c_str() : "");
    if (threadCounts.size() > 1)
        for (const Result& r : results)
            if (const Result* b = find(r.bins, results.front().threads); b && r.median > 0 && b != &r)
                std::printf("speed-up %d threads over %d at %d bins = %.3f\n", r.threads, b->threads, r.bins,
                            b->median / r.median);
    std::printf(
        "(peak_rss is the process's high-water mark so far; beams/s = beams stored per second of photon tracing;\n"
        " estimates/s = ray-beam estimates per second of camera pass; all threads)\n");
}

}  // namespace

void registerBench(CLI::App& app) {
    auto c = std::make_shared<BenchCmd>();
    CLI::App* cmd =
        app.add_subcommand("bench", "Measure time per pass, beams/s, estimates/s and memory for several bin counts");
    cmd->add_option("scene", c->scene, "Scene file, JSON or Mitsuba 3 XML (default: scenes/cornell_medium.json)");
    cmd->add_option("--bins-list", c->binsList, "Bin counts to measure (the first is the ratio's base)")
        ->delimiter(',')
        ->transform(flags::integer(1, INT_MAX, "each a number of time bins, e.g. 1,256,1024"));
    cmd->add_option("--threads-list", c->threadsList,
                    "Thread counts to measure at each bin count (speed-ups reported against the first)")
        ->delimiter(',')
        ->transform(flags::integer(1, 1024, "each a number of worker threads, e.g. 1,2"));
    cmd->add_option("--bench-passes", c->passes, "Passes per configuration (median reported)")
        ->transform(flags::integer(1, 100000, "passes measured per bin count"));
    cmd->add_option("--json", c->json,
                    "Also write the measurements (medians, stage shares, thread-ns per camera ray, "
                    "estimate and splatted bin, memory, the command) to FILE");
    c->ov.add(cmd);
    cmd->callback([c] { run(*c); });
}

}  // namespace tpb::app
