#include "film_export.h"

#include <cstdio>
#include <sstream>

namespace tpb {

std::string frameFileName(int bin) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "frame_%05d.exr", bin);
    return buf;
}

void exportFrame(const TransientFilm& film, int bin, const std::string& path, const ExportOptions& opt) {
    std::vector<float> img;
    film.frame(bin, opt.axis, opt.mode, img);
    writeExr(path, film.width(), film.height(), img, opt.pixel);
}

int exportFrames(const TransientFilm& film, const std::string& dir, const ExportOptions& opt,
                 const std::function<void(int, int)>& progress, const std::atomic<bool>* cancel) {
    ensureWritableDir(dir);
    const int last = opt.lastBin < 0 ? film.bins() - 1 : std::min(opt.lastBin, film.bins() - 1);
    const int step = std::max(1, opt.step);
    const int total = last >= opt.firstBin ? (last - opt.firstBin) / step + 1 : 0;
    int done = 0;
    for (int k = opt.firstBin; k <= last; k += step) {
        if (cancel && cancel->load()) break;
        exportFrame(film, k, dir + "/" + frameFileName(k), opt);
        ++done;
        if (progress) progress(done, total);
    }
    return done;
}

void exportSteady(const TransientFilm& film, const std::string& path, ExrPixel pixel) {
    std::vector<float> img;
    film.steadyImage(img);
    writeExr(path, film.width(), film.height(), img, pixel);
}

void exportStreak(const TransientFilm& film, int row, const std::string& path, const ExportOptions& opt) {
    std::vector<float> img;
    film.streak(row, opt.axis, opt.mode, img);
    writeExr(path, film.width(), film.bins(), img, opt.pixel);
}

void exportProfileCsv(const TransientFilm& film, int x, int y, const std::string& path, const ExportOptions& opt) {
    std::vector<float> prof;
    film.pixelProfile(x, y, opt.axis, opt.mode, prof);
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

}  // namespace tpb
