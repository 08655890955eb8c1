#include "film/film_snapshot.h"

#include "base/error.h"

#include <algorithm>

namespace tpb {

void TileSums::zero(size_t pixels, int bins_, int phasorCount_) {
    phasorCount = phasorCount_;
    for (int a = 0; a < 2; ++a) phasor[a].assign(pixels * phasorStride(), 0.0);
    passes = 0;
    weight = 0.0;
    binCount = bins_;
    absBound = 0.0;
    steady.assign(pixels * 3, 0.0);
    for (int a = 0; a < 2; ++a) {
        bins[a].assign(pixels * static_cast<size_t>(bins_) * 3, FilmSum(0));
        before[a].assign(pixels * 3, 0.0);
        after[a].assign(pixels * 3, 0.0);
    }
}

const std::vector<double>& TileBlock::cumulative(TimeAxis axis) const {
    const int a = static_cast<int>(axis);
    std::lock_guard<std::mutex> g(cumulativeMutex_);
    if (cumulativeValid_[a]) return cumulative_[a];
    cumulativeValid_[a] = true;
    [&] {
        const FilmSums& src = sums.bins[a];
        const size_t pixels = sums.before[a].size() / 3;
        std::vector<double>& cum = cumulative_[a];
        cum.resize(src.size());
        const size_t binCount = static_cast<size_t>(sums.binCount);
        if (pixels == 0 || binCount == 0) return;
        // Bin 0 starts from what arrived before the film; each next bin adds to the previous one
        // (the same additions, in the same order, as a running sum over the bins).
        for (size_t p = 0; p < pixels; ++p) {
            const size_t i0 = sums.binIndex(p, 0);
            for (int c = 0; c < 3; ++c) cum[i0 + c] = sums.before[a][p * 3 + c] + src[i0 + c];
            for (size_t j = i0 + 3; j < i0 + binCount * 3; ++j) cum[j] = cum[j - 3] + src[j];
        }
    }();
    return cumulative_[a];
}

void TileBlock::invalidateCumulative() {
    std::lock_guard<std::mutex> g(cumulativeMutex_);
    for (int a = 0; a < 2; ++a) {
        cumulativeValid_[a] = false;
        std::vector<double>().swap(cumulative_[a]);
    }
}

FilmLayout::FilmLayout(int w, int h, const TimeBins& t, const PhasorSpec& p)
    : width(w), height(h), tilesX((w + kTile - 1) / kTile), time(t), phasor(p) {
    TPB_CHECK(w > 0 && h > 0 && t.bins > 0);
    const int tilesY = (h + kTile - 1) / kTile;
    for (int ty = 0; ty < tilesY; ++ty)
        for (int tx = 0; tx < tilesX; ++tx)
            tiles.push_back({tx * kTile, ty * kTile, std::min(kTile, w - tx * kTile), std::min(kTile, h - ty * kTile)});
}

FilmSnapshot::FilmSnapshot(std::shared_ptr<const FilmLayout> layout,
                           std::vector<std::shared_ptr<const TileBlock>> blocks)
    : layout_(std::move(layout)), blocks_(std::move(blocks)) {
    TPB_CHECK(layout_ && blocks_.size() == layout_->tiles.size());
}

int64_t FilmSnapshot::minPasses() const {
    int64_t m = INT64_MAX;
    for (const auto& b : blocks_) m = std::min(m, b->sums.passes);
    return blocks_.empty() ? 0 : m;
}

int64_t FilmSnapshot::maxPasses() const {
    int64_t m = 0;
    for (const auto& b : blocks_) m = std::max(m, b->sums.passes);
    return m;
}

}  // namespace tpb
