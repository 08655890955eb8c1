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
#include "film/time_axis.h"
#include "film/time_kernel.h"
#include "film/time_splat.h"
#include "film/film_snapshot.h"
#include "film/phasor.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <vector>

namespace tpb {

// Accumulates one pixel's contributions during one pass, in double, touched bins only. Besides
// the touched range [lo, hi] of each axis it keeps which bins were touched (one bit per bin): at
// fine time resolution a pixel's range is mostly gaps (at 1024 bins on the default scene about a
// third of it is touched, in ~20 runs), and the tile's add reads and writes the touched runs only
// (forEachRun), not the whole range (issue 15).
class PixelAccumulator {
public:
    // With an active phasor spec (film/phasor.h) it also sums each estimate's phasors.
    explicit PixelAccumulator(int bins = 1, const PhasorSpec* phasor = nullptr) { reset(bins, phasor); }
    void reset(int bins, const PhasorSpec* phasor = nullptr);
    // Adds c to one bin and marks it touched.
    TPB_HOT_INLINE void add(TimeAxis axis, int bin, const Color& c) {
        addUnmarked(axis, bin, c);
        mark(axis, bin, bin);
    }
    // Adds c to one bin without marking it: the caller marks a range covering it (mark) before the
    // pixel is read or cleared (the splat marks each estimate's range once, not bin by bin).
    TPB_HOT_INLINE void addUnmarked(TimeAxis axis, int bin, const Color& c) {
        double* p = &data_[(static_cast<size_t>(axis) * bins_ + bin) * 3];
        p[0] += c.x;
        p[1] += c.y;
        p[2] += c.z;
    }
    // Marks bins [k0, k1] touched (0 <= k0 <= k1 < bins).
    TPB_HOT_INLINE void mark(TimeAxis axis, int k0, int k1) {
        const int a = static_cast<int>(axis);
        lo_[a] = std::min(lo_[a], k0);
        hi_[a] = std::max(hi_[a], k1);
        uint64_t* w = &marks_[static_cast<size_t>(a) * words_];
        const int w0 = k0 >> 6, w1 = k1 >> 6;
        const uint64_t head = ~uint64_t(0) << (k0 & 63), tail = ~uint64_t(0) >> (63 - (k1 & 63));
        if (w0 == w1) {
            w[w0] |= head & tail;
            return;
        }
        w[w0] |= head;
        for (int i = w0 + 1; i < w1; ++i) w[i] = ~uint64_t(0);
        w[w1] |= tail;
    }
    // Calls f(k0, k1) for each maximal run [k0, k1] of touched bins of an axis, in increasing order.
    template <class F>
    void forEachRun(TimeAxis axis, F&& f) const {
        const int a = static_cast<int>(axis);
        const uint64_t* w = &marks_[static_cast<size_t>(a) * words_];
        const int end = hi_[a] + 1;  // no bit is set at or beyond it
        // The first bin >= k (and < end) whose bit is `set`, else end.
        const auto next = [w, end](int k, bool set) {
            const uint64_t flip = set ? 0 : ~uint64_t(0);
            int i = k >> 6;
            uint64_t bits = (w[i] ^ flip) & (~uint64_t(0) << (k & 63));
            while (bits == 0) {
                if (++i * 64 >= end) return end;
                bits = w[i] ^ flip;
            }
            return std::min(end, i * 64 + __builtin_ctzll(bits));
        };
        for (int k = lo_[a]; k < end;) {
            const int k0 = next(k, true);
            if (k0 >= end) return;
            const int k1 = next(k0, false);
            f(k0, k1 - 1);
            k = k1;
        }
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
    // The phasor sums (nullptr: no phasor film): per axis [frequency][Re rgb, Im rgb].
    const PhasorSpec* phasorSpec() const { return phasor_; }
    double* phasor(TimeAxis a) {
        phasorTouched_ = true;
        return &phasorData_[static_cast<size_t>(a) * phasorStride()];
    }
    const double* phasor(TimeAxis a) const { return &phasorData_[static_cast<size_t>(a) * phasorStride()]; }
    bool phasorTouched() const { return phasorTouched_; }
    size_t phasorStride() const { return phasor_ ? static_cast<size_t>(phasor_->count()) * 6 : 0; }
    void clearTouched();  // zero the touched runs, ready for the next pixel

private:
    int bins_ = 0, words_ = 0;
    std::vector<double> data_;
    std::vector<uint64_t> marks_;  // [axis][bin / 64]: bit bin % 64 set when touched
    int lo_[2], hi_[2];
    Color steady_{0.0};
    Color before_[2] = {Color(0.0), Color(0.0)}, after_[2] = {Color(0.0), Color(0.0)};
    const PhasorSpec* phasor_ = nullptr;
    std::vector<double> phasorData_;  // [axis][frequency][Re rgb, Im rgb]
    bool phasorTouched_ = false;
};

struct FilmStats {
    std::atomic<int64_t> rejectedSamples{0};  // NaN/Inf estimates discarded
    // Pixel sums that would have exceeded the film's float images (3.4e38): the pass's contribution to
    // that pixel was dropped (counted, reported; the film never holds Inf).
    std::atomic<int64_t> overflowedPixels{0};
    // Staged tile adds that copied the tile's block because a snapshot held it (film_snapshot.h),
    // and all staged tile adds: how much readers cost the writers (the viewer prints both in its
    // timeline). A diagnostic of this run: not merged, not in checkpoints.
    std::atomic<int64_t> copiedTiles{0}, stagedTiles{0};
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
// With a floor (time_splat.h): no part of the profile is binned earlier than it, per axis.
void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L,
                 const SegmentProfile& profile, double aReal, double bReal, double aUnwarped, double bUnwarped,
                 const TimeKernel& kernel, const ArrivalFloor& floor = {});
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
                 const TimeKernel& kernel, const ArrivalFloor& floor = {});
inline void splatInstant(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, double tReal,
                         double tUnwarped, const TimeKernel& kernel, const ArrivalFloor& floor = {}) {
    splatSpread(time, acc, tally, L, Color(0.0), 0.0, 0.0, tReal, 0.0, tUnwarped, 0.0, kernel, floor);
}

// One render thread's staging for the tile it writes: the touched runs of bins of every pixel it
// has finished in that tile, packed one after another (TileWriter::addPixel copies them out of the
// thread's one accumulator, which so stays in cache), and what the tile's add needs per pixel.
// Kept across tiles and passes: its buffers grow to the largest tile once, then are reused.
struct TileStaging {
    struct Run {
        int bin = 0, count = 0;  // bins [bin, bin + count) of one axis
    };
    struct Pixel {
        uint32_t pixel = 0;                                   // index in the tile
        uint32_t firstRun[2] = {0, 0}, runCount[2] = {0, 0};  // its runs in `runs`, per axis
        size_t offset[2] = {0, 0};  // of its first run's rgb in `values`, per axis (the runs follow)
        Color steady{0.0}, before[2] = {Color(0.0), Color(0.0)}, after[2] = {Color(0.0), Color(0.0)};
        double largest = 0.0;    // largest |value| of the pixel's pass (TileSums::absBound)
        bool hasPhasor = false;  // its phasor sums are in `phasor` from phasorOffset (both axes)
        size_t phasorOffset = 0;
    };
    std::vector<Pixel> pixels;   // in the order they came
    std::vector<Run> runs;       // the touched runs, [pixel][axis][run]
    std::vector<double> values;  // the touched runs' rgb, [pixel][axis][run][bin][rgb]
    std::vector<double> phasor;  // [pixel with phasors][axis][frequency][Re rgb, Im rgb]
    void clear() {
        pixels.clear();
        runs.clear();
        values.clear();
        phasor.clear();
    }
};

// Stages pixel `pixelInTile` (index in its tile, row-major) of a pass from `acc` into `staging`
// and clears acc's touched bins: for TileWriter::addStaged. A pixel is staged once per pass.
void stagePixel(TileStaging& staging, uint32_t pixelInTile, PixelAccumulator& acc);

class TransientFilm {
public:
    static constexpr int kTile = FilmLayout::kTile;

    // With an active phasor spec the film also sums each estimate's phasors (film/phasor.h).
    TransientFilm(int width, int height, const TimeBins& time, const PhasorSpec& phasor = {});
    const PhasorSpec& phasor() const { return layout_->phasor; }
    int width() const { return layout_->width; }
    int height() const { return layout_->height; }
    const TimeBins& time() const { return layout_->time; }
    int bins() const { return layout_->time.bins; }
    int tileCount() const { return static_cast<int>(layout_->tiles.size()); }
    TileRect tileRect(int tile) const { return layout_->tiles[tile]; }
    uint64_t bytes() const;  // of the live film's blocks (the formula in film_bytes.cpp must agree)

    // Writer side (one writer per tile at a time): construct (waits for the tile's previous
    // writer), add pixels, destroy (adds the pass to the tile, counts it, publishes).
    // With a TileStaging (the driver gives one per thread), addPixel() copies the pixel's touched
    // runs into the staging and clears `acc` (the thread's one accumulator stays in cache: 48 KB at
    // 1024 bins, of which a pixel touches about a third in ~20 runs per axis on the default scene),
    // and the destructor adds the staged
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
        // Adds pixels staged earlier for this tile (stagePixel): an integrator that gathers a pass's
        // pixels before the tiles run (a scan's laser points, integrators/photon_beams.cpp).
        void addStaged(const TileStaging& staged);

    private:
        // Adds one staged pixel's pass to `sums` unless a sum would leave float's range (counted);
        // returns the largest |value| it added (for TileSums::absBound), 0 when dropped.
        double addTo(TileSums& sums, const TileStaging& staged, const TileStaging::Pixel& px);
        void commitStaged();
        TransientFilm& film_;
        int tile_;
        std::unique_lock<std::mutex> lock_;
        std::shared_ptr<TileBlock> next_;  // the copy (no staging)
        TileStaging* staging_ = nullptr;
        TileStaging own_;       // no staging: one pixel at a time
        double passMax_ = 0.0;  // largest value added (no staging)
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
        std::mutex writer;  // held by the tile's TileWriter (and merge, clear)
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
