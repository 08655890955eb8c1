// `tpb bench`: throughput of the progressive core on a scene, for several bin counts in one run
// (medians over passes; the machines are shared and noisy, so compare ratios measured together).
#include "cli/common.h"
#include "cli/flags.h"
#include "cli/interrupt.h"
#include "cli/commands.h"
#include "base/error.h"

#include <algorithm>
#include <climits>
#include <cstdio>

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
    int passes = 5;
    RenderOverrides ov;
};

void run(BenchCmd& c) {
    InterruptScope interrupts;  // Ctrl-C/SIGTERM: stop after the pass in progress, print what was measured
    if (c.binsList.empty()) throw UserError("--bins-list needs at least one bin count, e.g. 1,256,1024");
    std::printf("%8s %12s %12s %12s %14s %16s %12s %10s\n", "bins", "pass_s(med)", "photon_s", "camera_s", "beams/s",
                "estimates/s", "film", "peak_rss");
    double base = 0.0;
    std::vector<std::pair<int, double>> results;
    for (int bins : c.binsList) {
        if (interrupted()) break;
        RenderOverrides ov = c.ov;
        ov.bins = bins;
        const PreparedRender prepared = loadAndBuild(c.scene, ov);
        Driver drv(*prepared.scene, prepared.settings, prepared.time);
        std::vector<double> passSec, photonSec, cameraSec, beamsPerSec, estPerSec;
        for (int p = 1; p <= c.passes; ++p) {
            if (interrupted() || !drv.runPass(p)) break;
            const PassStats s = drv.lastPass();
            passSec.push_back(s.passSec);
            photonSec.push_back(s.photonSec);
            cameraSec.push_back(s.cameraSec);
            beamsPerSec.push_back(s.beams / std::max(s.photonSec, 1e-9));
            estPerSec.push_back(s.camera.beamEstimates / std::max(s.cameraSec, 1e-9));
        }
        if (passSec.empty()) break;  // interrupted before a pass of this configuration finished
        const double med = median(passSec);
        if (results.empty()) base = med;
        results.emplace_back(bins, med);
        std::printf("%8d %12.3f %12.3f %12.3f %14.4g %16.4g %12s %10s\n", bins, med, median(photonSec), median(cameraSec),
                    median(beamsPerSec), median(estPerSec), humanBytes(drv.film().bytes()).c_str(),
                    humanBytes(peakRssBytes()).c_str());
    }
    if (interrupted()) {
        std::fprintf(stderr, "interrupted by %s: %zu of %zu configurations measured\n", interruptName().c_str(),
                     results.size(), c.binsList.size());
        exitCode() = 128 + interruptSignal();
    }
    for (const auto& [bins, med] : results)
        std::printf("ratio time/pass %d bins : %d bins = %.3f\n", bins, c.binsList.front(), base > 0 ? med / base : 0.0);
    std::printf("(peak_rss is the process's high-water mark so far; beams/s = beams stored per second of photon tracing;\n"
                " estimates/s = ray-beam estimates per second of camera pass; all threads)\n");
}

}  // namespace

void registerBench(CLI::App& app) {
    auto c = std::make_shared<BenchCmd>();
    CLI::App* cmd = app.add_subcommand("bench", "Measure time per pass, beams/s, estimates/s and memory for several bin counts");
    cmd->add_option("scene", c->scene, "Scene file (default: scenes/cornell_medium.json)");
    cmd->add_option("--bins-list", c->binsList, "Bin counts to measure (the first is the ratio's base)")
        ->delimiter(',')
        ->transform(flags::integer(1, INT_MAX, "each a number of time bins, e.g. 1,256,1024"));
    cmd->add_option("--bench-passes", c->passes, "Passes per configuration (median reported)")
        ->transform(flags::integer(1, 100000, "passes measured per bin count"));
    c->ov.add(cmd);
    cmd->callback([c] { run(*c); });
}

}  // namespace tpb::app
