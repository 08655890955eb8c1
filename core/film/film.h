// The transient film: RGB radiance per pixel per time bin, on two time axes (real time, camera
// path included; camera-unwarped time, camera path excluded), plus the steady-state image.
//
// Units: a bin holds the part of the steady-state radiance carried by light whose arrival OPL falls
// in that bin (i.e. the delta-pulse response integrated over the bin). Per pixel and axis the film
// also keeps what arrived before its first bin and after its last, so that
//     steady = before + sum over bins + after      (per pixel, per axis, up to rounding).
// Continuous emission (light on from the pulse instant) is the step response: the frame of bin k is
// before + the running sum of bins 0..k, computed on demand (transport is linear and
// time-invariant); its last frame is steady - after.
//
// Concurrency: the image is split in 16x16 tiles. A tile has one writer at a time (the worker that
// renders it in the current pass) and its own pass count, so a reader always sees, per tile, the
// average of the passes that tile has completed - never a partially gathered pass. Sums are float
// (per pass, each pixel is accumulated in double first); steady-state sums are double.
#pragma once
#include "base/math.h"
#include "scene/scene_desc.h"
#include "estimators/time_splat.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <vector>

namespace tpb {

enum class TimeAxis { Real = 0, Unwarped = 1 };

struct TileRect { int x0, y0, w, h; };

// Accumulates one pixel's contributions during one pass, in double, touched bins only.
class PixelAccumulator {
public:
    explicit PixelAccumulator(int bins = 1) { reset(bins); }
    void reset(int bins);
    void add(TimeAxis axis, int bin, const Color& c) {
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
    // Pixel sums that would have overflowed the film's float storage: the pass's contribution to
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
    void flushInto(FilmStats& fs) const;
    FilmTally& operator+=(const FilmTally& o);
};

// Adds one estimate to a pixel's accumulator on both time axes and the steady state. Its energy
// L lies along s in [s0, s1] with density exp(-kappa s) and arrives at a + b s (time_splat.h); a
// non-finite estimate is counted in tally.rejected and dropped.
void splatSpread(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, const Color& kappa,
                 double s0, double s1, double aReal, double bReal, double aUnwarped, double bUnwarped);
// An estimate that arrives at one instant on each axis (surface photons, path-traced paths).
inline void splatInstant(const TimeBins& time, PixelAccumulator& acc, FilmTally& tally, const Color& L, double tReal,
                         double tUnwarped) {
    splatSpread(time, acc, tally, L, Color(0.0), 0.0, 0.0, tReal, 0.0, tUnwarped, 0.0);
}

class TransientFilm {
public:
    static constexpr int kTile = 16;

    TransientFilm(int width, int height, const TimeBins& time);
    int width() const { return width_; }
    int height() const { return height_; }
    const TimeBins& time() const { return time_; }
    int bins() const { return time_.bins; }
    int tileCount() const { return static_cast<int>(tiles_.size()); }
    TileRect tileRect(int tile) const { return tiles_[tile].rect; }
    uint64_t bytes() const;

    // Writer side (one writer per tile at a time): lock, add pixels, finish.
    class TileWriter {
    public:
        TileWriter(TransientFilm& film, int tile);
        ~TileWriter();
        void addPixel(int x, int y, const PixelAccumulator& acc);
    private:
        TransientFilm& film_;
        int tile_;
        std::unique_lock<std::mutex> lock_;
    };

    // Reader side. Each returns averages (sum / passes of the tile). `wait=false` skips tiles that
    // are being written (their pixels are left untouched in `out`), returning false if any was.
    bool frame(int bin, TimeAxis axis, EmissionMode mode, std::vector<float>& out, bool wait = true) const;
    bool steadyImage(std::vector<float>& out, bool wait = true) const;  // W*H*3
    // Energy that arrived before the film's first bin / after its last, per pixel (W*H*3).
    bool beforeImage(TimeAxis axis, std::vector<float>& out, bool wait = true) const;
    bool afterImage(TimeAxis axis, std::vector<float>& out, bool wait = true) const;
    void pixelProfile(int x, int y, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const;  // bins*3
    void streak(int row, TimeAxis axis, EmissionMode mode, std::vector<float>& out) const;  // bins rows x W cols x 3
    // Whole volume (W*H*bins*3, pixel-major: ((y*W + x)*bins + k)*3), in double.
    void volume(TimeAxis axis, EmissionMode mode, std::vector<double>& out) const;
    int64_t minPasses() const;  // passes completed by every tile
    void clear();

    FilmStats stats;

private:
    struct Tile {
        TileRect rect;
        size_t offset = 0;  // into sums_ (per axis)
        int64_t passes = 0;
        std::vector<double> steady;            // w*h*3
        std::vector<double> before[2], after[2];  // per axis, w*h*3
        mutable std::mutex mutex;
    };
    // Layout per axis: [tile][bin][pixel in tile][rgb], so a frame reads contiguous blocks.
    size_t index(const Tile& t, int bin, int px, int py) const {
        return t.offset + (static_cast<size_t>(bin) * t.rect.w * t.rect.h + static_cast<size_t>(py) * t.rect.w + px) * 3;
    }
    int tileOf(int x, int y) const { return (y / kTile) * tilesX_ + (x / kTile); }
    // Copies a per-pixel image kept in double (steady, before, after), averaged over passes.
    enum class PerPixel { Steady, Before, After };
    static const std::vector<double>& perPixel(const Tile& t, PerPixel which, TimeAxis axis);
    bool perPixelImage(PerPixel which, TimeAxis axis, std::vector<float>& out, bool wait) const;

    int width_, height_, tilesX_;
    TimeBins time_;
    std::vector<Tile> tiles_;
    std::vector<float> sums_[2];
};


}  // namespace tpb
