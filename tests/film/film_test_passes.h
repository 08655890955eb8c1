// Synthetic passes for the film tests: every pixel of every tile gets, per pass, an estimate
// whose colour and arrival times depend only on (seed, pass, pixel), spread over part of the
// film's time range with some of it before and after (splatSpread, transient_film.h).
#pragma once
#include "film/transient_film.h"

#include <random>

namespace tpb::test {

// With `staging`, the tiles are written as the driver writes them (TileWriter's staging).
inline void addRandomPass(TransientFilm& film, uint64_t seed, uint64_t pass, TileStaging* staging = nullptr) {
    PixelAccumulator acc(film.bins());
    FilmTally tally;
    const double t0 = film.time().startOpl, span = film.time().endOpl() - t0;
    for (int tile = 0; tile < film.tileCount(); ++tile) {
        TransientFilm::TileWriter w(film, tile, staging);
        const TileRect r = film.tileRect(tile);
        for (int y = r.y0; y < r.y0 + r.h; ++y)
            for (int x = r.x0; x < r.x0 + r.w; ++x) {
                std::mt19937_64 rng(seed * 1000003u + pass * 7919u + static_cast<uint64_t>(y * film.width() + x));
                std::uniform_real_distribution<double> u(0.0, 1.0);
                for (int e = 0; e < 3; ++e) {
                    const Color L(u(rng), u(rng) * 3.0, u(rng) * 0.1);
                    const double a = t0 + (u(rng) * 1.2 - 0.1) * span, b = u(rng) * 0.3 * span;
                    const Color kappa(u(rng) * 2.0);
                    splatSpread(film.time(), acc, tally, L, kappa, 0.0, 1.0, a, b, a * 0.9, b);
                }
                w.addPixel(x, y, acc);
                acc.clearTouched();
            }
    }
    tally.flushInto(film.stats);
}

}  // namespace tpb::test
