// Film snapshots (core/film/film_snapshot.h): a snapshot held while passes are added does not
// change, and snapshots taken while writers add passes are per-tile consistent (each tile shows
// whole passes only). The concurrent test runs under ThreadSanitizer (tools/sanitize thread).
#include "film/film_view.h"
#include "film_test_passes.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

using namespace tpb;

TEST(FilmSnapshot, HeldSnapshotDoesNotChangeWhilePassesAreAdded) {
    TransientFilm film(40, 20, TimeBins{0.0, 0.5, 6});
    test::addRandomPass(film, 3, 1);
    test::addRandomPass(film, 3, 2);
    const std::shared_ptr<const FilmSnapshot> held = film.snapshot();
    const std::vector<double> volBefore = volume(*held, TimeAxis::Real, EmissionMode::Delta);
    const std::vector<float> contBefore = frameImage(*held, 2, TimeAxis::Unwarped, EmissionMode::Continuous);
    const std::vector<float> steadyBefore = steadyImage(*held);
    test::addRandomPass(film, 3, 3);
    film.clear();
    test::addRandomPass(film, 3, 4);
    EXPECT_EQ(held->minPasses(), 2);
    EXPECT_EQ(held->maxPasses(), 2);
    EXPECT_EQ(volume(*held, TimeAxis::Real, EmissionMode::Delta), volBefore);
    EXPECT_EQ(frameImage(*held, 2, TimeAxis::Unwarped, EmissionMode::Continuous), contBefore);
    EXPECT_EQ(steadyImage(*held), steadyBefore);
    // A new snapshot sees the film as it is now: one pass (4) after the clear.
    const std::shared_ptr<const FilmSnapshot> now = film.snapshot();
    EXPECT_EQ(now->minPasses(), 1);
    EXPECT_NE(steadyImage(*now), steadyBefore);
}

// Writers add passes tile by tile on two threads; every pass adds exactly 1 to every bin value
// and steady value of the tile (exact in float and double), pixel by pixel. A reader taking
// snapshots all the while must see, in every tile, every value equal to that tile's pass count:
// a partly added pass would show as a mix.
TEST(FilmSnapshotConcurrent, SnapshotsTakenWhileWritingArePerTileConsistent) {
    TransientFilm film(48, 40, TimeBins{0.0, 1.0, 3});
    const int passes = 40;
    std::atomic<int> writersLeft{2};
    PixelAccumulator one(film.bins());
    for (int a = 0; a < 2; ++a)
        for (int k = 0; k < film.bins(); ++k) one.add(static_cast<TimeAxis>(a), k, Color(1.0));
    one.addSteady(Color(1.0));
    const auto writer = [&](int parity) {
        for (int p = 0; p < passes; ++p)
            for (int tile = parity; tile < film.tileCount(); tile += 2) {
                TransientFilm::TileWriter w(film, tile);
                const TileRect r = film.tileRect(tile);
                for (int y = r.y0; y < r.y0 + r.h; ++y)
                    for (int x = r.x0; x < r.x0 + r.w; ++x) w.addPixel(x, y, one);
            }
        --writersLeft;
    };
    std::thread w0(writer, 0), w1(writer, 1);
    int snapshots = 0, mixed = 0;
    int64_t lastMin = 0;
    bool done = false;
    while (!done) {
        done = writersLeft.load() == 0;  // one more snapshot after the writers finished
        const std::shared_ptr<const FilmSnapshot> s = film.snapshot();
        ++snapshots;
        EXPECT_GE(s->minPasses(), lastMin);  // tiles never lose passes
        lastMin = s->minPasses();
        if (!s->complete()) ++mixed;
        for (int t = 0; t < s->tileCount(); ++t) {
            const TileSums& sums = s->block(t).sums;
            const double n = static_cast<double>(sums.passes);
            bool ok = true;
            for (int a = 0; a < 2; ++a)
                for (FilmSum v : sums.bins[a]) ok = ok && v == n;
            for (double v : sums.steady) ok = ok && v == n;
            ASSERT_TRUE(ok) << "tile " << t << " shows part of a pass (" << sums.passes << " passes)";
        }
    }
    w0.join();
    w1.join();
    const std::shared_ptr<const FilmSnapshot> last = film.snapshot();
    EXPECT_EQ(last->minPasses(), passes);
    EXPECT_TRUE(last->complete());
    for (float v : frameImage(*last, 1, TimeAxis::Real, EmissionMode::Delta)) EXPECT_EQ(v, 1.0f);
    for (float v : frameImage(*last, 2, TimeAxis::Real, EmissionMode::Continuous)) EXPECT_EQ(v, 3.0f);
    EXPECT_GE(snapshots, 1);
    (void)mixed;  // how many caught a pass in progress depends on the scheduler: not checked
}
