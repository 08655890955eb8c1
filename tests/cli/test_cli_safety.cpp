// Work that must never be lost (issue 33, items 1-3 and 7): the built `tpb` binary (TPB_BINARY, or
// $TPB_TEST_BINARY to see a test fail on an older build) is run into temp folders and stopped by the
// signals a user's session sends; its outputs and checkpoint must survive, be verified before they
// get their final name, and every failure must name its file and end with a non-zero exit code.
#include "support/temp_dir.h"
#include "support/tpb_process.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

using tpb::test::now;
using tpb::test::Proc;
using tpb::test::slurp;
using tpb::test::spawnTpb;
using tpb::test::tpbBinary;

Proc waitTpb(pid_t pid, const fs::path& dir, double timeoutSec) {
    return tpb::test::waitTpb(pid, dir, now(), timeoutSec);
}

Proc runTpb(const std::vector<std::string>& args, const fs::path& dir, const std::vector<std::string>& env = {},
            double timeoutSec = 120.0) {
    return tpb::test::runTpb(args, dir, env, timeoutSec);
}

// Polls `file` until it contains `text` (true), the process has ended or `timeoutSec` passed.
bool waitForText(const fs::path& file, const std::string& text, pid_t pid, double timeoutSec) {
    const double t0 = now();
    while (now() - t0 < timeoutSec) {
        if (slurp(file).find(text) != std::string::npos) return true;
        siginfo_t info{};
        if (waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == pid)
            return false;  // ended (left to be reaped by waitTpb)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
}

// A closed box in fog with the camera and a point light inside: 16x16 px.
std::string boxScene(int bins, const std::string& render) {
    return "{\"version\": 1,\n"
           " \"camera\": {\"position\": [0, 0.5, 0.9], \"look_at\": [0, 0.5, 0], \"fov\": 60, \"resolution\": [16, "
           "16]},\n"
           " \"film\": {\"bins\": " +
           std::to_string(bins) +
           "},\n"
           " \"media\": {\"fog\": {\"sigma_s\": 0.5, \"sigma_a\": 0.05}}, \"global_medium\": \"fog\",\n"
           " \"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": 0.7}},\n"
           " \"shapes\": [{\"type\": \"box\", \"min\": [-1, 0, -1], \"max\": [1, 1, 1], \"material\": \"white\", "
           "\"flip_normals\": true}],\n"
           " \"lights\": [{\"type\": \"point\", \"position\": [0, 0.8, 0], \"power\": 5}],\n"
           " \"render\": " +
           render + "}\n";
}

class CliSafety : public ::testing::Test {
protected:
    void SetUp() override {
        tmp_ = std::make_unique<tpb::test::TempDir>(
            "safety_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        dir_ = tmp_->path();
    }
    fs::path write(const std::string& name, const std::string& text) {
        const fs::path p = dir_ / name;
        fs::create_directories(p.parent_path());
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }
    std::unique_ptr<tpb::test::TempDir> tmp_;
    fs::path dir_;
};

}  // namespace

// Item 2: a closed terminal or ssh session (SIGHUP, here sent twice as a shell and the kernel both
// send it) stops the render like SIGTERM: the finished passes and the checkpoint are written, exit
// 129. Before, the default disposition killed the process and every pass was lost.
TEST_F(CliSafety, SighupWritesTheFinishedPassesAndTheCheckpoint) {
    const fs::path scene =
        write("scene.json", boxScene(8, "{\"photons_per_pass\": 20000, \"passes\": 100000, \"seed\": 1}"));
    const fs::path out = dir_ / "out";
    const pid_t pid = spawnTpb({"render", scene.string(), "-o", out.string(), "--threads", "2", "--strip", "0"}, dir_);
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(waitForText(dir_ / "stderr.txt", "pass 1:", pid, 60.0)) << slurp(dir_ / "stderr.txt");
    kill(pid, SIGHUP);
    kill(pid, SIGHUP);  // a second hangup does not quit at once (it is not a second Ctrl-C)
    const Proc p = waitTpb(pid, dir_, 120.0);
    EXPECT_FALSE(p.timedOut);
    EXPECT_EQ(p.signal, 0) << "killed by the hangup: the finished passes are lost\n" << p.err;
    EXPECT_EQ(p.code, 129) << p.err;
    EXPECT_NE(p.err.find("interrupted by SIGHUP (the terminal was closed): writing the "), std::string::npos) << p.err;
    ASSERT_TRUE(fs::exists(out / "summary.json")) << p.err;
    const nlohmann::json summary = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_GE(summary["passes"].get<int>(), 1);
    EXPECT_EQ(summary["outputs"]["frames_written"].get<int>(), 8);
    EXPECT_TRUE(fs::exists(out / "checkpoint.tpbck")) << p.err;
    EXPECT_NE(p.err.find("checkpoint (interrupted): "), std::string::npos) << p.err;
}

// Item 1: a new render into a folder removed the earlier render's checkpoint with its other outputs
// ("removed 39 files of an earlier render"), even a --preview. Now it is refused (exit 2, nothing
// touched) with the checkpoint's passes and the ways forward; --resume still finds it, and only
// --overwrite-checkpoint lets it go.
TEST_F(CliSafety, NewRenderIntoAFolderWithACheckpointIsRefusedAndTheCheckpointKept) {
    const fs::path scene = write("scene.json", boxScene(8, "{\"photons_per_pass\": 2000, \"passes\": 2, \"seed\": 1}"));
    const fs::path out = dir_ / "out";
    const std::vector<std::string> base{"render", scene.string(), "-o", out.string(), "--strip", "0"};
    auto with = [&](std::vector<std::string> extra) {
        std::vector<std::string> a = base;
        a.insert(a.end(), extra.begin(), extra.end());
        return a;
    };
    Proc p = runTpb(with({"--checkpoint", "-q"}), dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    const std::string checkpoint = slurp(out / "checkpoint.tpbck");
    const std::string steady = slurp(out / "steady.exr");
    ASSERT_FALSE(checkpoint.empty());

    for (const std::vector<std::string>& extra :
         {std::vector<std::string>{"--preview"}, std::vector<std::string>{"--no-checkpoint", "--passes", "1"},
          std::vector<std::string>{"--method", "pt", "--passes", "1"}}) {
        SCOPED_TRACE(extra[0]);
        p = runTpb(with(extra), dir_);
        EXPECT_EQ(p.code, 2) << p.err;
        EXPECT_NE(p.err.find("error: " + (out / "checkpoint.tpbck").string() +
                             ": holds the checkpoint of an earlier render (2 passes of "),
                  std::string::npos)
            << p.err;
        EXPECT_NE(p.err.find("which this tpb render would remove; a checkpoint is never discarded silently: continue "
                             "that render with `tpb render --resume " +
                             out.string() +
                             "`, give this run another "
                             "folder with -o, or add --overwrite-checkpoint to discard it"),
                  std::string::npos)
            << p.err;
        EXPECT_EQ(p.out.find("removed "), std::string::npos) << p.out;
        EXPECT_TRUE(slurp(out / "checkpoint.tpbck") == checkpoint) << "the checkpoint was removed or changed";
        EXPECT_TRUE(slurp(out / "steady.exr") == steady) << "nothing of the earlier render may be touched";
    }
    // The way forward the message names works: the checkpoint is there to resume.
    p = runTpb({"render", "--resume", out.string(), "--passes", "3", "--strip", "0", "-q"}, dir_);
    ASSERT_EQ(p.code, 0) << p.err;
    EXPECT_EQ(nlohmann::json::parse(slurp(out / "summary.json"))["passes"].get<int>(), 3);

    // A checkpoint the manifest does not list (copied in, or saved by the viewer) would be
    // overwritten by the next checkpoint of a new render: refused too.
    const fs::path other = dir_ / "other";
    fs::create_directories(other);
    fs::copy_file(out / "checkpoint.tpbck", other / "checkpoint.tpbck");
    p = runTpb({"render", scene.string(), "-o", other.string(), "--no-frames", "--strip", "0", "-q"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("which this tpb render would overwrite"), std::string::npos) << p.err;

    // Asked for explicitly: the earlier checkpoint goes, and the render says so.
    p = runTpb(with({"--preview", "--overwrite-checkpoint"}), dir_);
    EXPECT_EQ(p.code, 0) << p.err;
    EXPECT_FALSE(fs::exists(out / "checkpoint.tpbck"));
    EXPECT_NE(p.err.find("note: removed the earlier render's " + (out / "checkpoint.tpbck").string() +
                         " (--overwrite-checkpoint)"),
              std::string::npos)
        << p.err;
}

// Item 3: on a full disk ffmpeg exits with 0 after failing to write its trailer; tpb renamed the
// truncated, unplayable transient.mp4 into place (and then blamed summary.json). A fake ffmpeg on
// PATH does what ffmpeg does then: reads every frame, writes the start of an MP4 without its index,
// says so on stderr and exits 0. The file must be checked before it gets its final name, and the
// error must name transient.mp4.
TEST_F(CliSafety, VideoThatFfmpegLeftIncompleteIsRefusedAndNamed) {
    const fs::path scene = write("scene.json", boxScene(8, "{\"photons_per_pass\": 2000, \"passes\": 1, \"seed\": 1}"));
    const fs::path fake =
        write("fakebin/ffmpeg",
              "#!/bin/sh\n"
              "for a; do last=$a; done\n"
              "cat >/dev/null\n"
              "printf '\\000\\000\\000\\030ftypisom\\000\\000\\002\\000isomiso2\\000\\000\\020\\000mdat' "
              ">\"$last\"\n"
              "echo \"[mp4 @ 0x1] Error writing trailer of $last: No space left on device\" >&2\n"
              "exit 0\n");
    fs::permissions(fake, fs::perms::owner_all);
    const fs::path out = dir_ / "out";
    const std::string path = "PATH=" + (dir_ / "fakebin").string() + ":" + std::getenv("PATH");
    const Proc p =
        runTpb({"render", scene.string(), "-o", out.string(), "--no-frames", "--strip", "0", "--mp4"}, dir_, {path});
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("error: " + (out / "transient.mp4").string() +
                         ": ffmpeg exited with 0 but the video it wrote is not playable: it is cut short"),
              std::string::npos)
        << p.err;
    EXPECT_NE(p.err.find("No space left on device"), std::string::npos) << p.err;  // what ffmpeg said
    EXPECT_EQ(p.err.find("summary.json:"), std::string::npos) << p.err;
    EXPECT_FALSE(fs::exists(out / "transient.mp4"));
    for (const auto& e : fs::directory_iterator(out))
        EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
    const nlohmann::json summary = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_NE(summary["outputs"]["error"].get<std::string>().find("transient.mp4"), std::string::npos);
    for (const auto& f : summary["outputs"]["files"]) EXPECT_NE(f.get<std::string>(), "transient.mp4");
}

// Item 7: `--checkpoint` that could not be written only warned, and the render exited 0: a script
// believed it could resume. Now the outputs are still written, and the exit code is 2 with an error
// naming the checkpoint's file (here its name is taken by a folder, so the rename fails).
TEST_F(CliSafety, CheckpointThatCannotBeWrittenIsAnError) {
    const fs::path scene = write("scene.json", boxScene(8, "{\"photons_per_pass\": 2000, \"passes\": 1, \"seed\": 1}"));
    const fs::path out = dir_ / "out";
    fs::create_directories(out / "checkpoint.tpbck");
    const Proc p =
        runTpb({"render", scene.string(), "-o", out.string(), "--no-frames", "--strip", "0", "--checkpoint"}, dir_);
    EXPECT_EQ(p.code, 2) << p.err;
    EXPECT_NE(p.err.find("error: the checkpoint was not written: " + (out / "checkpoint.tpbck").string() + ": "),
              std::string::npos)
        << p.err;
    EXPECT_NE(p.err.find("this render cannot be resumed"), std::string::npos) << p.err;
    EXPECT_TRUE(fs::exists(out / "summary.json")) << "the outputs are still written";
    EXPECT_EQ(nlohmann::json::parse(slurp(out / "summary.json"))["checkpoint"].get<std::string>(), "");
    EXPECT_TRUE(fs::is_directory(out / "checkpoint.tpbck"));
}
