#include "film/film_export.h"
#include "film/output_names.h"

#include "base/math.h"
#include "film/film_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace tpb {

void exportFrame(const FilmSnapshot& film, int bin, const std::string& path, const ExportOptions& opt) {
    writeExr(path, film.width(), film.height(), frameImage(film, bin, opt.axis, opt.mode, opt.response), opt.pixel);
}

namespace {
int lastExportBin(int bins, const ExportOptions& opt) {
    return opt.lastBin < 0 ? bins - 1 : std::min(opt.lastBin, bins - 1);
}
}  // namespace

int exportFrameCount(int bins, const ExportOptions& opt) {
    const int last = lastExportBin(bins, opt);
    return last >= opt.firstBin ? (last - opt.firstBin) / std::max(1, opt.step) + 1 : 0;
}

int exportFrames(const FilmSnapshot& film, const std::string& dir, const ExportOptions& opt,
                 const std::function<void(int, int)>& progress, const std::atomic<bool>* cancel) {
    ensureWritableDir(dir);
    const int last = lastExportBin(film.bins(), opt);
    const int step = std::max(1, opt.step);
    const int total = exportFrameCount(film.bins(), opt);
    int done = 0;
    for (int k = opt.firstBin; k <= last; k += step) {
        if (cancel && cancel->load()) break;
        exportFrame(film, k, dir + "/" + frameName(k), opt);
        ++done;
        if (progress) progress(done, total);
    }
    return done;
}

void exportSteady(const FilmSnapshot& film, const std::string& path, ExrPixel pixel) {
    writeExr(path, film.width(), film.height(), steadyImage(film), pixel);
}

void exportStreak(const FilmSnapshot& film, int row, const std::string& path, const ExportOptions& opt) {
    writeExr(path, film.width(), film.bins(), streakImage(film, row, opt.axis, opt.mode, opt.response), opt.pixel);
}

void exportProfileCsv(const FilmSnapshot& film, int x, int y, const std::string& path, const ExportOptions& opt) {
    const std::vector<float> prof = pixelProfile(film, x, y, opt.axis, opt.mode, opt.response);
    std::ostringstream os;
    os << "bin,t_opl_m,t_ns,r,g,b\n";
    const TimeBins& tb = film.time();
    for (int k = 0; k < film.bins(); ++k) {
        const double t = tb.startOpl + (k + 0.5) * tb.binWidth;
        os << k << ',' << t << ',' << t / kC_m_per_ns << ',' << prof[k * 3] << ',' << prof[k * 3 + 1] << ','
           << prof[k * 3 + 2] << '\n';
    }
    writeTextFile(path, os.str());
}

std::vector<int> energeticBins(const FilmSnapshot& film, int count, TimeAxis axis) {
    count = std::clamp(count, 1, film.bins());
    // From the 0.5% to the 90% quantile of the (delta) arrival-time distribution summed over the image.
    const std::vector<double> perBin = binEnergy(film, axis);
    double total = 0.0;
    for (double v : perBin) total += std::max(v, 0.0);
    int kLo = 0, kHi = film.bins() - 1;
    if (total > 0.0) {
        double cum = 0.0;
        kLo = -1;
        for (int k = 0; k < film.bins(); ++k) {
            cum += std::max(perBin[k], 0.0);
            if (kLo < 0 && cum >= 0.005 * total) kLo = k;
            if (cum >= 0.9 * total) {
                kHi = k;
                break;
            }
        }
        kLo = std::max(kLo, 0);
    }
    std::vector<int> bins;
    for (int i = 0; i < count; ++i)
        bins.push_back(
            std::min(kHi, kLo + static_cast<int>(std::lround(i * double(kHi - kLo) / std::max(1, count - 1)))));
    return bins;
}

std::vector<int> exportStripPng(const FilmSnapshot& film, const std::string& path, int count, const ExportOptions& opt,
                                const ToneMap& tone) {
    const std::vector<int> binsUsed = energeticBins(film, count, opt.axis);
    count = static_cast<int>(binsUsed.size());
    const int W = film.width(), H = film.height();
    std::vector<float> strip(static_cast<size_t>(W) * count * H * 3, 0.0f), img;
    for (int i = 0; i < count; ++i) {
        img = frameImage(film, binsUsed[i], opt.axis, opt.mode, opt.response);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int c = 0; c < 3; ++c)
                    strip[((static_cast<size_t>(y) * W * count) + static_cast<size_t>(i) * W + x) * 3 + c] =
                        img[(static_cast<size_t>(y) * W + x) * 3 + c];
    }
    writePng8(path, W * count, H, toneMapImage(strip, tone));
    return binsUsed;
}

}  // namespace tpb
