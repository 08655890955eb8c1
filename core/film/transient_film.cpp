#include "film/transient_film.h"

#include "film/film_view.h"

#include "base/error.h"
#include "base/memory.h"
#include "film/film_bytes.h"

#include <algorithm>
#include <cfloat>
#include <climits>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

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
    binsSplatted += o.binsSplatted;
    for (int a = 0; a < 2; ++a) {
        outside[a] += o.outside[a];
        before[a] += o.before[a];
        inside[a] += o.inside[a];
    }
    return *this;
}

namespace {

// One estimate onto both time axes and the steady state; `splat` is splatTime or the smoothed one.
// With a phasor film, also the estimate's phasors: `profile` is its profile (without the time
// kernel, film/phasor.h) and `floor` its causal floor.
template <class Splat>
void splatBothAxes(PixelAccumulator& acc, FilmTally& tally, const Color& L, double aReal, double bReal, double aUnw,
                   double bUnw, const SegmentProfile* profile, const ArrivalFloor& floor, Splat&& splat) {
    if (!isFinite(L) || !std::isfinite(aReal) || !std::isfinite(aUnw) || !std::isfinite(bReal) ||
        !std::isfinite(bUnw)) {
        ++tally.rejected;
        return;
    }
    if (isBlack(L)) return;
    // What lands in the bins is summed as it lands (exactly zero when nothing does, which the
    // all-black-film check relies on), what falls outside comes back split by side.
    // The bins each splat writes are contiguous: they are marked touched once, as a range.
    Color binned[2] = {Color(0.0), Color(0.0)};
    int64_t written = 0;
    const auto onAxis = [&](TimeAxis axis, double a, double b) TPB_HOT_LAMBDA {
        int kMin = INT_MAX, kMax = -1;
        Color& sum = binned[static_cast<int>(axis)];
        const auto binSink = [&](int k, const Color& c) TPB_HOT_LAMBDA {
            acc.addUnmarked(axis, k, c);
            kMin = std::min(kMin, k);
            kMax = std::max(kMax, k);
            sum += c;
            ++written;
        };
        OutsideFilm out;
        if constexpr (std::is_invocable_v<Splat&, double, double, decltype(binSink)&, TimeAxis>)
            out = splat(a, b, binSink, axis);
        else
            out = splat(a, b, binSink);
        if (kMax >= 0) acc.mark(axis, kMin, kMax);
        return out;
    };
    const OutsideFilm outReal = onAxis(TimeAxis::Real, aReal, bReal);
    const OutsideFilm outUnw = onAxis(TimeAxis::Unwarped, aUnw, bUnw);
    tally.binsSplatted += written;
    acc.addSteady(L);
    const OutsideFilm* outs[2] = {&outReal, &outUnw};
    for (int a = 0; a < 2; ++a) {
        // Most estimates land wholly inside the film: nothing to add outside (adding zeros would
        // change no sum).
        if (!isBlack(outs[a]->before) || !isBlack(outs[a]->after)) {
            acc.addOutside(static_cast<TimeAxis>(a), *outs[a]);
            const double before = luminance(outs[a]->before);
            tally.before[a] += before;
            tally.outside[a] += before + luminance(outs[a]->after);
        }
        tally.inside[a] += luminance(binned[a]);
    }
    if (const PhasorSpec* ph = acc.phasorSpec(); ph && profile) {
        addEstimatePhasor(*ph, L, *profile, aReal, bReal, floor.real, acc.phasor(TimeAxis::Real));
        addEstimatePhasor(*ph, L, *profile, aUnw, bUnw, floor.unwarped, acc.phasor(TimeAxis::Unwarped));
    }
}

}  // namespace

void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, const Color& kappa,
                 double s0, double s1, double aReal, double bReal, double aUnw, double bUnw) {
    const SegmentProfile profile(kappa, s0, s1);  // the same on both axes
    splatBothAxes(acc, tally, L, aReal, bReal, aUnw, bUnw, &profile, {},
                  [&](double a, double b, auto&& sink)
                      TPB_HOT_LAMBDA { return splatTime(time, L, profile, a, b, sink); });
}

void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L,
                 const SegmentProfile& profile, double aReal, double bReal, double aUnw, double bUnw,
                 const TimeKernel& kernel, const ArrivalFloor& floor) {
    if (kernel.active()) {
        splatSpread(time, acc, tally, L, profile.kappa, profile.s0, profile.s1, aReal, bReal, aUnw, bUnw, kernel,
                    floor);
        return;
    }
    if (floor.active()) {
        splatBothAxes(acc, tally, L, aReal, bReal, aUnw, bUnw, &profile, floor,
                      [&](double a, double b, auto&& sink, TimeAxis axis) {
                          return splatTimeFloored(time, L, profile, a, b,
                                                  axis == TimeAxis::Real ? floor.real : floor.unwarped, sink);
                      });
        return;
    }
    splatBothAxes(acc, tally, L, aReal, bReal, aUnw, bUnw, &profile, {},
                  [&](double a, double b, auto&& sink)
                      TPB_HOT_LAMBDA { return splatTime(time, L, profile, a, b, sink); });
}

void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, const Color& kappa,
                 double s0, double s1, double aReal, double bReal, double aUnw, double bUnw, const TimeKernel& kernel,
                 const ArrivalFloor& floor) {
    if (!kernel.active() && !floor.active()) {  // the kernel-free code itself: bit-identical films
        splatSpread(time, acc, tally, L, kappa, s0, s1, aReal, bReal, aUnw, bUnw);
        return;
    }
    if (!kernel.active()) {
        splatSpread(time, acc, tally, L, SegmentProfile(kappa, s0, s1), aReal, bReal, aUnw, bUnw, kernel, floor);
        return;
    }
    // The phasor film takes the profile without the kernel (film/phasor.h).
    std::optional<SegmentProfile> unsmoothed;
    if (acc.phasorSpec()) unsmoothed.emplace(kappa, s0, s1);
    splatBothAxes(acc, tally, L, aReal, bReal, aUnw, bUnw, unsmoothed ? &*unsmoothed : nullptr, floor,
                  [&](double a, double b, auto&& sink, TimeAxis axis) {
                      return splatTimeSmoothed(time, L, kappa, s0, s1, a, b, kernel, sink,
                                               axis == TimeAxis::Real ? floor.real : floor.unwarped);
                  });
}

void PixelAccumulator::reset(int bins, const PhasorSpec* phasor) {
    phasor_ = phasor && phasor->active() ? phasor : nullptr;
    phasorData_.assign(phasorStride() * 2, 0.0);
    phasorTouched_ = false;
    bins_ = bins;
    words_ = (bins + 63) / 64;
    data_.assign(static_cast<size_t>(bins) * 2 * 3, 0.0);
    marks_.assign(static_cast<size_t>(words_) * 2, 0);
    lo_[0] = lo_[1] = bins;
    hi_[0] = hi_[1] = -1;
    steady_ = Color(0.0);
    for (int a = 0; a < 2; ++a) before_[a] = after_[a] = Color(0.0);
}

void PixelAccumulator::clearTouched() {
    for (int a = 0; a < 2; ++a) {
        if (hi_[a] >= lo_[a]) {
            double* row = &data_[static_cast<size_t>(a) * bins_ * 3];
            forEachRun(static_cast<TimeAxis>(a), [row](int k0, int k1) {
                std::fill(row + static_cast<size_t>(k0) * 3, row + static_cast<size_t>(k1 + 1) * 3, 0.0);
            });
            uint64_t* w = &marks_[static_cast<size_t>(a) * words_];
            std::fill(w + (lo_[a] >> 6), w + (hi_[a] >> 6) + 1, uint64_t(0));
        }
        lo_[a] = bins_;
        hi_[a] = -1;
        before_[a] = after_[a] = Color(0.0);
    }
    steady_ = Color(0.0);
    if (phasorTouched_) {
        std::fill(phasorData_.begin(), phasorData_.end(), 0.0);
        phasorTouched_ = false;
    }
}

TransientFilm::TransientFilm(int width, int height, const TimeBins& time, const PhasorSpec& phasor)
    : layout_(std::make_shared<const FilmLayout>(width, height, time, phasor)),
      tiles_(new Tile[layout_->tiles.size()]) {
    for (int t = 0; t < tileCount(); ++t) {
        TileSums zero;
        zero.zero(layout_->pixels(t), time.bins, phasor.count());
        tiles_[t].block = std::make_shared<TileBlock>(std::move(zero));
    }
}

std::shared_ptr<const TileBlock> TransientFilm::current(int tile) const {
    // A lease: the returned pointer owns the block and counts as one of its readers until the
    // last copy of it is dropped (the deleter's release pairs with the writer's acquire in
    // TileBlock::readers(), so in-place adds never overlap a read).
    std::shared_ptr<TileBlock> block;
    {
        std::lock_guard<std::mutex> g(tiles_[tile].publish);
        block = tiles_[tile].block;
        block->readers_.fetch_add(1, std::memory_order_relaxed);
    }
    const TileBlock* raw = block.get();
    return std::shared_ptr<const TileBlock>(raw, [keep = std::move(block)](const TileBlock* b) mutable {
        b->readers_.fetch_sub(1, std::memory_order_release);
        keep.reset();
    });
}

void TransientFilm::publish(int tile, std::shared_ptr<TileBlock> block) {
    std::shared_ptr<TileBlock> old;  // freed outside the lock (if no snapshot holds it)
    {
        std::lock_guard<std::mutex> g(tiles_[tile].publish);
        old = std::exchange(tiles_[tile].block, std::move(block));
    }
}

uint64_t TransientFilm::bytes() const {
    // What the live film holds (the formula in film_bytes.cpp must agree: test_transient_film checks it).
    uint64_t n = 0;
    const std::shared_ptr<const FilmSnapshot> s = snapshot();
    for (int t = 0; t < s->tileCount(); ++t) {
        const TileSums& sums = s->block(t).sums;
        n += sums.steady.size() * sizeof(double);
        for (int a = 0; a < 2; ++a)
            n += sums.bins[a].size() * sizeof(FilmSum) +
                 (sums.before[a].size() + sums.after[a].size() + sums.phasor[a].size()) * sizeof(double);
    }
    return n;
}

std::shared_ptr<const FilmSnapshot> TransientFilm::snapshot() const {
    std::vector<std::shared_ptr<const TileBlock>> blocks(static_cast<size_t>(tileCount()));
    for (int t = 0; t < tileCount(); ++t) blocks[t] = current(t);
    return std::make_shared<const FilmSnapshot>(layout_, std::move(blocks));
}

void TransientFilm::clear() {
    for (int t = 0; t < tileCount(); ++t) {
        std::lock_guard<std::mutex> g(tiles_[t].writer);
        TileSums zero;
        zero.zero(layout_->pixels(t), bins(), phasor().count());
        publish(t, std::make_shared<TileBlock>(std::move(zero)));
    }
    stats.rejectedSamples = 0;
    stats.overflowedPixels = 0;
    stats.copiedTiles = 0;
    stats.stagedTiles = 0;
    for (int a = 0; a < 2; ++a) {
        stats.outside[a] = 0.0;
        stats.before[a] = 0.0;
        stats.inside[a] = 0.0;
    }
}

void TransientFilm::restoreTile(int tile, TileSums sums) {
    if (tile < 0 || tile >= tileCount())
        throw std::invalid_argument("TransientFilm::restoreTile: no tile " + std::to_string(tile));
    const size_t px = layout_->pixels(tile);
    bool ok = sums.binCount == bins() && sums.steady.size() == px * 3 && sums.phasorCount == phasor().count();
    for (int a = 0; a < 2; ++a)
        ok = ok && sums.bins[a].size() == px * static_cast<size_t>(bins()) * 3 && sums.before[a].size() == px * 3 &&
             sums.after[a].size() == px * 3 && sums.phasor[a].size() == px * sums.phasorStride();
    if (!ok)
        throw std::invalid_argument("TransientFilm::restoreTile: tile " + std::to_string(tile) + " has the wrong size");
    std::lock_guard<std::mutex> g(tiles_[tile].writer);
    publish(tile, std::make_shared<TileBlock>(std::move(sums)));
}

void TransientFilm::merge(const TransientFilm& other) {
    if (&other == this) throw std::invalid_argument("TransientFilm::merge: a film cannot be merged into itself");
    const TimeBins &ta = time(), &tb = other.time();
    if (other.width() != width() || other.height() != height() || ta.bins != tb.bins || ta.startOpl != tb.startOpl ||
        ta.binWidth != tb.binWidth || !(phasor() == other.phasor()))
        throw std::invalid_argument("TransientFilm::merge: the films differ in size or time axis (" +
                                    std::to_string(width()) + "x" + std::to_string(height()) + "x" +
                                    std::to_string(bins()) + " vs " + std::to_string(other.width()) + "x" +
                                    std::to_string(other.height()) + "x" + std::to_string(other.bins()) + ")");
    const std::shared_ptr<const FilmSnapshot> theirs = other.snapshot();
    for (int t = 0; t < tileCount(); ++t) {
        std::lock_guard<std::mutex> g(tiles_[t].writer);
        TileSums sum = current(t)->sums;
        const TileSums& add = theirs->block(t).sums;
        sum.passes += add.passes;
        sum.weight += add.weight;
        sum.absBound += add.absBound;
        const auto addAll = [](auto& dst, const auto& src) {
            for (size_t i = 0; i < dst.size(); ++i) dst[i] += src[i];
        };
        addAll(sum.steady, add.steady);
        for (int a = 0; a < 2; ++a) {
            addAll(sum.bins[a], add.bins[a]);
            addAll(sum.before[a], add.before[a]);
            addAll(sum.after[a], add.after[a]);
            addAll(sum.phasor[a], add.phasor[a]);
        }
        publish(t, std::make_shared<TileBlock>(std::move(sum)));
    }
    stats.rejectedSamples += other.stats.rejectedSamples.load();
    stats.overflowedPixels += other.stats.overflowedPixels.load();
    for (int a = 0; a < 2; ++a) {
        stats.outside[a] = stats.outside[a].load() + other.stats.outside[a].load();
        stats.before[a] = stats.before[a].load() + other.stats.before[a].load();
        stats.inside[a] = stats.inside[a].load() + other.stats.inside[a].load();
    }
}

namespace {

// A pixel's pass as the tile's add reads it: its touched runs, appended to the staging's runs and
// values, its outside and steady sums, and its largest |value|. The NaN guard is upstream:
// splatSpread rejects (and counts) non-finite estimates, so none reaches the accumulator; this
// scan would not catch one reliably (a NaN is kept only if no larger-compared value follows it).
TileStaging::Pixel pixelRecord(const PixelAccumulator& acc, uint32_t pixel, TileStaging& staging) {
    TileStaging::Pixel px;
    px.pixel = pixel;
    double largest = 0.0;
    const auto grow = [&largest](double x) {
        x = std::abs(x);
        if (!(x <= largest)) largest = x;
    };
    const auto grow3 = [&grow](const Color& c) {
        grow(c.x);
        grow(c.y);
        grow(c.z);
    };
    // The largest |value| of the touched bins: four independent maxima (no branch, no chain
    // through one register), the same value as a scan one by one.
    double m[4] = {0.0, 0.0, 0.0, 0.0};
    for (int a = 0; a < 2; ++a) {
        const TimeAxis axis = static_cast<TimeAxis>(a);
        px.before[a] = acc.before(axis);
        px.after[a] = acc.after(axis);
        grow3(px.before[a]);
        grow3(px.after[a]);
        px.firstRun[a] = static_cast<uint32_t>(staging.runs.size());
        px.offset[a] = staging.values.size();
        acc.forEachRun(axis, [&](int k0, int k1) {
            staging.runs.push_back({k0, k1 - k0 + 1});
            const double* v = acc.bin(axis, k0);
            const size_t n = static_cast<size_t>(k1 - k0 + 1) * 3;
            staging.values.insert(staging.values.end(), v, v + n);
            size_t j = 0;
            for (; j + 4 <= n; j += 4)
                for (int l = 0; l < 4; ++l) m[l] = std::max(m[l], std::abs(v[j + l]));
            for (; j < n; ++j) m[0] = std::max(m[0], std::abs(v[j]));
        });
        px.runCount[a] = static_cast<uint32_t>(staging.runs.size()) - px.firstRun[a];
    }
    grow(std::max(std::max(m[0], m[1]), std::max(m[2], m[3])));
    px.steady = acc.steady();
    grow3(px.steady);
    px.largest = largest;
    if (acc.phasorSpec() && acc.phasorTouched()) {
        px.hasPhasor = true;
        px.phasorOffset = staging.phasor.size();
        for (int a = 0; a < 2; ++a) {
            const double* v = acc.phasor(static_cast<TimeAxis>(a));
            staging.phasor.insert(staging.phasor.end(), v, v + acc.phasorStride());
        }
    }
    return px;
}

}  // namespace

TransientFilm::TileWriter::TileWriter(TransientFilm& film, int tile, TileStaging* staging, double passWeight)
    : film_(film), tile_(tile), lock_(film.tiles_[tile].writer), staging_(staging), passWeight_(passWeight) {
    if (!staging_) {
        next_ = std::make_shared<TileBlock>(film.current(tile)->sums);
        return;
    }
    staging_->clear();
}

TransientFilm::TileWriter::~TileWriter() {
    if (staging_) {
        commitStaged();
        return;
    }
    ++next_->sums.passes;
    next_->sums.weight += passWeight_;
    next_->sums.absBound += passMax_;
    film_.publish(tile_, std::move(next_));
}

void TransientFilm::TileWriter::commitStaged() {
    Tile& tile = film_.tiles_[tile_];
    film_.stats.stagedTiles.fetch_add(1, std::memory_order_relaxed);
    const auto addStaged = [&](TileSums& sums) {
        double passMax = 0.0;
        for (const TileStaging::Pixel& px : staging_->pixels) passMax = std::max(passMax, addTo(sums, *staging_, px));
        ++sums.passes;
        sums.weight += passWeight_;
        sums.absBound += passMax;
    };
    {
        std::lock_guard<std::mutex> g(tile.publish);
        if (tile.block->readers() == 0) {  // no snapshot holds it, and none can take it without this lock
            addStaged(tile.block->sums);
            tile.block->invalidateCumulative();
        } else {
            next_ = std::make_shared<TileBlock>(tile.block->sums);
            film_.stats.copiedTiles.fetch_add(1, std::memory_order_relaxed);
        }
    }
    if (next_) {  // a snapshot holds the block: add to a copy (outside the lock), then publish it
        addStaged(next_->sums);
        film_.publish(tile_, std::move(next_));
    }
    staging_->clear();
}

void TransientFilm::TileWriter::addPixel(int x, int y, PixelAccumulator& acc) {
    const TileRect r = film_.tileRect(tile_);
    const uint32_t pixel = static_cast<uint32_t>((y - r.y0) * r.w + (x - r.x0));
    if (staging_) {
        staging_->pixels.push_back(pixelRecord(acc, pixel, *staging_));
        acc.clearTouched();
        return;
    }
    own_.clear();
    const TileStaging::Pixel px = pixelRecord(acc, pixel, own_);
    passMax_ = std::max(passMax_, addTo(next_->sums, own_, px));
}

void stagePixel(TileStaging& staging, uint32_t pixelInTile, PixelAccumulator& acc) {
    staging.pixels.push_back(pixelRecord(acc, pixelInTile, staging));
    acc.clearTouched();
}

void TransientFilm::TileWriter::addStaged(const TileStaging& staged) {
    if (!staging_) {
        for (const TileStaging::Pixel& px : staged.pixels)
            passMax_ = std::max(passMax_, addTo(next_->sums, staged, px));
        return;
    }
    // Appended to this writer's staging, the records' run and value offsets moved past its own.
    const uint32_t runBase = static_cast<uint32_t>(staging_->runs.size());
    const size_t valueBase = staging_->values.size();
    staging_->runs.insert(staging_->runs.end(), staged.runs.begin(), staged.runs.end());
    staging_->values.insert(staging_->values.end(), staged.values.begin(), staged.values.end());
    const size_t phasorBase = staging_->phasor.size();
    staging_->phasor.insert(staging_->phasor.end(), staged.phasor.begin(), staged.phasor.end());
    for (TileStaging::Pixel px : staged.pixels) {
        for (int a = 0; a < 2; ++a) {
            px.firstRun[a] += runBase;
            px.offset[a] += valueBase;
        }
        px.phasorOffset += phasorBase;
        staging_->pixels.push_back(px);
    }
}

double TransientFilm::TileWriter::addTo(TileSums& t, const TileStaging& staged, const TileStaging::Pixel& px) {
    // The averages are read as float: a pass whose contribution would push a sum past FLT_MAX (a
    // light power near 1e38, or ~1e30 with a tiny kernel over many passes) is dropped for this
    // pixel and counted, so the film never holds (or shows) Inf. Checked first, then added, so a
    // pixel gets all of the pass or none of it. The check reads the pixel's own values only
    // while the tile's bound (TileSums::absBound) says no sum can get near FLT_MAX, and every sum
    // it adds to only when it does.
    const size_t pixel = px.pixel;
    // Calls f(k0, count, values) for each staged run of axis a (values: its rgb, count x 3).
    const auto forRuns = [&](int a, const auto& f) {
        const double* v = staged.values.data() + px.offset[a];
        for (uint32_t r = 0; r < px.runCount[a]; ++r) {
            const TileStaging::Run& run = staged.runs[px.firstRun[a] + r];
            f(run.bin, run.count, v);
            v += static_cast<size_t>(run.count) * 3;
        }
    };
    double largest = px.largest;
    const size_t i = pixel * 3;
    if (!(t.absBound + largest <= 0.25 * static_cast<double>(FLT_MAX))) {  // also catches NaN
        const auto fits = [](double sum, double add) {
            const double r = sum + add;
            return r >= -static_cast<double>(FLT_MAX) && r <= static_cast<double>(FLT_MAX);  // false for NaN too
        };
        bool ok = true;
        for (int a = 0; a < 2 && ok; ++a)
            forRuns(a, [&](int k0, int count, const double* v) {
                const FilmSum* dst = &t.bins[a][t.binIndex(pixel, k0)];
                for (int j = 0; j < count * 3 && ok; ++j) ok = fits(dst[j], v[j]);
            });
        const auto fits3 = [&](const std::vector<double>& sum, const Color& add) {
            return fits(sum[i], add.x) && fits(sum[i + 1], add.y) && fits(sum[i + 2], add.z);
        };
        ok = ok && fits3(t.steady, px.steady);
        for (int a = 0; a < 2 && ok; ++a) ok = fits3(t.before[a], px.before[a]) && fits3(t.after[a], px.after[a]);
        if (!ok) {
            film_.stats.overflowedPixels.fetch_add(1, std::memory_order_relaxed);
            return 0.0;
        }
        if (!std::isfinite(largest)) largest = 0.0;  // unreachable with finite sums; keeps the bound finite
    }
    // Each touched run is contiguous in both (the staging and the tile: [bin][rgb]); the bins
    // between runs are zero in this pass and are not read.
    for (int a = 0; a < 2; ++a)
        forRuns(a, [&](int k0, int count, const double* v) {
            FilmSum* dst = &t.bins[a][t.binIndex(pixel, k0)];
            const size_t n = static_cast<size_t>(count) * 3;
            for (size_t j = 0; j < n; ++j) dst[j] += static_cast<FilmSum>(v[j]);
        });
    const auto add3 = [i](std::vector<double>& dst, const Color& c) {
        dst[i] += c.x;
        dst[i + 1] += c.y;
        dst[i + 2] += c.z;
    };
    add3(t.steady, px.steady);
    for (int a = 0; a < 2; ++a) {
        add3(t.before[a], px.before[a]);
        add3(t.after[a], px.after[a]);
    }
    if (px.hasPhasor) {
        const size_t n = t.phasorStride();
        const double* v = staged.phasor.data() + px.phasorOffset;
        for (int a = 0; a < 2; ++a, v += n) {
            double* dst = t.phasor[a].data() + pixel * n;
            for (size_t j = 0; j < n; ++j) dst[j] += v[j];
        }
    }
    return largest;
}

void TransientFilm::frame(int bin, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const {
    out = frameImage(*snapshot(), bin, axis, mode);
}
void TransientFilm::steadyImage(std::vector<float>& out) const { out = tpb::steadyImage(*snapshot()); }
void TransientFilm::beforeImage(TimeAxis axis, std::vector<float>& out) const {
    out = tpb::beforeImage(*snapshot(), axis);
}
void TransientFilm::afterImage(TimeAxis axis, std::vector<float>& out) const {
    out = tpb::afterImage(*snapshot(), axis);
}
void TransientFilm::pixelProfile(int x, int y, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const {
    out = tpb::pixelProfile(*snapshot(), x, y, axis, mode);
}
void TransientFilm::streak(int row, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const {
    out = streakImage(*snapshot(), row, axis, mode);
}
void TransientFilm::volume(TimeAxis axis, EmissionMode mode, std::vector<double>& out) const {
    out = tpb::volume(*snapshot(), axis, mode);
}
int64_t TransientFilm::minPasses() const { return snapshot()->minPasses(); }

}  // namespace tpb
