// The command-line flag validators (CLI11): the first check of a flag, at parse time.
#pragma once
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

namespace tpb::app {

// ---- flag validation --------------------------------------------------------------------------
// CLI11 validators whose messages name the allowed range and the meaning of special values, and
// that check finiteness ("--time nan" used to render forever). integer() and threads() rewrite the
// value (1e6 -> 1000000, a capped thread count), so they are attached with ->transform(), the
// others with ->check(). They run while the command line is
// parsed, before any subcommand starts, so a bad flag never leaves a file behind. CLI11 prefixes
// the flag: "error: --passes: must be an integer >= 0 (0 = ...); got -3".
namespace flags {
// An integer in [lo, hi]; an integral number written as 1e6 is accepted (and rewritten as digits).
CLI::Validator integer(int64_t lo, int64_t hi, const std::string& meaning = "");
// A finite number in [lo, hi] (or (lo, hi] when loOpen).
CLI::Validator number(double lo, double hi, bool loOpen, const std::string& meaning = "");
// A seed: an integer in [0, 2^64 - 1] (strtoull would wrap -1 to 2^64 - 1).
CLI::Validator seed();
// Worker threads: an integer >= 0; more than maxUsefulThreads() is capped with a warning.
CLI::Validator threads();
// --pulse delta | gaussian:FWHM_NS | square:WIDTH_NS and --sensor ideal | gaussian:FWHM_NS | exp:TAU_NS
// (film/time_response.h).
CLI::Validator pulse();
CLI::Validator sensor();
// --counts off | photons=P,efficiency=E,dark_hz=R,... (film/photon_counting.h)
CLI::Validator counts();
}  // namespace flags

}  // namespace tpb::app
