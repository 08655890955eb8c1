// The transient film: RGB radiance per pixel per time bin, on two time axes (real time, camera
// path included; camera-unwarped time, camera path excluded), plus the steady-state image. This
// file is the accumulation side (tiles, per-tile pass counts, TileWriter, merging films); readers
// take an immutable snapshot (film_snapshot.h) and read images from it (film_view.h).
//
// Units: a bin holds the part of the steady-state radiance carried by light whose arrival OPL falls
// in that bin (i.e. the delta-pulse response integrated over the bin). Per pixel and axis the film
// also keeps what arrived before its first bin and after its last, so that
//     steady = before + sum over bins + after      (per pixel, per axis, up to rounding).
// Continuous emission (light on from the pulse instant) is the step response: the frame of bin k is
// before + the running sum of bins 0..k (transport is linear and time-invariant), read from prefix
// sums (film_view.h); its last frame is steady - after.
//
// Concurrency: the image is split in 16x16 tiles. A tile has one writer at a time (the worker that
// renders it in the current pass, TileWriter) and its own pass count. The writer stages its pass
// (per-thread TileStaging) and adds it to the tile when it finishes, in place when no snapshot
// holds the tile's block, else to a copy it then publishes (film_snapshot.h), so a reader always
// sees, per tile, the sum of the passes that tile has completed - never a partially gathered pass.
// Either way each sum gets the same one addition per pass: the films are bit-identical.
// Sums are double (FilmSum, film_snapshot.h: per bin, and the steady-state, before and after sums);
// the images read from them are float (film_view.h).
#pragma once
#include "base/math.h"
#include "scene/scene_desc.h"
#include "estimators/time_kernel.h"
#include "estimators/time_splat.h"
#include "film/film_snapshot.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <vector>

namespace tpb {

// Accumulates one pixel's contributions during one pass, in double, touched bins only.
class PixelAccumulator {
public:
    explicit PixelAccumulator(int bins = 1) { reset(bins); }
    void reset(int bins);
    TPB_HOT_INLINE void add(TimeAxis axis, int bin, const Color& c) {
        double* p = &data_[(static_cast<size_t>(axis) * bins_ + bin) * 3];
        p[0] += c.x; p[1] += c.y; p[2] += c.z;
        int& lo = lo_[static_cast<int>(axis)];
        int& hi = hi_[static_cast<int>(axis)];
        lo = std::min(lo, bin);
        hi = std::max(hi, bin);
    }
    void addSteady(const Color& c) { steady_ += c; }
    void addOutside(TimeAxis axis, const OutsideFilm& o) {
        before_[static_cast<int>(axis)] += o.before;
        after_[static_cast<int>(axis)] += o.after;
    }
    const Color& steady() const { return steady_; }
    const Color& before(TimeAxis a) const { return before_[static_cast<int>(a)]; }
    const Color& after(TimeAxis a) const { return after_[static_cast<int>(a)]; }
    int lo(TimeAxis a) const { return lo_[static_cast<int>(a)]; }
    int hi(TimeAxis a) const { return hi_[static_cast<int>(a)]; }
    const double* bin(TimeAxis a, int k) const { return &data_[(static_cast<size_t>(a) * bins_ + k) * 3]; }
    void clearTouched();  // zero the touched range, ready for the next pixel

private:
    int bins_ = 0;
    std::vector<double> data_;
    int lo_[2], hi_[2];
    Color steady_{0.0};
    Color before_[2] = {Color(0.0), Color(0.0)}, after_[2] = {Color(0.0), Color(0.0)};
};

struct FilmStats {
    std::atomic<int64_t> rejectedSamples{0};  // NaN/Inf estimates discarded
    // Pixel sums that would have exceeded the film's float images (3.4e38): the pass's contribution to
    // that pixel was dropped (counted, reported; the film never holds Inf).
    std::atomic<int64_t> overflowedPixels{0};
    // Luminance of energy that fell outside the film's time range (sum over passes, not averaged),
    // per time axis, of it the part that arrived before the film, and the luminance that landed
    // inside (to report the fractions).
    std::atomic<double> outside[2] = {0.0, 0.0};
    std::atomic<double> before[2] = {0.0, 0.0};
    std::atomic<double> inside[2] = {0.0, 0.0};
};

// Per-thread tallies of what estimates add to the film's counters, flushed once per pass.
struct FilmTally {
    int64_t rejected = 0;            // NaN/Inf estimates discarded
    double outside[2] = {0.0, 0.0};  // luminance outside the film's time range, per axis
    double before[2] = {0.0, 0.0};   // of it, the part before the film's start
    double inside[2] = {0.0, 0.0};   // luminance inside it
    int64_t binsSplatted = 0;        // bins written, both axes (tpb bench: cost per splatted bin)
    void flushInto(FilmStats& fs) const;
    FilmTally& operator+=(const FilmTally& o);
};

// Adds one estimate to a pixel's accumulator on both time axes and the steady state. Its energy
// L lies along s in [s0, s1] with density exp(-kappa s) and arrives at a + b s (time_splat.h); a
// non-finite estimate is counted in tally.rejected and dropped.
void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, const Color& kappa,
                 double s0, double s1, double aReal, double bReal, double aUnwarped, double bUnwarped);
// The same with the estimate's profile built by the caller (which may share its totals: beam2d).
void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L,
                 const SegmentProfile& profile, double aReal, double bReal, double aUnwarped, double bUnwarped,
                 const TimeKernel& kernel);
// An estimate that arrives at one instant on each axis (surface photons, path-traced paths).
inline void splatInstant(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, double tReal,
                         double tUnwarped) {
    splatSpread(time, acc, tally, L, Color(0.0), 0.0, 0.0, tReal, 0.0, tUnwarped, 0.0);
}
// The same with the estimate's time profile first convolved with a time kernel (estimators/
// time_kernel.h, on both axes; the steady state is unchanged). An inactive kernel runs the code
// above, bit for bit.
void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, const Color& kappa,
                 double s0, double s1, double aReal, double bReal, double aUnwarped, double bUnwarped,
                 const TimeKernel& kernel);
inline void splatInstant(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, double tReal,
                         double tUnwarped, const TimeKernel& kernel) {
    splatSpread(time, acc, tally, L, Color(0.0), 0.0, 0.0, tReal, 0.0, tUnwarped, 0.0, kernel);
}

// One render thread's staging for the tile it writes: the touched bins of every pixel it has
// finished in that tile, packed one after another (TileWriter::addPixel copies them out of the
// thread's one accumulator, which so stays in cache), and what the tile's add needs per pixel.
// Kept across tiles and passes: its buffers grow to the largest tile once, then are reused.
struct TileStaging {
    struct Pixel {
        uint32_t pixel = 0;              // index in the tile
        int lo[2] = {0, 0}, hi[2] = {-1, -1};  // touched bins per axis (hi < lo: none)
        size_t offset[2] = {0, 0};       // of bin lo's rgb in `values`, per axis
        Color steady{0.0}, before[2] = {Color(0.0), Color(0.0)}, after[2] = {Color(0.0), Color(0.0)};
        double largest = 0.0;            // largest |value| of the pixel's pass (TileSums::absBound)
    };
    std::vector<Pixel> pixels;  // in the order they came
    std::vector<double> values;  // the touched bins' rgb, [pixel][axis][bin lo..hi][rgb]
    void clear() {
        pixels.clear();
        values.clear();
    }
};

class TransientFilm {
public:
    static constexpr int kTile = FilmLayout::kTile;

    TransientFilm(int width, int height, const TimeBins& time);
    int width() const { return layout_->width; }
    int height() const { return layout_->height; }
    const TimeBins& time() const { return layout_->time; }
    int bins() const { return layout_->time.bins; }
    int tileCount() const { return static_cast<int>(layout_->tiles.size()); }
    TileRect tileRect(int tile) const { return layout_->tiles[tile]; }
    uint64_t bytes() const;  // of the live film's blocks (the formula in memory_budget.cpp must agree)

    // Writer side (one writer per tile at a time): construct (waits for the tile's previous
    // writer), add pixels, destroy (adds the pass to the tile, counts it, publishes).
    // With a TileStaging (the driver gives one per thread), addPixel() copies the pixel's touched
    // bins into the staging and clears `acc` (the thread's one accumulator stays in cache: a pass
    // with 1024 bins touches ~2/3 of them per pixel, 32 KB), and the destructor adds the staged
    // pixels to the tile in place when no snapshot holds its block (no copy of the tile), else to
    // a copy. Without one, the tile's block is copied at construction and pixels are added to the
    // copy as they come (`acc` is left as it was; the caller clears it).
    class TileWriter {
    public:
        // passWeight: the pass's weight in the average (RenderSettings::passWeight).
        TileWriter(TransientFilm& film, int tile, TileStaging* staging = nullptr, double passWeight = 1.0);
        ~TileWriter();
        TileWriter(const TileWriter&) = delete;
        TileWriter& operator=(const TileWriter&) = delete;
        void addPixel(int x, int y, PixelAccumulator& acc);
    private:
        // Adds one pixel's pass to `sums` unless a sum would leave float's range (counted);
        // returns the largest |value| it added (for TileSums::absBound), 0 when dropped.
        double addTo(TileSums& sums, const TileStaging::Pixel& px, const double* const bins[2]);
        void commitStaged();
        TransientFilm& film_;
        int tile_;
        std::unique_lock<std::mutex> lock_;
        std::shared_ptr<TileBlock> next_;  // the copy (no staging)
        TileStaging* staging_ = nullptr;
        double passMax_ = 0.0;              // largest value added (no staging)
        double passWeight_ = 1.0;
    };

    // The tiles' current blocks: cheap (a pointer copy per tile), never waits for a writer.
    std::shared_ptr<const FilmSnapshot> snapshot() const;

    // Adds another film's sums and pass counts (and its counters), tile by tile: for checkpoints
    // and films rendered elsewhere. Throws std::invalid_argument unless it has the same size and
    // time axis. The merged sums equal one film of all the passes to < 1e-12 relative (one extra
    // double rounding per value, FilmSum in film_snapshot.h).
    void merge(const TransientFilm& other);
    // Replaces a tile's sums and pass count (a checkpoint being read: render/checkpoint.h). Throws
    // std::invalid_argument unless they have the tile's size and the film's bins.
    void restoreTile(int tile, TileSums sums);

    // Shorthands that take a snapshot and read it (film_view.h).
    void frame(int bin, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const;
    void steadyImage(std::vector<float>& out) const;  // W*H*3
    // Energy that arrived before the film's first bin / after its last, per pixel (W*H*3).
    void beforeImage(TimeAxis axis, std::vector<float>& out) const;
    void afterImage(TimeAxis axis, std::vector<float>& out) const;
    void pixelProfile(int x, int y, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const;  // bins*3
    void streak(int row, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const;  // bins rows x W cols x 3
    // Whole volume (W*H*bins*3, pixel-major: ((y*W + x)*bins + k)*3), in double.
    void volume(TimeAxis axis, EmissionMode mode, std::vector<double>& out) const;
    int64_t minPasses() const;  // passes completed by every tile
    void clear();

    FilmStats stats;

private:
    struct Tile {
        std::mutex writer;   // held by the tile's TileWriter (and merge, clear)
        // Guards `block`: held for a pointer copy or swap, and by an in-place add (which needs
        // that no snapshot holds the block, i.e. block->readers() == 0 under this lock).
        mutable std::mutex publish;
        std::shared_ptr<TileBlock> block;
    };
    std::shared_ptr<const TileBlock> current(int tile) const;
    void publish(int tile, std::shared_ptr<TileBlock> block);

    std::shared_ptr<const FilmLayout> layout_;
    std::unique_ptr<Tile[]> tiles_;
};

}  // namespace tpb
