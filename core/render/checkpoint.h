// Checkpoints of a progressive render (issue 16): the accumulated film (every tile's sums and pass
// count, bit for bit), the film's counters, the finished passes' statistics, and what the render
// was (fingerprint.h, and the command-line overrides it ran with), in one file written atomically
// (io/atomic_file.h: a checkpoint cut by Ctrl-C or a full disk never replaces the previous one).
//
// Resuming is exact: pass i depends only on (seed, i) (driver.h) and adds one double to each sum,
// so a film restored from a checkpoint of n passes and rendered on to N holds the same bits as one
// run of N passes (tests/render/test_checkpoint.cpp). A checkpoint is written only between passes,
// when every tile holds the same passes (an aborted pass leaves some tiles ahead: refused).
//
// ---- File format (".tpbck", version 1; tpb's film container, io/film_container.h) ---------------
//   bytes 0..7    magic "TPBCKPT\n"
//   bytes 8..15   N: length of the JSON header, unsigned 64-bit little-endian
//   bytes 16..    the JSON header (N bytes, UTF-8): format "tpb-checkpoint", version 1, byte_order
//                 "little", scene (absolute path), created (UTC, ISO 8601), passes, width, height,
//                 time {bins, start_opl_m, bin_width_opl_m}, tiles, payload_bytes, fingerprint
//                 [[key, value]...], overrides {flag values of the run}, stats {rejected_samples,
//                 overflowed_pixels, outside, before, inside (per axis)}, history [per pass]
//   then          the payload, tile after tile (tiles of 16x16 pixels, row-major; edge tiles smaller):
//                 int64 passes, float64 abs_bound, then float64 arrays: steady [pixels][rgb],
//                 bins real [pixels][bins][rgb], bins unwarped, before real, before unwarped, after
//                 real, after unwarped ([pixels][rgb] each)
//   then          8 bytes: a 64-bit hash of the payload's 64-bit words (WordHash), to refuse a
//                 corrupted file; nothing after it.
#pragma once
#include "film/transient_film.h"
#include "integrators/integrator.h"
#include "render/fingerprint.h"
#include "render/prepare.h"
#include "integrators/render_settings.h"

#include <memory>
#include <string>
#include <vector>

namespace tpb {

inline constexpr const char* kCheckpointFile = "checkpoint.tpbck";

struct CheckpointInfo {
    std::string scene;    // absolute path of the scene file
    std::string created;  // UTC, ISO 8601
    uint64_t passes = 0;
    int width = 0, height = 0;
    TimeBins time;
    PhasorSpec phasor;  // the phasor film's frequencies (film/phasor.h); none when inactive
    Fingerprint fingerprint;
    SettingsOverrides overrides;  // the flags the render ran with (a resume adopts them)
};

struct Checkpoint {
    CheckpointInfo info;
    std::unique_ptr<TransientFilm> film;  // sums, pass counts and counters (stats) restored
    std::vector<PassStats> history;       // the finished passes, in order
};

// Writes `film` (every tile at info.passes passes: otherwise UserError) and `history` to `path`.
void writeCheckpoint(const std::string& path, const CheckpointInfo& info, const TransientFilm& film,
                     const std::vector<PassStats>& history);
// The header alone (cheap: the film is not read). UserError naming the file for anything that is
// not a complete version-1 checkpoint (wrong magic, truncated, bad header).
CheckpointInfo readCheckpointInfo(const std::string& path);
// Everything; also checks the payload's hash. With `into` (a film of the checkpoint's size and time
// axis, else UserError), the sums and counters go into that film tile by tile and Checkpoint::film
// stays null: a resume then holds one film plus a tile, not two films (a 12 GiB film on 24 GB).
Checkpoint readCheckpoint(const std::string& path, TransientFilm* into = nullptr);

// The overrides of a resumed run: the checkpoint's, with the resuming command's own on top where
// they may differ (passes, time budget, threads); any other flag the resuming command gives must
// equal the checkpoint's (UserError "--seed 2: the checkpoint was rendered with --seed 1; ..."
// naming the fix). `given` names the flags as the CLI spells them.
// The overrides a checkpoint stores: `flags` (the film's shape, the pass count...) with every
// setting that enters a pass written out as an override, the radii as absolute values (so a resume
// runs no radius pilot and reproduces settings edited in the viewer).
SettingsOverrides checkpointOverrides(const RenderSettings& s, const SettingsOverrides& flags);

// What a checkpoint of a render of `p` records: the scene (absolute path), its fingerprint with the
// settings the driver runs (`running`: the viewer may have edited them), and the overrides that
// reproduce those settings from the scene file (checkpointOverrides of `flags`).
CheckpointInfo checkpointInfoFor(const PreparedRender& p, const RenderSettings& running, const SettingsOverrides& flags,
                                 uint64_t passes);

SettingsOverrides resumeOverrides(const SettingsOverrides& checkpoint, const SettingsOverrides& given);

}  // namespace tpb
