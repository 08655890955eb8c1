#include "film/picture_export.h"

#include "base/error.h"
#include "base/math.h"
#include "film/film_view.h"
#include "io/image_io.h"
#include "io/video_encoder.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tpb {

namespace {

// A 3x5 pixel font for the labels: the glyphs a time in ns needs.
const char* glyph(char c) {
    switch (c) {
        case '0': return "111101101101111";
        case '1': return "010110010010111";
        case '2': return "111001111100111";
        case '3': return "111001111001111";
        case '4': return "101101111001001";
        case '5': return "111100111001111";
        case '6': return "111100111101111";
        case '7': return "111001010010010";
        case '8': return "111101111101111";
        case '9': return "111101111001111";
        case '.': return "000000000000010";
        case '-': return "000000111000000";
        case 'e': return "000111111100111";
        case 'n': return "000110101101101";
        case 's': return "000011110001110";
        default: return "000000000000000";  // space and anything else
    }
}

int labelWidth(const std::string& s, int scale) {
    return s.empty() ? 0 : static_cast<int>(s.size()) * 4 * scale - scale;
}

void drawLabel(std::vector<unsigned char>& img, int imgW, int x0, int y0, const std::string& s, int scale) {
    for (size_t i = 0; i < s.size(); ++i) {
        const char* g = glyph(s[i]);
        for (int gy = 0; gy < 5; ++gy)
            for (int gx = 0; gx < 3; ++gx) {
                if (g[gy * 3 + gx] != '1') continue;
                for (int sy = 0; sy < scale; ++sy)
                    for (int sx = 0; sx < scale; ++sx) {
                        const size_t p = (static_cast<size_t>(y0 + gy * scale + sy) * imgW + x0 +
                                          static_cast<int>(i) * 4 * scale + gx * scale + sx) *
                                         3;
                        img[p] = img[p + 1] = img[p + 2] = 230;
                    }
            }
    }
}

std::string timeLabel(const FilmSnapshot& film, int bin) {
    const TimeBins& t = film.time();
    char b[32];
    std::snprintf(b, sizeof b, "%.4g ns", (t.startOpl + (bin + 0.5) * t.binWidth) / kC_m_per_ns);
    return b;
}

}  // namespace

ToneMap autoExposedToneMap(const FilmSnapshot& film, const ExportOptions& opt, ToneMap base) {
    int bin = film.bins() - 1;
    if (opt.mode == EmissionMode::Delta) {
        const std::vector<double> e = binEnergy(film, opt.axis);
        bin = static_cast<int>(std::max_element(e.begin(), e.end()) - e.begin());
    }
    const ExposureFit fit = fitExposure(frameImage(film, bin, opt.axis, opt.mode, opt.response));
    if (fit.found) base.exposureEv += fit.ev;
    return base;
}

float writeAutoExposedPng(const std::string& path, int width, int height, const std::vector<float>& rgb, ToneMap base) {
    const ExposureFit fit = fitExposure(rgb);
    if (fit.found) base.exposureEv += fit.ev;
    writePng8(path, width, height, toneMapImage(rgb, base));
    return base.exposureEv;
}

int exportMp4(const FilmSnapshot& film, const std::string& path, const ExportOptions& opt, const ToneMap& tone,
              double fps, const std::function<void(int, int)>& progress, const std::atomic<bool>* cancel) {
    const int total = exportFrameCount(film.bins(), opt);
    if (total <= 0) throw UserError(path, 0, "", "no frame to encode: the selected bins are empty");
    const int last = opt.lastBin < 0 ? film.bins() - 1 : std::min(opt.lastBin, film.bins() - 1);
    VideoEncoder enc(path, film.width(), film.height(), fps);
    int done = 0;
    for (int k = opt.firstBin; k <= last; k += std::max(1, opt.step)) {
        if (cancel && cancel->load()) {
            enc.abort();
            return 0;
        }
        enc.addFrame(toneMapImage(frameImage(film, k, opt.axis, opt.mode, opt.response), tone).data());
        ++done;
        if (progress) progress(done, total);
    }
    enc.finish();
    return done;
}

ContactSheet makeContactSheet(const FilmSnapshot& film, int count, const ExportOptions& opt, const ToneMap& tone) {
    ContactSheet s;
    s.bins = energeticBins(film, count, opt.axis);
    const int n = static_cast<int>(s.bins.size());
    const int W = film.width(), H = film.height();
    const int scale = W >= 96 ? 2 : 1;
    int labelW = 0;
    for (int k : s.bins) {
        s.labels.push_back(timeLabel(film, k));
        labelW = std::max(labelW, labelWidth(s.labels.back(), scale));
    }
    const int gap = ContactSheet::kSheetGap, labelH = 5 * scale + 2 * gap;
    s.columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
    s.rows = (n + s.columns - 1) / s.columns;
    s.cellWidth = std::max(W, labelW);
    s.cellHeight = H + labelH;
    s.width = s.columns * s.cellWidth + (s.columns + 1) * gap;
    s.height = s.rows * s.cellHeight + (s.rows + 1) * gap;
    s.rgb.assign(static_cast<size_t>(s.width) * s.height * 3, 24);  // dark grey background
    for (int i = 0; i < n; ++i) {
        const int cx = gap + (i % s.columns) * (s.cellWidth + gap), cy = gap + (i / s.columns) * (s.cellHeight + gap);
        const int fx = cx + (s.cellWidth - W) / 2;
        s.frameX.push_back(fx);
        s.frameY.push_back(cy);
        const std::vector<unsigned char> px =
            toneMapImage(frameImage(film, s.bins[i], opt.axis, opt.mode, opt.response), tone);
        for (int y = 0; y < H; ++y)
            std::copy_n(&px[static_cast<size_t>(y) * W * 3], static_cast<size_t>(W) * 3,
                        &s.rgb[(static_cast<size_t>(cy + y) * s.width + fx) * 3]);
        drawLabel(s.rgb, s.width, cx + (s.cellWidth - labelWidth(s.labels[i], scale)) / 2, cy + H + gap, s.labels[i],
                  scale);
    }
    return s;
}

std::vector<int> exportContactSheet(const FilmSnapshot& film, const std::string& path, int count,
                                    const ExportOptions& opt, const ToneMap& tone) {
    const ContactSheet s = makeContactSheet(film, count, opt, tone);
    writePng8(path, s.width, s.height, s.rgb);
    return s.bins;
}

}  // namespace tpb
