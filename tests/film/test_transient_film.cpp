// TransientFilm (core/film/transient_film.h): memory accounting, the energy it keeps outside its time
// range, the overflow guard of its sums, and merging films.
#include "film/transient_film.h"
#include "base/memory.h"
#include "film/film_bytes.h"
#include "film_test_passes.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <memory>
#include <random>
#include <utility>
#include <vector>
#include <stdexcept>

using namespace tpb;

namespace {

// Adds one pass in which every pixel gets `L` spread uniformly over t in [t0, t1] (both axes).
void addUniformPass(TransientFilm& film, const Color& L, double t0, double t1, TileStaging* staging = nullptr) {
    PixelAccumulator acc(film.bins());
    FilmTally tally;
    for (int tile = 0; tile < film.tileCount(); ++tile) {
        TransientFilm::TileWriter w(film, tile, staging);
        const TileRect r = film.tileRect(tile);
        for (int y = r.y0; y < r.y0 + r.h; ++y)
            for (int x = r.x0; x < r.x0 + r.w; ++x) {
                splatSpread(film.time(), acc, tally, L, Color(0.0), 0.0, 1.0, t0, t1 - t0, t0, t1 - t0);
                w.addPixel(x, y, acc);
                acc.clearTouched();
            }
    }
    tally.flushInto(film.stats);
}

}  // namespace

// One formula for the film's memory (issue 12, item 16): the budget the loader checks and the CLI
// prints is what the film allocates, for sizes that are and are not multiples of the tile size.
TEST(Film, BytesFormulaIsWhatTheFilmAllocates) {
    for (const auto& [w, h, bins] : {std::tuple{16, 16, 1}, {17, 5, 3}, {33, 47, 64}, {1, 1, 1000}}) {
        const TransientFilm film(w, h, TimeBins{0.0, 0.1, bins});
        EXPECT_EQ(film.bytes(), filmBytes(w, h, bins)) << w << "x" << h << "x" << bins;
    }
}

// Continuous emission is the step response (issue 12, item 1): frame k = before + bins 0..k, and
// the last continuous frame = steady - after, through every reader (frame, pixel profile, volume).
TEST(Film, ContinuousFramesStartFromWhatArrivedBeforeTheFilm) {
    TransientFilm film(20, 18, TimeBins{1.0, 0.5, 4});     // film [1, 3)
    addUniformPass(film, Color(1.0, 2.0, 3.0), 0.0, 5.0);  // t in [0, 5]: 0.2 before, 0.4 inside, 0.4 after
    addUniformPass(film, Color(1.0, 2.0, 3.0), 0.0, 5.0);
    std::vector<float> before, after, steady, f0, f3, prof;
    film.beforeImage(TimeAxis::Real, before);
    film.afterImage(TimeAxis::Unwarped, after);
    film.steadyImage(steady);
    film.frame(0, TimeAxis::Real, EmissionMode::Continuous, f0);
    film.frame(3, TimeAxis::Unwarped, EmissionMode::Continuous, f3);
    std::vector<double> vol;
    film.volume(TimeAxis::Real, EmissionMode::Continuous, vol);
    film.pixelProfile(19, 17, TimeAxis::Real, EmissionMode::Continuous, prof);
    for (size_t p = 0; p < steady.size() / 3; ++p)
        for (int c = 0; c < 3; ++c) {
            const double L = c + 1.0, i = p * 3 + c;
            EXPECT_NEAR(before[i], 0.2 * L, 1e-6);
            EXPECT_NEAR(after[i], 0.4 * L, 1e-6);
            EXPECT_NEAR(steady[i], L, 1e-12);
            EXPECT_NEAR(f0[i], 0.3 * L, 1e-6);               // before + bin 0
            EXPECT_NEAR(f3[i], steady[i] - after[i], 1e-6);  // the last one: everything but what comes after
            EXPECT_NEAR(vol[p * 4 * 3 + c], 0.3 * L, 1e-6);
            EXPECT_NEAR(vol[(p * 4 + 3) * 3 + c], 0.6 * L, 1e-6);
        }
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(prof[k * 3], 0.2 + 0.1 * (k + 1), 1e-6) << k;
    // The counters split what fell outside into before and after, in luminance.
    const double before0 = film.stats.before[0].load(), outside0 = film.stats.outside[0].load();
    EXPECT_NEAR(before0 / outside0, 0.2 / 0.6, 1e-9);
    film.clear();
    film.beforeImage(TimeAxis::Real, before);
    for (float v : before) EXPECT_EQ(v, 0.0f);
}

// Non-finite values never reach the film (issue 12, item 5): a pass that would push a float sum
// past FLT_MAX is dropped for that pixel and counted; what was there stays finite and unchanged.
TEST(Film, SumsThatWouldOverflowAreDroppedAndCounted) {
    TransientFilm film(4, 4, TimeBins{0.0, 1.0, 2});
    addUniformPass(film, Color(2e38), 0.0, 0.5);  // fits in a float
    EXPECT_EQ(film.stats.overflowedPixels.load(), 0);
    addUniformPass(film, Color(2e38), 0.0, 0.5);  // the sum 4e38 does not
    EXPECT_EQ(film.stats.overflowedPixels.load(), 16);
    std::vector<float> f;
    film.frame(0, TimeAxis::Real, EmissionMode::Delta, f);
    for (float v : f) {
        EXPECT_TRUE(std::isfinite(v));
        EXPECT_NEAR(v, 1e38, 1e32);  // one pass of 2e38, averaged over the tile's two passes
    }
    std::vector<float> steady;
    film.steadyImage(steady);
    for (float v : steady) EXPECT_TRUE(std::isfinite(v));
}

// Energy that arrives wholly before the film (no bin touched) counts in the overflow guard too (its
// before sum, and the steady sum that includes it): a second pass of 2e38 before the film would
// push those sums past FLT_MAX, so it is dropped, with or without the staging.
TEST(Film, OverflowGuardSeesEnergyThatMissesEveryBin) {
    for (bool staged : {false, true}) {
        TileStaging staging;
        TransientFilm film(4, 4, TimeBins{1.0, 1.0, 2});
        addUniformPass(film, Color(2e38), 0.0, 0.5, staged ? &staging : nullptr);
        EXPECT_EQ(film.stats.overflowedPixels.load(), 0);
        addUniformPass(film, Color(2e38), 0.0, 0.5, staged ? &staging : nullptr);
        EXPECT_EQ(film.stats.overflowedPixels.load(), 16) << "staged " << staged;
        std::vector<float> before;
        film.beforeImage(TimeAxis::Real, before);
        for (float v : before) EXPECT_TRUE(std::isfinite(v)) << "staged " << staged;
    }
}

// The driver's writers stage a tile's pixels (TileStaging: touched bins packed, added when the
// tile is done) and add in place, or to a copy while a snapshot holds the tile. Every way gives
// the sums, pass counts and overflow bounds of the plain writer, bit for bit: the same additions.
// One staging serves every tile and pass, as a render thread's does.
TEST(Film, StagedWritersGiveThePlainWritersSumsBitForBit) {
    const TimeBins time{0.5, 0.3, 9};
    TransientFilm plain(37, 21, time), staged(37, 21, time), copied(37, 21, time);
    TileStaging staging, staging2;
    for (uint64_t p = 1; p <= 4; ++p) {
        test::addRandomPass(plain, 3, p);
        test::addRandomPass(staged, 3, p, &staging);
        const auto held = copied.snapshot();  // every tile is added to a copy this pass
        test::addRandomPass(copied, 3, p, &staging2);
        EXPECT_EQ(held->minPasses(), static_cast<int64_t>(p - 1));
    }
    const auto a = plain.snapshot();
    for (const TransientFilm* f : {&staged, &copied}) {
        const auto b = f->snapshot();
        for (int t = 0; t < a->tileCount(); ++t) {
            const TileSums &x = a->block(t).sums, &y = b->block(t).sums;
            ASSERT_EQ(x.passes, y.passes);
            EXPECT_EQ(x.weight, y.weight);
            EXPECT_EQ(x.absBound, y.absBound);
            EXPECT_GT(x.absBound, 0.0);
            for (int ax = 0; ax < 2; ++ax) {
                ASSERT_TRUE(x.bins[ax] == y.bins[ax]) << "tile " << t << " axis " << ax;
                EXPECT_TRUE(x.before[ax] == y.before[ax]);
                EXPECT_TRUE(x.after[ax] == y.after[ax]);
            }
            EXPECT_TRUE(x.steady == y.steady);
        }
    }
}

// The accumulator's touched runs (PixelAccumulator::forEachRun): ranges marked at random, across
// and on the 64-bin word boundaries and the axis' ends, give exactly the maximal runs of bins
// that some range covered (a plain bool per bin says which), in increasing order; clearTouched
// zeroes every value and forgets the marks, round after round.
TEST(PixelAccumulator, RunsAreTheMaximalRunsOfTouchedBins) {
    const int bins = 300;  // five words, the last one partly used
    PixelAccumulator acc(bins);
    std::mt19937_64 rng(17);
    for (int round = 0; round < 200; ++round) {
        std::vector<bool> touched[2] = {std::vector<bool>(bins, false), std::vector<bool>(bins, false)};
        const int ranges = static_cast<int>(rng() % 6);
        for (int i = 0; i < ranges; ++i) {
            const int a = static_cast<int>(rng() % 2);
            static const int edges[] = {0, 1, 62, 63, 64, 65, 127, 128, 191, 192, 255, 256, 298, 299};
            const int k0 = rng() % 3 == 0 ? edges[rng() % 14] : static_cast<int>(rng() % bins);
            const int k1 = std::min(bins - 1, k0 + static_cast<int>(rng() % (rng() % 2 ? 4 : 140)));
            for (int k = k0; k <= k1; ++k) {
                acc.addUnmarked(static_cast<TimeAxis>(a), k, Color(1.0 + k, 2.0, 3.0));
                touched[a][k] = true;
            }
            acc.mark(static_cast<TimeAxis>(a), k0, k1);
        }
        if (rng() % 2) {  // single bins through add(), which marks them itself
            const int a = static_cast<int>(rng() % 2), k = static_cast<int>(rng() % bins);
            acc.add(static_cast<TimeAxis>(a), k, Color(0.5));
            touched[a][k] = true;
        }
        for (int a = 0; a < 2; ++a) {
            std::vector<std::pair<int, int>> expected, got;
            for (int k = 0; k < bins; ++k) {
                if (!touched[a][k]) continue;
                if (k > 0 && touched[a][k - 1])
                    expected.back().second = k;
                else
                    expected.push_back({k, k});
            }
            acc.forEachRun(static_cast<TimeAxis>(a), [&](int k0, int k1) { got.push_back({k0, k1}); });
            ASSERT_EQ(got, expected) << "round " << round << " axis " << a;
        }
        acc.clearTouched();
        for (int a = 0; a < 2; ++a) {
            for (int k = 0; k < bins; ++k) {
                const double* v = acc.bin(static_cast<TimeAxis>(a), k);
                ASSERT_TRUE(v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0) << "round " << round << " bin " << k;
            }
            int runs = 0;
            acc.forEachRun(static_cast<TimeAxis>(a), [&](int, int) { ++runs; });
            ASSERT_EQ(runs, 0);
        }
    }
}

// The tile's add reads each pixel's touched runs only (TileStaging::Run). With estimates that
// leave wide gaps between them on a 300-bin film, every sum is the sum, pass after pass, of the
// accumulator's values read densely over all the bins before each add: the gaps add nothing,
// and no touched value is missed.
TEST(Film, TouchedRunsAddWhatTheWholeAccumulatorHolds) {
    const TimeBins time{0.0, 0.01, 300};
    TransientFilm film(20, 18, time);
    std::vector<double> dense[2];
    for (int a = 0; a < 2; ++a) dense[a].assign(static_cast<size_t>(20 * 18) * 300 * 3, 0.0);
    PixelAccumulator acc(time.bins);
    FilmTally tally;
    TileStaging staging;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int pass = 0; pass < 3; ++pass)
        for (int tile = 0; tile < film.tileCount(); ++tile) {
            TransientFilm::TileWriter w(film, tile, &staging);
            const TileRect r = film.tileRect(tile);
            for (int y = r.y0; y < r.y0 + r.h; ++y)
                for (int x = r.x0; x < r.x0 + r.w; ++x) {
                    for (int e = 0; e < 4; ++e) {  // narrow estimates anywhere on the axis
                        const double t = u(rng) * 3.1 - 0.05, width = u(rng) * (e == 0 ? 0.9 : 0.05);
                        splatSpread(time, acc, tally, Color(u(rng), u(rng), 0.2), Color(u(rng)), 0.0, 1.0, t, width,
                                    t * 0.8, width);
                    }
                    for (int a = 0; a < 2; ++a)
                        for (int k = 0; k < time.bins; ++k)
                            for (int c = 0; c < 3; ++c)
                                dense[a][((static_cast<size_t>(y) * 20 + x) * 300 + k) * 3 + c] +=
                                    acc.bin(static_cast<TimeAxis>(a), k)[c];
                    w.addPixel(x, y, acc);
                    acc.clearTouched();
                }
        }
    const auto snap = film.snapshot();
    int gappy = 0;
    for (int tile = 0; tile < snap->tileCount(); ++tile) {
        const TileRect r = snap->tileRect(tile);
        const TileSums& s = snap->block(tile).sums;
        for (int y = r.y0; y < r.y0 + r.h; ++y)
            for (int x = r.x0; x < r.x0 + r.w; ++x) {
                const size_t p = static_cast<size_t>((y - r.y0) * r.w + (x - r.x0));
                for (int a = 0; a < 2; ++a) {
                    bool seen = false, gap = false;
                    for (int k = 0; k < time.bins; ++k)
                        for (int c = 0; c < 3; ++c) {
                            const double want = dense[a][((static_cast<size_t>(y) * 20 + x) * 300 + k) * 3 + c];
                            ASSERT_EQ(s.bins[a][s.binIndex(p, k) + c], want)
                                << x << "," << y << " axis " << a << " bin " << k;
                            if (c == 0 && want > 0.0) {
                                gappy += seen && gap;
                                seen = true;
                                gap = false;
                            } else if (c == 0 && seen) {
                                gap = true;
                            }
                        }
                }
            }
    }
    EXPECT_GT(gappy, 100);  // the passes did leave gaps inside pixels' touched ranges
}

// The writers count the staged tile adds, and those that copied their block because a snapshot
// held it (FilmStats::copiedTiles, the viewer's timeline prints both): none without a reader,
// every tile while one is held, none again once it is dropped.
TEST(Film, TileCopiesForHeldSnapshotsAreCounted) {
    const TimeBins time{0.5, 0.3, 9};
    TransientFilm film(37, 21, time);  // 3 x 2 tiles
    TileStaging staging;
    const int64_t tiles = film.tileCount();
    test::addRandomPass(film, 3, 1, &staging);
    EXPECT_EQ(film.stats.stagedTiles.load(), tiles);
    EXPECT_EQ(film.stats.copiedTiles.load(), 0);
    {
        const auto held = film.snapshot();
        test::addRandomPass(film, 3, 2, &staging);
        EXPECT_EQ(film.stats.copiedTiles.load(), tiles);
    }
    test::addRandomPass(film, 3, 3, &staging);
    EXPECT_EQ(film.stats.stagedTiles.load(), 3 * tiles);
    EXPECT_EQ(film.stats.copiedTiles.load(), tiles);
    film.clear();
    EXPECT_EQ(film.stats.stagedTiles.load(), 0);
    EXPECT_EQ(film.stats.copiedTiles.load(), 0);
}

// Merging (checkpoints, films from other machines): the films of passes 1-3 and 4-6 merged are
// the film of passes 1-6 to < 1e-12 relative in every sum (double sums: one extra rounding, ~1e-16),
// with the pass counts and counters added. A snapshot held before the merge is unchanged.
TEST(Film, MergeOfTwoRunsIsTheFilmOfAllTheirPasses) {
    const TimeBins time{0.5, 0.3, 7};
    TransientFilm all(21, 18, time), first(21, 18, time), second(21, 18, time);
    for (uint64_t p = 1; p <= 6; ++p) test::addRandomPass(all, 5, p);
    for (uint64_t p = 1; p <= 3; ++p) test::addRandomPass(first, 5, p);
    for (uint64_t p = 4; p <= 6; ++p) test::addRandomPass(second, 5, p);
    const auto held = first.snapshot();
    first.merge(second);
    EXPECT_EQ(held->minPasses(), 3);
    EXPECT_EQ(first.minPasses(), 6);
    const auto a = all.snapshot(), m = first.snapshot();
    double maxRel = 0.0;
    const auto compare = [&](double x, double y) {
        maxRel = std::max(maxRel, std::abs(x - y) / std::max(std::abs(x), 1e-300));
    };
    for (int t = 0; t < a->tileCount(); ++t) {
        const TileSums &sa = a->block(t).sums, &sm = m->block(t).sums;
        ASSERT_EQ(sm.passes, 6);
        for (int ax = 0; ax < 2; ++ax) {
            for (size_t i = 0; i < sa.bins[ax].size(); ++i) compare(sa.bins[ax][i], sm.bins[ax][i]);
            for (size_t i = 0; i < sa.before[ax].size(); ++i) compare(sa.before[ax][i], sm.before[ax][i]);
            for (size_t i = 0; i < sa.after[ax].size(); ++i) compare(sa.after[ax][i], sm.after[ax][i]);
        }
        for (size_t i = 0; i < sa.steady.size(); ++i) compare(sa.steady[i], sm.steady[i]);
    }
    EXPECT_LT(maxRel, 1e-12);
    EXPECT_NEAR(first.stats.inside[0].load(), all.stats.inside[0].load(), 1e-9 * all.stats.inside[0].load());
    EXPECT_NEAR(first.stats.outside[1].load(), all.stats.outside[1].load(), 1e-9 * all.stats.outside[1].load());
}

TEST(Film, MergeRefusesAFilmOfAnotherShape) {
    TransientFilm film(8, 8, TimeBins{0.0, 1.0, 4});
    TransientFilm wider(9, 8, TimeBins{0.0, 1.0, 4}), longer(8, 8, TimeBins{0.0, 1.0, 5}),
        later(8, 8, TimeBins{0.5, 1.0, 4});
    EXPECT_THROW(film.merge(wider), std::invalid_argument);
    EXPECT_THROW(film.merge(longer), std::invalid_argument);
    EXPECT_THROW(film.merge(later), std::invalid_argument);
    EXPECT_THROW(film.merge(film), std::invalid_argument);
    EXPECT_EQ(film.minPasses(), 0);
}

// Why the sums are double: the same six passes summed in float, in one run and as 1-3 + 4-6,
// differ by far more than the 1e-12 that merging is held to above (float rounds at ~6e-8).
TEST(Film, FloatSumsWouldNotMergeToTheTolerance) {
    const TimeBins time{0.5, 0.3, 7};
    std::vector<std::unique_ptr<TransientFilm>> passes;  // one film per pass: its sums are that pass's values
    for (uint64_t p = 1; p <= 6; ++p) {
        passes.push_back(std::make_unique<TransientFilm>(21, 18, time));
        test::addRandomPass(*passes.back(), 5, p);
    }
    std::vector<std::shared_ptr<const FilmSnapshot>> snaps;
    for (const auto& f : passes) snaps.push_back(f->snapshot());
    double maxRel = 0.0;
    for (int t = 0; t < snaps[0]->tileCount(); ++t)
        for (int ax = 0; ax < 2; ++ax)
            for (size_t i = 0; i < snaps[0]->block(t).sums.bins[ax].size(); ++i) {
                float all = 0.0f, first = 0.0f, second = 0.0f;
                for (int p = 0; p < 6; ++p) {
                    const float v = static_cast<float>(snaps[p]->block(t).sums.bins[ax][i]);
                    all += v;
                    (p < 3 ? first : second) += v;
                }
                const float merged = first + second;
                if (all != 0.0f) maxRel = std::max(maxRel, std::abs(static_cast<double>(merged) - all) / std::abs(all));
            }
    EXPECT_GT(maxRel, 1e-12);
    EXPECT_GT(maxRel, 1e-8);  // float rounding, not a few double ulps
}
