#include "film/film_view.h"

#include "base/math.h"

#include <algorithm>
#include <memory>
#include <mutex>
#include <optional>

namespace tpb {

namespace {

// The average divides by the passes' summed weight (TileSums::weight; = passes without a warm-up).
double inversePasses(const TileSums& t) { return t.weight > 0.0 ? 1.0 / t.weight : 0.0; }

// Writes a tile's [pixel][rgb] block of values (times `inv`) into the W*H*3 image.
template <class T>
void putTile(const FilmSnapshot& s, int tile, const T* src, double inv, std::vector<float>& out) {
    const TileRect& r = s.tileRect(tile);
    for (int py = 0; py < r.h; ++py)
        for (int px = 0; px < r.w; ++px)
            for (int c = 0; c < 3; ++c)
                out[((static_cast<size_t>(r.y0 + py) * s.width()) + r.x0 + px) * 3 + c] =
                    static_cast<float>(static_cast<double>(src[(static_cast<size_t>(py) * r.w + px) * 3 + c]) * inv);
}

// Writes bin `bin` of a tile's [pixel][bin][rgb] sums (times `inv`) into the W*H*3 image.
template <class T>
void putTileBin(const FilmSnapshot& s, int tile, const TileSums& sums, const T* src, int bin, double inv,
                std::vector<float>& out) {
    const TileRect& r = s.tileRect(tile);
    for (int py = 0; py < r.h; ++py)
        for (int px = 0; px < r.w; ++px) {
            const T* v = src + sums.binIndex(static_cast<size_t>(py) * r.w + px, bin);
            float* dst = &out[((static_cast<size_t>(r.y0 + py) * s.width()) + r.x0 + px) * 3];
            for (int c = 0; c < 3; ++c) dst[c] = static_cast<float>(static_cast<double>(v[c]) * inv);
        }
}

enum class PerPixel { Steady, Before, After };

std::vector<float> perPixelImage(const FilmSnapshot& s, PerPixel which, TimeAxis axis) {
    std::vector<float> out(static_cast<size_t>(s.width()) * s.height() * 3);
    const int a = static_cast<int>(axis);
    for (int t = 0; t < s.tileCount(); ++t) {
        const TileSums& sums = s.block(t).sums;
        const std::vector<double>& src = which == PerPixel::Steady   ? sums.steady
                                         : which == PerPixel::Before ? sums.before[a]
                                                                     : sums.after[a];
        putTile(s, t, src.data(), inversePasses(sums), out);
    }
    return out;
}

}  // namespace

namespace {

// Calls put(k, rgb) for every bin of pixel (x, y) with the average, delta or running sum.
template <class Put>
void forEachBinRaw(const FilmSnapshot& s, int x, int y, TimeAxis axis, EmissionMode mode, Put&& put) {
    const int tile = s.tileOf(x, y);
    const TileSums& t = s.block(tile).sums;
    const TileRect& r = s.tileRect(tile);
    const int a = static_cast<int>(axis);
    const double inv = inversePasses(t);
    const size_t pixel = static_cast<size_t>(y - r.y0) * r.w + (x - r.x0);
    double run[3] = {0.0, 0.0, 0.0};
    if (mode == EmissionMode::Continuous) std::copy(&t.before[a][pixel * 3], &t.before[a][pixel * 3] + 3, run);
    for (int k = 0; k < s.bins(); ++k) {
        const FilmSum* v = &t.bins[a][t.binIndex(pixel, k)];
        double rgb[3];
        for (int c = 0; c < 3; ++c) {
            run[c] = (mode == EmissionMode::Continuous ? run[c] : 0.0) + v[c];
            rgb[c] = run[c] * inv;
        }
        put(k, rgb);
    }
}

// The photon-counting model and its scale for one read (the steady image's mean luminance).
struct Counting {
    PhotonCounting model;
    CountScale scale;
};
std::optional<Counting> countingOf(const FilmSnapshot& s, const TimeResponse& r) {
    if (!r.counting.enabled) return std::nullopt;
    const PhotonCounting& m = r.counting;
    const std::vector<float> steady = steadyImage(s);
    double sum = 0.0;
    for (size_t i = 0; i + 2 < steady.size(); i += 3) sum += luminance(Color(steady[i], steady[i + 1], steady[i + 2]));
    const double pixels = static_cast<double>(s.width()) * s.height();
    return Counting{m, countScale(m, pixels > 0.0 ? sum / pixels : 0.0, s.time().binWidth)};
}

// The same through a pulse shape and sensor response: the pixel's series (delta or running sum),
// then the kernel along it (time_response.h); the identity reads it as forEachBinRaw does.
template <class Put>
void forEachBinKernel(const FilmSnapshot& s, int x, int y, TimeAxis axis, EmissionMode mode, const BinKernel& kernel,
                      Put&& put) {
    if (kernel.identity()) return forEachBinRaw(s, x, y, axis, mode, put);
    const int bins = s.bins();
    std::vector<double> series(static_cast<size_t>(bins) * 3), out(series.size());
    forEachBinRaw(s, x, y, axis, mode,
                  [&](int k, const double* rgb) { std::copy(rgb, rgb + 3, &series[static_cast<size_t>(k) * 3]); });
    double left[3] = {0.0, 0.0, 0.0}, right[3] = {0.0, 0.0, 0.0};
    if (mode == EmissionMode::Continuous) {
        const int tile = s.tileOf(x, y);
        const TileSums& t = s.block(tile).sums;
        const TileRect& r = s.tileRect(tile);
        const size_t pixel = static_cast<size_t>(y - r.y0) * r.w + (x - r.x0);
        const double inv = inversePasses(t);
        for (int c = 0; c < 3; ++c) {
            left[c] = t.before[static_cast<int>(axis)][pixel * 3 + c] * inv;
            right[c] = series[static_cast<size_t>(bins - 1) * 3 + c];
        }
    }
    applyKernel(kernel, series.data(), bins, left, right, out.data());
    for (int k = 0; k < bins; ++k) put(k, &out[static_cast<size_t>(k) * 3]);
}

// Then, with `counting`, the luminance counted (put(k, r = g = b = counts) for bins first..last).
template <class Put>
void forEachBin(const FilmSnapshot& s, int x, int y, TimeAxis axis, EmissionMode mode, const BinKernel& kernel,
                const Counting* counting, int first, int last, Put&& put) {
    if (!counting) return forEachBinKernel(s, x, y, axis, mode, kernel, put);
    const int bins = s.bins();
    last = std::min(last, bins - 1);
    std::vector<double> lum(static_cast<size_t>(bins)), counts(lum.size());
    forEachBinKernel(s, x, y, axis, mode, kernel, [&](int k, const double* rgb) {
        lum[static_cast<size_t>(k)] = luminance(Color(rgb[0], rgb[1], rgb[2]));
    });
    const uint64_t pixel = static_cast<uint64_t>(y) * static_cast<uint64_t>(s.width()) + static_cast<uint64_t>(x);
    // Ideal counts are independent per bin: a frame samples its bin only (pile-up samples 0..last).
    countPixel(counting->model, counting->scale, pixel, lum.data(), bins, first, last, counts.data());
    for (int k = first; k <= last; ++k) {
        const double grey[3] = {counts[static_cast<size_t>(k)], counts[static_cast<size_t>(k)],
                                counts[static_cast<size_t>(k)]};
        put(k, grey);
    }
}

// The pile-up counts of every pixel and bin (pixel-major, bins contiguous), for frameImage: a bin's
// counts depend on the bins before it, so frame by frame would cost O(bins^2) per pixel for a whole
// export (145 s instead of 3 for 128 x 128 x 256 frames). Kept for the last two (snapshot, axis,
// emission, response): a snapshot is its blocks (immutable; a weak pointer expires with its block).
// Memory: W H bins floats each, a twelfth of the film's own.
std::shared_ptr<const std::vector<float>> countedVolume(const FilmSnapshot& s, TimeAxis axis, EmissionMode mode,
                                                        const TimeResponse& response, const BinKernel& kernel) {
    struct Entry {
        std::vector<std::weak_ptr<const TileBlock>> blocks;
        TimeAxis axis;
        EmissionMode mode;
        TimeResponse response;
        std::shared_ptr<const std::vector<float>> counts;
    };
    static std::mutex mutex;
    static std::vector<Entry> cache;  // most recently used last
    constexpr size_t kKept = 2;
    const auto same = [&](const Entry& e) {
        if (e.axis != axis || e.mode != mode || !(e.response == response) ||
            e.blocks.size() != static_cast<size_t>(s.tileCount()))
            return false;
        for (int t = 0; t < s.tileCount(); ++t)
            if (e.blocks[static_cast<size_t>(t)].lock() != s.blockPointer(t)) return false;
        return true;
    };
    const std::lock_guard<std::mutex> lock(mutex);  // held while counting: each volume once
    for (size_t i = 0; i < cache.size(); ++i)
        if (same(cache[i])) {
            std::rotate(cache.begin() + static_cast<std::ptrdiff_t>(i),
                        cache.begin() + static_cast<std::ptrdiff_t>(i) + 1, cache.end());
            return cache.back().counts;
        }
    const Counting counting = *countingOf(s, response);
    const size_t bins = static_cast<size_t>(s.bins());
    auto counts = std::make_shared<std::vector<float>>(static_cast<size_t>(s.width()) * s.height() * bins);
    for (int y = 0; y < s.height(); ++y)
        for (int x = 0; x < s.width(); ++x) {
            float* dst = &(*counts)[(static_cast<size_t>(y) * s.width() + x) * bins];
            forEachBin(s, x, y, axis, mode, kernel, &counting, 0, s.bins() - 1,
                       [&](int k, const double* rgb) { dst[k] = static_cast<float>(rgb[0]); });
        }
    Entry e{{}, axis, mode, response, counts};
    for (int t = 0; t < s.tileCount(); ++t) e.blocks.push_back(s.blockPointer(t));
    if (cache.size() == kKept) cache.erase(cache.begin());
    cache.push_back(std::move(e));
    return counts;
}

}  // namespace

std::vector<float> frameImage(const FilmSnapshot& s, int bin, TimeAxis axis, EmissionMode mode,
                              const TimeResponse& response) {
    std::vector<float> out(static_cast<size_t>(s.width()) * s.height() * 3);
    bin = std::clamp(bin, 0, s.bins() - 1);
    const int a = static_cast<int>(axis);
    const std::shared_ptr<const BinKernel> shared = sharedBinKernel(response, s.time().binWidth, s.bins());
    const BinKernel& kernel = *shared;
    if (response.counting.pileup) {
        // Pile-up counts (photon_counting.h): a slice of the counted volume, counted once per snapshot.
        const std::shared_ptr<const std::vector<float>> counts = countedVolume(s, axis, mode, response, kernel);
        const size_t bins = static_cast<size_t>(s.bins()), pixels = static_cast<size_t>(s.width()) * s.height();
        for (size_t p = 0; p < pixels; ++p) out[p * 3] = out[p * 3 + 1] = out[p * 3 + 2] = (*counts)[p * bins + bin];
        return out;
    }
    if (response.counting.enabled) {
        // Ideal counts are independent per bin: each pixel's series through the kernel, `bin` drawn.
        const Counting counting = *countingOf(s, response);
        for (int y = 0; y < s.height(); ++y)
            for (int x = 0; x < s.width(); ++x) {
                float* dst = &out[(static_cast<size_t>(y) * s.width() + x) * 3];
                forEachBin(s, x, y, axis, mode, kernel, &counting, bin, bin,
                           [&](int, const double* rgb) { dst[0] = dst[1] = dst[2] = static_cast<float>(rgb[0]); });
            }
        return out;
    }
    if (!kernel.identity()) {
        // Y_bin = sum_i w_i S(bin - lo - i), S the delta sums or the running sums (time_response.h).
        const bool cont = mode == EmissionMode::Continuous;
        const int bins = s.bins();
        for (int t = 0; t < s.tileCount(); ++t) {
            const TileBlock& b = s.block(t);
            const TileSums& sums = b.sums;
            const double* src = cont ? b.cumulative(axis).data() : sums.bins[a].data();
            const double inv = inversePasses(sums);
            const TileRect& r = s.tileRect(t);
            for (int py = 0; py < r.h; ++py)
                for (int px = 0; px < r.w; ++px) {
                    const size_t pixel = static_cast<size_t>(py) * r.w + px;
                    const double zero[3] = {0.0, 0.0, 0.0};
                    const double* left = cont ? &sums.before[a][pixel * 3] : zero;
                    const double* right = cont ? src + sums.binIndex(pixel, bins - 1) : zero;
                    // (the same sum, in the same order, as applyKernel)
                    double acc[3] = {0.0, 0.0, 0.0};
                    if (kernel.after != 0.0)
                        for (int c = 0; c < 3; ++c) acc[c] += kernel.after * right[c];
                    for (size_t i = 0; i < kernel.w.size(); ++i) {
                        const int k = bin - (kernel.lo + static_cast<int>(i));
                        const double* v = k < 0 ? left : k >= bins ? right : src + sums.binIndex(pixel, k);
                        for (int c = 0; c < 3; ++c) acc[c] += kernel.w[i] * v[c];
                    }
                    if (kernel.before != 0.0)
                        for (int c = 0; c < 3; ++c) acc[c] += kernel.before * left[c];
                    float* dst = &out[((static_cast<size_t>(r.y0 + py) * s.width()) + r.x0 + px) * 3];
                    for (int c = 0; c < 3; ++c) dst[c] = static_cast<float>(acc[c] * inv);
                }
        }
        return out;
    }
    for (int t = 0; t < s.tileCount(); ++t) {
        const TileBlock& b = s.block(t);
        if (mode == EmissionMode::Continuous)
            putTileBin(s, t, b.sums, b.cumulative(axis).data(), bin, inversePasses(b.sums), out);
        else
            putTileBin(s, t, b.sums, b.sums.bins[a].data(), bin, inversePasses(b.sums), out);
    }
    return out;
}

std::vector<float> steadyImage(const FilmSnapshot& s) { return perPixelImage(s, PerPixel::Steady, TimeAxis::Real); }
std::vector<float> beforeImage(const FilmSnapshot& s, TimeAxis axis) {
    return perPixelImage(s, PerPixel::Before, axis);
}
std::vector<float> afterImage(const FilmSnapshot& s, TimeAxis axis) { return perPixelImage(s, PerPixel::After, axis); }

std::vector<float> pixelProfile(const FilmSnapshot& s, int x, int y, TimeAxis axis, EmissionMode mode,
                                const TimeResponse& response) {
    std::vector<float> out(static_cast<size_t>(s.bins()) * 3, 0.0f);
    if (x < 0 || y < 0 || x >= s.width() || y >= s.height()) return out;
    const std::optional<Counting> counting = countingOf(s, response);
    forEachBin(s, x, y, axis, mode, *sharedBinKernel(response, s.time().binWidth, s.bins()),
               counting ? &*counting : nullptr, 0, s.bins() - 1, [&](int k, const double* rgb) {
                   for (int c = 0; c < 3; ++c) out[static_cast<size_t>(k) * 3 + c] = static_cast<float>(rgb[c]);
               });
    return out;
}

std::vector<float> streakImage(const FilmSnapshot& s, int row, TimeAxis axis, EmissionMode mode,
                               const TimeResponse& response) {
    const int W = s.width();
    std::vector<float> out(static_cast<size_t>(s.bins()) * W * 3, 0.0f);
    if (row < 0 || row >= s.height()) return out;
    const std::shared_ptr<const BinKernel> kernel = sharedBinKernel(response, s.time().binWidth, s.bins());
    const std::optional<Counting> counting = countingOf(s, response);
    for (int x = 0; x < W; ++x)
        forEachBin(s, x, row, axis, mode, *kernel, counting ? &*counting : nullptr, 0, s.bins() - 1,
                   [&](int k, const double* rgb) {
                       for (int c = 0; c < 3; ++c)
                           out[(static_cast<size_t>(k) * W + x) * 3 + c] = static_cast<float>(rgb[c]);
                   });
    return out;
}

std::vector<double> volume(const FilmSnapshot& s, TimeAxis axis, EmissionMode mode, const TimeResponse& response) {
    const size_t bins = static_cast<size_t>(s.bins());
    const std::shared_ptr<const BinKernel> kernel = sharedBinKernel(response, s.time().binWidth, s.bins());
    std::vector<double> out(static_cast<size_t>(s.width()) * s.height() * bins * 3, 0.0);
    const std::optional<Counting> counting = countingOf(s, response);
    for (int y = 0; y < s.height(); ++y)
        for (int x = 0; x < s.width(); ++x) {
            double* dst = &out[(static_cast<size_t>(y) * s.width() + x) * bins * 3];
            forEachBin(s, x, y, axis, mode, *kernel, counting ? &*counting : nullptr, 0, s.bins() - 1,
                       [&](int k, const double* rgb) { std::copy(rgb, rgb + 3, dst + k * 3); });
        }
    return out;
}

std::vector<double> binEnergy(const FilmSnapshot& s, TimeAxis axis, int stride) {
    // The luminance of each pixel's average as a frame shows it (float), summed over the image; read
    // pixel by pixel, each one's time series contiguous (TileSums layout).
    const int bins = s.bins();
    std::vector<double> energy(static_cast<size_t>(bins), 0.0);
    const int a = static_cast<int>(axis);
    stride = std::max(stride, 1);
    for (int t = 0; t < s.tileCount(); ++t) {
        const TileSums& sums = s.block(t).sums;
        const double inv = inversePasses(sums);
        const TileRect& r = s.tileRect(t);
        const size_t pixels = static_cast<size_t>(r.w) * r.h;
        for (size_t p = 0; p < pixels; ++p) {
            const int x = r.x0 + static_cast<int>(p % static_cast<size_t>(r.w)),
                      y = r.y0 + static_cast<int>(p / static_cast<size_t>(r.w));
            if (x % stride != 0 || y % stride != 0) continue;
            const FilmSum* v = &sums.bins[a][sums.binIndex(p, 0)];
            for (int k = 0; k < bins; ++k, v += 3) {
                const auto f = [inv](FilmSum x) { return static_cast<float>(static_cast<double>(x) * inv); };
                energy[static_cast<size_t>(k)] += luminance(Color(f(v[0]), f(v[1]), f(v[2])));
            }
        }
    }
    return energy;
}

std::vector<double> phasorVolume(const FilmSnapshot& s, TimeAxis axis, const TimeResponse& response) {
    const PhasorSpec& spec = s.phasor();
    if (!spec.active()) return {};
    const size_t nf = static_cast<size_t>(spec.count()), stride = nf * 6;
    std::vector<Complex> h(nf, Complex(1.0, 0.0));
    if (!response.identity())
        for (size_t i = 0; i < nf; ++i) h[i] = responseTransform(response, spec.frequencies[i]);
    std::vector<double> out(static_cast<size_t>(s.width()) * s.height() * stride, 0.0);
    const int a = static_cast<int>(axis);
    for (int t = 0; t < s.tileCount(); ++t) {
        const TileSums& sums = s.block(t).sums;
        const TileRect& r = s.tileRect(t);
        const double inv = inversePasses(sums);
        for (int py = 0; py < r.h; ++py)
            for (int px = 0; px < r.w; ++px) {
                const double* src = sums.phasor[a].data() + (static_cast<size_t>(py) * r.w + px) * stride;
                double* dst = out.data() + (static_cast<size_t>(r.y0 + py) * s.width() + (r.x0 + px)) * stride;
                for (size_t i = 0; i < nf; ++i)
                    for (int c = 0; c < 3; ++c) {
                        const Complex v = Complex(src[i * 6 + c], src[i * 6 + 3 + c]) * inv * h[i];
                        dst[i * 6 + c] = v.real();
                        dst[i * 6 + 3 + c] = v.imag();
                    }
            }
    }
    return out;
}

}  // namespace tpb
