#include "film/film.h"

#include "base/error.h"
#include "render/memory_budget.h"

#include <algorithm>
#include <cfloat>
#include <cstring>

namespace tpb {

void FilmTally::flushInto(FilmStats& f) const {
    f.rejectedSamples.fetch_add(rejected);
    for (int a = 0; a < 2; ++a) {
        f.outside[a].fetch_add(outside[a]);
        f.before[a].fetch_add(before[a]);
        f.inside[a].fetch_add(inside[a]);
    }
}

FilmTally& FilmTally::operator+=(const FilmTally& o) {
    rejected += o.rejected;
    for (int a = 0; a < 2; ++a) {
        outside[a] += o.outside[a];
        before[a] += o.before[a];
        inside[a] += o.inside[a];
    }
    return *this;
}

void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, const Color& kappa,
                 double s0, double s1, double aReal, double bReal, double aUnw, double bUnw) {
    if (!isFinite(L) || !std::isfinite(aReal) || !std::isfinite(aUnw) || !std::isfinite(bReal) || !std::isfinite(bUnw)) {
        ++tally.rejected;
        return;
    }
    if (isBlack(L)) return;
    // What lands in the bins is summed as it lands (exactly zero when nothing does, which the
    // all-black-film check relies on), what falls outside comes back split by side.
    Color binned[2] = {Color(0.0), Color(0.0)};
    const OutsideFilm outReal = splatTime(time, L, kappa, s0, s1, aReal, bReal, [&](int k, const Color& c) {
        acc.add(TimeAxis::Real, k, c);
        binned[0] += c;
    });
    const OutsideFilm outUnw = splatTime(time, L, kappa, s0, s1, aUnw, bUnw, [&](int k, const Color& c) {
        acc.add(TimeAxis::Unwarped, k, c);
        binned[1] += c;
    });
    acc.addSteady(L);
    acc.addOutside(TimeAxis::Real, outReal);
    acc.addOutside(TimeAxis::Unwarped, outUnw);
    const OutsideFilm* outs[2] = {&outReal, &outUnw};
    for (int a = 0; a < 2; ++a) {
        const double before = luminance(outs[a]->before);
        tally.before[a] += before;
        tally.outside[a] += before + luminance(outs[a]->after);
        tally.inside[a] += luminance(binned[a]);
    }
}

void PixelAccumulator::reset(int bins) {
    bins_ = bins;
    data_.assign(static_cast<size_t>(bins) * 2 * 3, 0.0);
    lo_[0] = lo_[1] = bins;
    hi_[0] = hi_[1] = -1;
    steady_ = Color(0.0);
    for (int a = 0; a < 2; ++a) before_[a] = after_[a] = Color(0.0);
}

void PixelAccumulator::clearTouched() {
    for (int a = 0; a < 2; ++a) {
        if (hi_[a] >= lo_[a]) {
            double* p = &data_[(static_cast<size_t>(a) * bins_ + lo_[a]) * 3];
            std::fill(p, p + static_cast<size_t>(hi_[a] - lo_[a] + 1) * 3, 0.0);
        }
        lo_[a] = bins_;
        hi_[a] = -1;
        before_[a] = after_[a] = Color(0.0);
    }
    steady_ = Color(0.0);
}

TransientFilm::TransientFilm(int width, int height, const TimeBins& time)
    : width_(width), height_(height), tilesX_((width + kTile - 1) / kTile), time_(time) {
    TPB_CHECK(width > 0 && height > 0 && time.bins > 0);
    const int tilesY = (height + kTile - 1) / kTile;
    tiles_ = std::vector<Tile>(static_cast<size_t>(tilesX_) * tilesY);
    size_t offset = 0;
    for (int ty = 0; ty < tilesY; ++ty)
        for (int tx = 0; tx < tilesX_; ++tx) {
            Tile& t = tiles_[ty * tilesX_ + tx];
            t.rect = {tx * kTile, ty * kTile, std::min(kTile, width - tx * kTile), std::min(kTile, height - ty * kTile)};
            t.offset = offset;
            t.steady.assign(static_cast<size_t>(t.rect.w) * t.rect.h * 3, 0.0);
            for (int a = 0; a < 2; ++a) {
                t.before[a].assign(t.steady.size(), 0.0);
                t.after[a].assign(t.steady.size(), 0.0);
            }
            offset += static_cast<size_t>(t.rect.w) * t.rect.h * time.bins * 3;
        }
    sums_[0].assign(offset, 0.0f);
    sums_[1].assign(offset, 0.0f);
}

uint64_t TransientFilm::bytes() const {
    // What the film really holds (the formula in memory_budget.cpp must agree: test_film checks it).
    uint64_t n = (sums_[0].size() + sums_[1].size()) * sizeof(float);
    for (const Tile& t : tiles_) {
        n += t.steady.size() * sizeof(double);
        for (int a = 0; a < 2; ++a) n += (t.before[a].size() + t.after[a].size()) * sizeof(double);
    }
    return n;
}

void TransientFilm::clear() {
    for (Tile& t : tiles_) {
        std::lock_guard<std::mutex> g(t.mutex);
        t.passes = 0;
        std::fill(t.steady.begin(), t.steady.end(), 0.0);
        for (int a = 0; a < 2; ++a) {
            std::fill(t.before[a].begin(), t.before[a].end(), 0.0);
            std::fill(t.after[a].begin(), t.after[a].end(), 0.0);
            const size_t n = static_cast<size_t>(t.rect.w) * t.rect.h * time_.bins * 3;
            std::fill(sums_[a].begin() + t.offset, sums_[a].begin() + t.offset + n, 0.0f);
        }
    }
    stats.rejectedSamples = 0;
    stats.overflowedPixels = 0;
    for (int a = 0; a < 2; ++a) { stats.outside[a] = 0.0; stats.before[a] = 0.0; stats.inside[a] = 0.0; }
}

TransientFilm::TileWriter::TileWriter(TransientFilm& film, int tile)
    : film_(film), tile_(tile), lock_(film.tiles_[tile].mutex) {}

TransientFilm::TileWriter::~TileWriter() { ++film_.tiles_[tile_].passes; }

void TransientFilm::TileWriter::addPixel(int x, int y, const PixelAccumulator& acc) {
    Tile& t = film_.tiles_[tile_];
    const int px = x - t.rect.x0, py = y - t.rect.y0;
    // The sums are float: a pass whose contribution would push a sum past FLT_MAX (a light power
    // near 1e38, or ~1e30 with a tiny kernel over many passes) is dropped for this pixel and
    // counted, so the film never holds Inf. Checked first, then added, so a pixel gets all of the
    // pass or none of it.
    const auto fits = [](float sum, double add) {
        const double r = static_cast<double>(sum) + add;
        return r >= -static_cast<double>(FLT_MAX) && r <= static_cast<double>(FLT_MAX);  // false for NaN too
    };
    bool ok = true;
    for (int a = 0; a < 2 && ok; ++a) {
        const TimeAxis axis = static_cast<TimeAxis>(a);
        const float* sums = film_.sums_[a].data();
        for (int k = acc.lo(axis); k <= acc.hi(axis) && ok; ++k) {
            const double* v = acc.bin(axis, k);
            const float* dst = sums + film_.index(t, k, px, py);
            ok = fits(dst[0], v[0]) && fits(dst[1], v[1]) && fits(dst[2], v[2]);
        }
    }
    // The double images (steady, before, after) are read back as float too: same limit.
    const size_t i = (static_cast<size_t>(py) * t.rect.w + px) * 3;
    const auto fits3 = [&](const std::vector<double>& sum, const Color& add) {
        return fits(0.0f, sum[i] + add.x) && fits(0.0f, sum[i + 1] + add.y) && fits(0.0f, sum[i + 2] + add.z);
    };
    ok = ok && fits3(t.steady, acc.steady());
    for (int a = 0; a < 2 && ok; ++a)
        ok = fits3(t.before[a], acc.before(static_cast<TimeAxis>(a))) && fits3(t.after[a], acc.after(static_cast<TimeAxis>(a)));
    if (!ok) {
        film_.stats.overflowedPixels.fetch_add(1, std::memory_order_relaxed);
        return;
    }
    for (int a = 0; a < 2; ++a) {
        const TimeAxis axis = static_cast<TimeAxis>(a);
        float* sums = film_.sums_[a].data();
        for (int k = acc.lo(axis); k <= acc.hi(axis); ++k) {
            const double* v = acc.bin(axis, k);
            float* dst = sums + film_.index(t, k, px, py);
            dst[0] += static_cast<float>(v[0]);
            dst[1] += static_cast<float>(v[1]);
            dst[2] += static_cast<float>(v[2]);
        }
    }
    const auto add3 = [i](std::vector<double>& dst, const Color& c) {
        dst[i] += c.x;
        dst[i + 1] += c.y;
        dst[i + 2] += c.z;
    };
    add3(t.steady, acc.steady());
    for (int a = 0; a < 2; ++a) {
        add3(t.before[a], acc.before(static_cast<TimeAxis>(a)));
        add3(t.after[a], acc.after(static_cast<TimeAxis>(a)));
    }
}

bool TransientFilm::frame(int bin, TimeAxis axis, EmissionMode mode, std::vector<float>& out, bool wait) const {
    out.resize(static_cast<size_t>(width_) * height_ * 3);
    bin = std::clamp(bin, 0, time_.bins - 1);
    const float* sums = sums_[static_cast<int>(axis)].data();
    bool complete = true;
    std::vector<double> acc;
    for (const Tile& t : tiles_) {
        std::unique_lock<std::mutex> lock(t.mutex, std::defer_lock);
        if (wait) lock.lock();
        else if (!lock.try_lock()) { complete = false; continue; }
        const size_t n = static_cast<size_t>(t.rect.w) * t.rect.h * 3;
        const double inv = t.passes > 0 ? 1.0 / static_cast<double>(t.passes) : 0.0;
        const int k0 = mode == EmissionMode::Continuous ? 0 : bin;
        if (mode == EmissionMode::Continuous) acc = t.before[static_cast<int>(axis)];  // step response
        else acc.assign(n, 0.0);
        for (int k = k0; k <= bin; ++k) {
            const float* src = sums + index(t, k, 0, 0);
            for (size_t i = 0; i < n; ++i) acc[i] += src[i];
        }
        for (int py = 0; py < t.rect.h; ++py)
            for (int px = 0; px < t.rect.w; ++px)
                for (int c = 0; c < 3; ++c)
                    out[((static_cast<size_t>(t.rect.y0 + py) * width_) + t.rect.x0 + px) * 3 + c] =
                        static_cast<float>(acc[(static_cast<size_t>(py) * t.rect.w + px) * 3 + c] * inv);
    }
    return complete;
}

const std::vector<double>& TransientFilm::perPixel(const Tile& t, PerPixel which, TimeAxis axis) {
    const int a = static_cast<int>(axis);
    return which == PerPixel::Steady ? t.steady : which == PerPixel::Before ? t.before[a] : t.after[a];
}

bool TransientFilm::perPixelImage(PerPixel which, TimeAxis axis, std::vector<float>& out, bool wait) const {
    out.resize(static_cast<size_t>(width_) * height_ * 3);
    bool complete = true;
    for (const Tile& t : tiles_) {
        std::unique_lock<std::mutex> lock(t.mutex, std::defer_lock);
        if (wait) lock.lock();
        else if (!lock.try_lock()) { complete = false; continue; }
        const double inv = t.passes > 0 ? 1.0 / static_cast<double>(t.passes) : 0.0;
        const std::vector<double>& src = perPixel(t, which, axis);
        for (int py = 0; py < t.rect.h; ++py)
            for (int px = 0; px < t.rect.w; ++px)
                for (int c = 0; c < 3; ++c)
                    out[((static_cast<size_t>(t.rect.y0 + py) * width_) + t.rect.x0 + px) * 3 + c] =
                        static_cast<float>(src[(static_cast<size_t>(py) * t.rect.w + px) * 3 + c] * inv);
    }
    return complete;
}

bool TransientFilm::steadyImage(std::vector<float>& out, bool wait) const {
    return perPixelImage(PerPixel::Steady, TimeAxis::Real, out, wait);
}
bool TransientFilm::beforeImage(TimeAxis axis, std::vector<float>& out, bool wait) const {
    return perPixelImage(PerPixel::Before, axis, out, wait);
}
bool TransientFilm::afterImage(TimeAxis axis, std::vector<float>& out, bool wait) const {
    return perPixelImage(PerPixel::After, axis, out, wait);
}

void TransientFilm::pixelProfile(int x, int y, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const {
    out.assign(static_cast<size_t>(time_.bins) * 3, 0.0f);
    if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
    const Tile& t = tiles_[tileOf(x, y)];
    std::lock_guard<std::mutex> g(t.mutex);
    const double inv = t.passes > 0 ? 1.0 / static_cast<double>(t.passes) : 0.0;
    const float* sums = sums_[static_cast<int>(axis)].data();
    const int px = x - t.rect.x0, py = y - t.rect.y0;
    const double* before = &t.before[static_cast<int>(axis)][(static_cast<size_t>(py) * t.rect.w + px) * 3];
    double run[3] = {0.0, 0.0, 0.0};
    if (mode == EmissionMode::Continuous) std::copy(before, before + 3, run);
    for (int k = 0; k < time_.bins; ++k) {
        const float* v = sums + index(t, k, px, py);
        for (int c = 0; c < 3; ++c) {
            run[c] = (mode == EmissionMode::Continuous ? run[c] : 0.0) + v[c];
            out[static_cast<size_t>(k) * 3 + c] = static_cast<float>(run[c] * inv);
        }
    }
}

void TransientFilm::streak(int row, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const {
    out.assign(static_cast<size_t>(time_.bins) * width_ * 3, 0.0f);
    if (row < 0 || row >= height_) return;
    std::vector<float> prof;
    for (int x = 0; x < width_; ++x) {
        pixelProfile(x, row, axis, mode, prof);
        for (int k = 0; k < time_.bins; ++k)
            for (int c = 0; c < 3; ++c)
                out[(static_cast<size_t>(k) * width_ + x) * 3 + c] = prof[static_cast<size_t>(k) * 3 + c];
    }
}

void TransientFilm::volume(TimeAxis axis, EmissionMode mode, std::vector<double>& out) const {
    const size_t bins = static_cast<size_t>(time_.bins);
    out.assign(static_cast<size_t>(width_) * height_ * bins * 3, 0.0);
    const float* sums = sums_[static_cast<int>(axis)].data();
    for (const Tile& t : tiles_) {
        std::lock_guard<std::mutex> g(t.mutex);
        const double inv = t.passes > 0 ? 1.0 / static_cast<double>(t.passes) : 0.0;
        for (int py = 0; py < t.rect.h; ++py)
            for (int px = 0; px < t.rect.w; ++px) {
                double* dst = &out[((static_cast<size_t>(t.rect.y0 + py) * width_) + t.rect.x0 + px) * bins * 3];
                double run[3] = {0.0, 0.0, 0.0};
                if (mode == EmissionMode::Continuous) {
                    const double* before = &t.before[static_cast<int>(axis)][(static_cast<size_t>(py) * t.rect.w + px) * 3];
                    std::copy(before, before + 3, run);
                }
                for (size_t k = 0; k < bins; ++k) {
                    const float* v = sums + index(t, static_cast<int>(k), px, py);
                    for (int c = 0; c < 3; ++c) {
                        run[c] = (mode == EmissionMode::Continuous ? run[c] : 0.0) + v[c];
                        dst[k * 3 + c] = run[c] * inv;
                    }
                }
            }
    }
}

int64_t TransientFilm::minPasses() const {
    int64_t m = INT64_MAX;
    for (const Tile& t : tiles_) {
        std::lock_guard<std::mutex> g(t.mutex);
        m = std::min(m, t.passes);
    }
    return tiles_.empty() ? 0 : m;
}

}  // namespace tpb
