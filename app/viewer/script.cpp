// The scripted-input harness of the viewer's screenshot mode (`tpb view --screenshot`, used by
// the tests under Xvfb): --click and --export injected as ImGui mouse input where a user's clicks
// go, key presses, the wait until everything has settled, and the machine-readable report printed
// with the screenshot.
#include "viewer/app.h"

#include "base/error.h"
#include "io/image_io.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace tpb::app {

bool Viewer::settled() {
    if (driver().running() || session_.exportJob().busy() || profileJob_.valid() || binEnergyJob_.valid() ||
        session_.checkpointStage() != ViewerSession::CheckpointStage::Idle)
        return false;
    if (st_.autoBin && !(binEnergyRequested_ == binEnergyKey())) return false;
    if (!(frameKey_ == frameKey()) || !frameComplete_) return false;
    if (!backprojectionSettled()) return false;
    return profileKey_ == profileKey();
}

namespace {

// The keys a script can press (--click key:NAME), as GLFW codes; -1 for another name.
int scriptedKey(const std::string& name) {
    const std::pair<const char*, int> keys[] = {
        {"Escape", GLFW_KEY_ESCAPE}, {"Q", GLFW_KEY_Q},         {"F", GLFW_KEY_F},        {"1", GLFW_KEY_1},
        {"Left", GLFW_KEY_LEFT},     {"Right", GLFW_KEY_RIGHT}, {"Space", GLFW_KEY_SPACE}};
    for (const auto& [n, code] : keys)
        if (name == n) return code;
    return -1;
}

// "Export (EXR)/Current frame" may be written "Export/Current frame" (a section without its note).
bool controlNamed(const ControlRect& c, const std::string& want) {
    if (c.name == want) return true;
    const size_t slash = c.name.find('/'), paren = c.name.find(" (");
    return slash != std::string::npos && paren < slash && c.name.substr(0, paren) + c.name.substr(slash) == want;
}

}  // namespace

void Viewer::scriptedInput() {
    // Screenshot mode: the pointer stays off the window (no hover in the picture) except to do the
    // --click and --export clicks, as ImGui mouse input, so they go where a user's clicks go: the
    // control's hit test and ID. Each waits until the previous one's effect is over.
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
    for (bool& down : io.MouseDown) down = false;
    if (clickIndex_ >= clicks_.size() || !scriptError_.empty()) return;
    const std::string& want = clicks_[clickIndex_];
    if (want.rfind("key:", 0) == 0) {  // a key press, on the frame after the previous click
        if (clickIndex_ == 0 && settleFrames_ < 3) return;
        const int key = scriptedKey(want.substr(4));
        if (key < 0) {
            scriptError_ = "--click '" + want + "': no such key; the keys are Escape, Q, F, 1, Left, Right, Space";
            return;
        }
        std::printf("key: %s\n", want.c_str() + 4);
        std::fflush(stdout);
        pressedKeys().push_back(key);
        ++clickIndex_;
        settleFrames_ = 0;
        return;
    }
    if (clickPhase_ == 0) {
        if (settleFrames_ < 3) return;
        const auto c = std::find_if(controls_.begin(), controls_.end(),
                                    [&](const ControlRect& r) { return controlNamed(r, want); });
        if (c == controls_.end()) {
            scriptError_ = "--click '" + want + "': no such control in the window; the controls are:";
            for (const ControlRect& r : controls_) scriptError_ += "\n  " + r.name;
            return;
        }
        if (!c->visible) {
            scriptError_ = "--click '" + want + "': the control is scrolled out of view; use a taller --window-size";
            return;
        }
        clickPos_ = ImVec2(std::floor(0.5f * (c->min.x + c->max.x)), std::floor(0.5f * (c->min.y + c->max.y)));
        std::printf("click: %s at %.0f %.0f\n", c->name.c_str(), clickPos_.x, clickPos_.y);
        std::fflush(stdout);
    }
    // Frames: 1 hover, 2 press, 3 release (a button fires on release over it).
    ++clickPhase_;
    io.MousePos = clickPos_;
    io.MouseDown[0] = clickPhase_ == 2;
    if (clickPhase_ == 3) {
        clickPhase_ = 0;
        ++clickIndex_;
        settleFrames_ = 0;
    }
}

void Viewer::takeScreenshot(int fbWidth, int fbHeight) {
    const std::vector<unsigned char> px = readBackBuffer(fbWidth, fbHeight);
    const std::filesystem::path parent = std::filesystem::path(opt_.screenshot).parent_path();
    if (!parent.empty()) ensureWritableDir(parent.string());
    writePng8(opt_.screenshot, fbWidth, fbHeight, px);
    screenshotTaken_ = true;
    const uint64_t passes = driver().completedPasses();
    if (passes < static_cast<uint64_t>(opt_.afterPasses))
        std::fprintf(stderr, "warning: the render stopped after %llu passes (asked: %lld)\n",
                     static_cast<unsigned long long>(passes), static_cast<long long>(opt_.afterPasses));
    std::printf("screenshot: %s (%dx%d) after %llu passes\n", opt_.screenshot.c_str(), fbWidth, fbHeight,
                static_cast<unsigned long long>(passes));
    // Machine-readable: where the film image is in the screenshot and how it was mapped.
    std::printf("image_area %.3f %.3f %.3f %.3f zoom %.6f exposure_ev %.9g bin %d steady %d mode %s axis %s\n",
                imageMin_.x, imageMin_.y, imageSize_.x, imageSize_.y, imageZoom_,
                static_cast<double>(st_.showSteady ? st_.evSteady : st_.evFrame), st_.bin, st_.showSteady ? 1 : 0,
                st_.mode == EmissionMode::Delta ? "delta" : "continuous",
                st_.axis == TimeAxis::Real ? "real" : "unwarped");
    std::printf("image_panel %.3f %.3f %.3f %.3f fit %d\n", canvasMin_.x, canvasMin_.y, canvasSize_.x, canvasSize_.y,
                view_.fit ? 1 : 0);
    // The time axes' ticks (ns) and the colour bar's labels, as drawn.
    const auto labels = [](const char* what, const std::vector<AxisTick>& ticks) {
        std::printf("%s", what);
        for (const AxisTick& t : ticks) std::printf(" %s", t.label.c_str());
        std::printf("\n");
    };
    labels("ticks streak_ns", streakTicksNs_);
    labels("ticks profile_ns", profileTicksNs_);
    labels("colour_bar", colourBarTicks_);
    std::printf("profile_log %d\n", st_.profileLog ? 1 : 0);
    if (bp_ && bp_->error.empty()) {  // the back-projection shown (backprojection_view.cpp)
        const BackprojectionVolume& v = bp_->volume;
        const Vec3 p = v.grid.voxel(v.peakI, v.peakJ, v.peakK);
        std::printf(
            "backprojection passes %llu voxels %d %d %d pairs %lld ms %.3f peak_voxel %d %d %d depth_m %.6g "
            "position_m %.6g %.6g %.6g front_area %.1f %.1f %.1f %.1f\n",
            static_cast<unsigned long long>(bp_->passes), v.grid.nx(), v.grid.ny(), v.grid.nz(),
            static_cast<long long>(bp_->pairs), 1000.0 * bp_->seconds, v.peakI, v.peakJ, v.peakK,
            v.grid.depthsM[static_cast<size_t>(v.peakK)], p.x, p.y, p.z, bpFrontArea_.x, bpFrontArea_.y, bpFrontArea_.z,
            bpFrontArea_.w);
    } else if (bp_) {
        std::printf("backprojection error %s\n", bp_->error.c_str());
    }
    std::printf("noise relative_error %.6g batches %d\n", noise_.relativeError(), noise_.batches());
    // How fast the picture came: seconds from the driver's start to the first fetched image with
    // light, and to the end of each pass (the warm-up's effect; issue 15's targets: light within 1 s,
    // four passes within 3 s).
    std::printf("timeline first_light_s %.3f warmup %d pass_end_s", firstLightSec_, driver().settings().warmupPasses);
    for (const PassStats& ps : driver().history()) std::printf(" %.3f", ps.elapsedSec);
    // Tile adds that had to copy their block because the viewer held a snapshot of it, of all.
    const FilmStats& fs = driver().film().stats;
    std::printf(" copied_tiles %lld of %lld\n", static_cast<long long>(fs.copiedTiles.load()),
                static_cast<long long>(fs.stagedTiles.load()));
    // From the launch of `tpb view`: the window's first frame, the film ready (the passes start).
    std::printf("opening window_s %.3f film_ready_s %.3f\n", windowShownSec_, filmReadySec_);
    // The controls (window pixels) now and in the first frame, drawn while the first pass rendered.
    std::printf("messages_area %.1f %.1f\n", controlsMinX_, controlsMaxX_);
    std::printf("layout_first passes %llu running %d\n", static_cast<unsigned long long>(firstPasses_),
                firstRunning_ ? 1 : 0);
    for (const ControlRect& c : firstControls_)
        std::printf("control_first %.1f %.1f %.1f %.1f %s\n", c.min.x, c.min.y, c.max.x - c.min.x, c.max.y - c.min.y,
                    c.name.c_str());
    for (const ControlRect& c : controls_)
        std::printf("control %.1f %.1f %.1f %.1f %s\n", c.min.x, c.min.y, c.max.x - c.min.x, c.max.y - c.min.y,
                    c.name.c_str());
    std::fflush(stdout);
}

void Viewer::endFrameChecks() {
    // Screenshot mode: the film is final, every click done and its effect over. Checks, then the
    // picture is taken by the caller.
    if (!session_.exportError().empty() || session_.checkpointFailed()) exitCode_ = kViewerExitUserError;
    if (!opt_.exportDir.empty()) {
        const std::string frame = st_.outDir + "/" + frameName(st_.bin, outputTag(st_.axis, st_.mode, st_.response));
        for (const std::string& want : {frame, st_.outDir + "/" + kSteadyExrName})
            if (std::find(session_.exported().begin(), session_.exported().end(), want) == session_.exported().end()) {
                std::fprintf(stderr, "error: --export: the Export buttons did not write %s\n", want.c_str());
                exitCode_ = 1;
            }
    }
    if (!idClashes_.empty()) exitCode_ = 1;  // reported on stderr when found
}

}  // namespace tpb::app
