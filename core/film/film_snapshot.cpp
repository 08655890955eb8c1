#include "film/film_snapshot.h"

#include "base/error.h"

#include <algorithm>

namespace tpb {

void TileSums::zero(size_t pixels, int binCount) {
    passes = 0;
    absBound = 0.0;
    steady.assign(pixels * 3, 0.0);
    for (int a = 0; a < 2; ++a) {
        bins[a].assign(pixels * static_cast<size_t>(binCount) * 3, FilmSum(0));
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
        const size_t n = sums.before[a].size();  // pixels x rgb
        std::vector<double>& cum = cumulative_[a];
        cum.resize(src.size());
        if (n == 0) return;
        const size_t binCount = src.size() / n;
        // Bin 0 starts from what arrived before the film; each next bin adds to the previous one
        // (the same additions, in the same order, as a running sum over the bins).
        for (size_t i = 0; i < n; ++i) cum[i] = sums.before[a][i] + src[i];
        for (size_t k = 1; k < binCount; ++k)
            for (size_t i = 0; i < n; ++i) cum[k * n + i] = cum[(k - 1) * n + i] + src[k * n + i];
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

FilmLayout::FilmLayout(int w, int h, const TimeBins& t)
    : width(w), height(h), tilesX((w + kTile - 1) / kTile), time(t) {
    TPB_CHECK(w > 0 && h > 0 && t.bins > 0);
    const int tilesY = (h + kTile - 1) / kTile;
    for (int ty = 0; ty < tilesY; ++ty)
        for (int tx = 0; tx < tilesX; ++tx)
            tiles.push_back({tx * kTile, ty * kTile, std::min(kTile, w - tx * kTile), std::min(kTile, h - ty * kTile)});
}

FilmSnapshot::FilmSnapshot(std::shared_ptr<const FilmLayout> layout, std::vector<std::shared_ptr<const TileBlock>> blocks)
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
