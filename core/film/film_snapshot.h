// An immutable view of the transient film's sums: what a reader (the viewer, an export, the CLI,
// a reference comparison) holds while passes go on. The film itself is transient_film.h; the
// images read from a snapshot (frames, steady, profile, streak, volume) are film_view.h.
//
// Tile blocks, written in place or copied on write: the image is split in 16x16 tiles and each
// tile's sums live in one TileBlock held by std::shared_ptr. Readers see it as const. A TileWriter
// (transient_film.h) gathers its pass's pixels into per-thread staging first and adds them to the
// tile when it finishes: in place, under the tile's publish lock, when no snapshot holds the block
// (TileBlock::readers() == 0; the usual case: the viewer and the CLI drop snapshots after reading them, so a headless render
// never copies a tile); otherwise it copies the block, adds to the copy and publishes the copy
// (a pointer swap under the same lock), leaving the snapshot's block untouched. A snapshot is the
// vector of the tiles' current block pointers: taking one costs one pointer copy per tile and
// waits at most for one tile's in-place add (the staged bins of 256 pixels, well under a
// millisecond at 256 bins), and is per-tile consistent (every tile holds the sum of the passes it
// has completed, its own pass count, never part of a pass). Tiles may differ by one pass while a
// pass is being rendered (minPasses() / maxPasses()).
//
// Memory: the live film (one block per tile) + the staging of each render thread (one tile of
// pixel accumulators) + a copy per tile written while a snapshot holds its block, and the blocks
// that snapshots still hold after the film replaced them: a snapshot held across a whole pass keeps
// up to one more film's worth alive, so readers should drop snapshots they no longer show. The
// continuous-emission prefix sums (cumulative()) are computed lazily per block and axis, and add
// bins x RGB doubles per pixel per axis read in continuous mode, for as long as that block lives
// unchanged (an in-place add drops them; a block that the next pass replaces takes them with it).
#pragma once
#include "base/large_buffer.h"
#include "film/phasor.h"
#include "film/time_splat.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace tpb {

enum class TimeAxis { Real = 0, Unwarped = 1 };

struct TileRect {
    int x0, y0, w, h;
};

// The type of the per-bin sums: double, so that films rendered separately (checkpoints, other
// machines) merge to what one run of all their passes gives, to < 1e-12 relative per value (one
// extra double rounding per value, ~1e-16, against ~1e-7 in float: tests/film/test_transient_film.cpp).
// Memory: bins x 2 axes x RGB x 8 bytes per pixel (film_bytes.h).
using FilmSum = double;
// The per-bin sums of a tile: large, so in huge pages (base/large_buffer.h).
using FilmSums = std::vector<FilmSum, LargeBufferAllocator<FilmSum>>;

// The sums of one tile over the passes it has completed (not averaged).
struct TileSums {
    int64_t passes = 0;
    // The sum of the passes' weights (RenderSettings::passWeight: 1 for a full pass, the share of
    // the photons for a warm-up pass): the film's average divides the sums by it. Equal to `passes`
    // when every pass was a full one.
    double weight = 0.0;
    // Per axis: [pixel in tile][bin][rgb] (binIndex), so a pass adds each pixel's time series to one
    // contiguous run (issue 15: the [bin][pixel] layout made every bin of the add a cache miss, a
    // fifth of a 1024-bin pass); a frame reads one value per pixel with a stride of bins x 3.
    FilmSums bins[2];
    int binCount = 0;
    std::vector<double> steady;               // [pixel][rgb]
    std::vector<double> before[2], after[2];  // per axis, [pixel][rgb]: light before the first bin / after the last
    // The phasor film (film/phasor.h), per axis: [pixel][frequency][Re rgb, Im rgb]; empty without.
    // Not in the overflow check: |a phasor sum| <= the steady sum of its pixel, which is checked.
    std::vector<double> phasor[2];
    int phasorCount = 0;
    // An upper bound of |every sum| in the tile (grows by each pass's largest value; merges add the
    // bounds): while bound + the largest value of a pixel's pass stays far from FLT_MAX, that pass
    // cannot push a sum out of float's range and the writer skips the per-value check.
    double absBound = 0.0;
    void zero(size_t pixels, int binCount, int phasorCount = 0);
    size_t phasorStride() const { return static_cast<size_t>(phasorCount) * 6; }  // per pixel and axis
    // Index in bins[axis] of the red value of `bin` of the tile's pixel `pixel`.
    size_t binIndex(size_t pixel, int bin) const {
        return (pixel * static_cast<size_t>(binCount) + static_cast<size_t>(bin)) * 3;
    }
};

class TileBlock {
public:
    explicit TileBlock(TileSums s) : sums(std::move(s)) {}
    TileSums sums;
    // Step response per pixel (emission_mode "continuous", transient_film.h): before + the running
    // sum of bins 0..k, in double, layout as sums.bins[axis]. Computed on first use (thread-safe,
    // once per block and axis): O(bins x pixels) once, then one read per pixel per frame.
    const std::vector<double>& cumulative(TimeAxis axis) const;
    // Drops the prefix sums after the sums changed in place (only by the tile's writer, while no
    // snapshot holds the block: no reader can be using them).
    void invalidateCumulative();

    // Readers that hold this block (snapshots and other leases from TransientFilm::current()).
    // Taken under the tile's publish lock; dropped with release order when a lease ends, so a
    // writer that reads 0 (acquire, under the same lock) happens after every read of the sums and
    // may add to them in place. (shared_ptr::use_count() cannot say this: it is a relaxed read.)
    int readers() const { return readers_.load(std::memory_order_acquire); }

private:
    friend class TransientFilm;
    mutable std::atomic<int> readers_{0};
    mutable std::mutex cumulativeMutex_;
    mutable bool cumulativeValid_[2] = {false, false};
    mutable std::vector<double> cumulative_[2];
};

// The film's geometry, shared by the film and its snapshots.
struct FilmLayout {
    static constexpr int kTile = 16;
    FilmLayout(int width, int height, const TimeBins& time, const PhasorSpec& phasor = {});
    int width, height, tilesX;
    TimeBins time;
    PhasorSpec phasor;
    std::vector<TileRect> tiles;
    int tileOf(int x, int y) const { return (y / kTile) * tilesX + (x / kTile); }
    size_t pixels(int tile) const { return static_cast<size_t>(tiles[tile].w) * tiles[tile].h; }
};

class FilmSnapshot {
public:
    FilmSnapshot(std::shared_ptr<const FilmLayout> layout, std::vector<std::shared_ptr<const TileBlock>> blocks);
    int width() const { return layout_->width; }
    int height() const { return layout_->height; }
    const TimeBins& time() const { return layout_->time; }
    int bins() const { return layout_->time.bins; }
    const PhasorSpec& phasor() const { return layout_->phasor; }
    int tileCount() const { return static_cast<int>(blocks_.size()); }
    const TileRect& tileRect(int tile) const { return layout_->tiles[tile]; }
    int tileOf(int x, int y) const { return layout_->tileOf(x, y); }
    const TileBlock& block(int tile) const { return *blocks_[tile]; }
    // The block itself: readers that cache what they derive from a snapshot key it on its blocks.
    const std::shared_ptr<const TileBlock>& blockPointer(int tile) const { return blocks_[tile]; }
    int64_t passes(int tile) const { return blocks_[tile]->sums.passes; }
    int64_t minPasses() const;  // passes completed by every tile
    int64_t maxPasses() const;  // passes completed by some tile
    // Every tile has completed the same passes, at least one (no pass is shown in part).
    bool complete() const { return minPasses() > 0 && minPasses() == maxPasses(); }

private:
    std::shared_ptr<const FilmLayout> layout_;
    std::vector<std::shared_ptr<const TileBlock>> blocks_;
};

}  // namespace tpb
