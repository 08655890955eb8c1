// `tpb view`: the interactive viewer (GLFW window, OpenGL 3.3 core, Dear ImGui). The driver
// renders in the background; this file holds the command line, the window and the main loop,
// including the headless screenshot mode used by the tests (--screenshot, --after-passes).
#include "base/error.h"
#include "io/image_io.h"
#include "viewer/app.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <thread>

namespace tpb::app {

namespace {

std::string gGlfwError;
std::atomic<int> gCloseSignal{0};  // the signal that closed the window, 0 = none
std::atomic<int> gStopSignals{0};  // Ctrl-C and SIGTERM received (a second one cancels an export)
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler only touches lock-free atomics");

void onGlfwError(int code, const char* msg) { gGlfwError = msg ? msg : "GLFW error " + std::to_string(code); }

// Ctrl-C, SIGTERM and SIGHUP (a closed terminal) close the window like its close button: the
// export or checkpoint being written is finished (~Viewer). After a hangup SIGPIPE is ignored (a
// message to the closed terminal's pipe must not kill the viewer); a second hangup changes nothing.
extern "C" void onCloseSignal(int sig) {
    if (sig == SIGHUP) {
        struct sigaction ignore {};
        ignore.sa_handler = SIG_IGN;
        sigaction(SIGPIPE, &ignore, nullptr);
    } else {
        gStopSignals.fetch_add(1);
    }
    int none = 0;
    gCloseSignal.compare_exchange_strong(none, sig);
}

// Installs onCloseSignal for its lifetime (a hangup ignored under nohup stays ignored) and restores
// the previous dispositions.
class CloseSignals {
public:
    CloseSignals() {
        gCloseSignal = 0;
        gStopSignals = 0;
        struct sigaction sa {};
        sa.sa_handler = onCloseSignal;
        sigemptyset(&sa.sa_mask);
        for (int i = 0; i < 4; ++i) sigaction(kSignals[i], nullptr, &previous_[i]);
        sigaction(SIGINT, &sa, nullptr);
        sigaction(SIGTERM, &sa, nullptr);
        if (previous_[2].sa_handler != SIG_IGN) sigaction(SIGHUP, &sa, nullptr);
    }
    ~CloseSignals() {
        for (int i = 0; i < 4; ++i) sigaction(kSignals[i], &previous_[i], nullptr);
    }
    CloseSignals(const CloseSignals&) = delete;
    CloseSignals& operator=(const CloseSignals&) = delete;

private:
    static constexpr int kSignals[4] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};
    struct sigaction previous_[4];
};

// Key presses (and auto-repeats), recorded by a GLFW key callback: ImGui 1.86 samples key states
// once per frame, so a press and release between two frames would be lost. ImGui chains to it.
std::vector<int> gKeys;  // (pressedKeys())
void onKey(GLFWwindow*, int key, int, int action, int) {
    const bool arrow = key == GLFW_KEY_LEFT || key == GLFW_KEY_RIGHT;  // the only keys that repeat
    if (action == GLFW_PRESS || (action == GLFW_REPEAT && arrow)) gKeys.push_back(key);
}

// The window and its GL context; glfwTerminate on destruction.
class GlfwWindow {
public:
    GlfwWindow(int width, int height, const std::string& title, bool vsync) {
        glfwSetErrorCallback(onGlfwError);
        if (!glfwInit()) fail();
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        glfwWindowHint(GLFW_DOUBLEBUFFER, GLFW_TRUE);
        window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!window_) {
            glfwTerminate();
            fail();
        }
        glfwMakeContextCurrent(window_);
        glfwSwapInterval(vsync ? 1 : 0);
    }
    ~GlfwWindow() {
        if (window_) glfwDestroyWindow(window_);
        glfwTerminate();
    }
    GlfwWindow(const GlfwWindow&) = delete;
    GlfwWindow& operator=(const GlfwWindow&) = delete;
    GLFWwindow* get() const { return window_; }

private:
    [[noreturn]] static void fail() {
        const std::string why = gGlfwError.empty() ? "" : " (" + gGlfwError + ")";
        throw UserError("cannot open a window" + why + ": no display? use `tpb render` or run under xvfb-run");
    }
    GLFWwindow* window_ = nullptr;
};

class ImGuiSession {
public:
    explicit ImGuiSession(GLFWwindow* window) {
        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;  // the layout is fixed; write nothing to the cwd
        ImGui::StyleColorsDark();
        glfwSetKeyCallback(window, onKey);  // before ImGui installs its callbacks, which chain to it
        ImGui_ImplGlfw_InitForOpenGL(window, true);
        if (!ImGui_ImplOpenGL3_Init("#version 330 core")) {
            ImGui_ImplGlfw_Shutdown();
            ImGui::DestroyContext();
            throw std::runtime_error("Dear ImGui: cannot initialise the OpenGL 3 renderer");
        }
    }
    ~ImGuiSession() {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    ImGuiSession(const ImGuiSession&) = delete;
    ImGuiSession& operator=(const ImGuiSession&) = delete;
};

}  // namespace

std::vector<int>& pressedKeys() { return gKeys; }

Viewer::Viewer(const PreparedRender& prepared, const RenderSettings& settings, const ViewOptions& opt,
               GLFWwindow* window, const std::string& resumePath)
    : prepared_(prepared),
      scene_(*prepared.scene),
      time_(prepared.time),
      scenePath_(prepared.source.path),
      opt_(opt),
      window_(window),
      // The steady preview while the film is allocated (session.h): not on a resume (the checkpoint
      // has passes to show) nor in screenshot mode (the picture is of --after-passes).
      session_(prepared, settings, opt.flags, resumePath, resumePath.empty() && opt.screenshot.empty(),
               [] { glfwPostEmptyEvent(); }) {
    const Scene& scene = scene_;
    program_.load(TPB_SHADER_DIR);
    const int maxTex = maxTextureSize();
    if (scene.camera.width > maxTex || scene.camera.height > maxTex || time_.bins > maxTex)
        throw UserError("the film (" + std::to_string(scene.camera.width) + "x" + std::to_string(scene.camera.height) +
                        ", " + std::to_string(time_.bins) + " bins) exceeds the largest OpenGL texture (" +
                        std::to_string(maxTex) + "); lower --width/--height/--bins");

    // Initial view: the scene's render settings, then the flags (as `tpb render` does).
    const RenderSettings& rd = settings;
    st_.axis = (rd.unwarp || opt.unwarp) && !opt.realTime ? TimeAxis::Unwarped : TimeAxis::Real;
    st_.mode = (rd.emission == EmissionMode::Continuous || opt.continuous) && !opt.delta ? EmissionMode::Continuous
                                                                                         : EmissionMode::Delta;
    // --bin and --time were checked against the film (runView). Without them, the bin of peak
    // energy once light arrives (updateBinEnergy): bin 0 is often before any light.
    if (opt.bin)
        setBin(*opt.bin);
    else if (opt.timeNs)
        setBin(time_.binOf(*opt.timeNs * kC_m_per_ns));
    st_.autoBin = !opt.bin && !opt.timeNs;
    if (opt.exposure) {
        st_.evFrame = st_.evSteady = static_cast<float>(*opt.exposure);
        st_.autoFrame = st_.autoSteady = false;
    }
    st_.response = *parseSensor(opt.sensor, *parsePulse(opt.pulse));  // (checked when parsed)
    st_.response.counting = parseCounting(opt.counts);
    if (st_.response.pulse != PulseShape::Delta) st_.pulseNs = st_.response.pulseWidth / kC_m_per_ns;
    if (st_.response.sensor != SensorShape::Ideal) st_.sensorNs = st_.response.sensorWidth / kC_m_per_ns;
    st_.display.falseColor = opt.falseColor;
    st_.display.srgb = !opt.noSrgb;
    // The first picture (issue 33): without a time asked for, the steady image - every surface
    // the light reaches, a picture within the first passes - until the user picks a time. A single
    // time bin of the first passes is a few photons' discs (the default scene's peak bin after two
    // passes: 5 % of the pixels lit; the steady image after the warm-up's three: over 90 %).
    st_.showSteady = opt.steady || (!opt.frame && !opt.bin && !opt.timeNs);
    st_.steadyUntilTime = st_.showSteady && !opt.steady;
    st_.selX = scene.camera.width / 2;
    st_.selY = scene.camera.height / 2;
    if (opt.pixel.size() == 2) {
        st_.selX = std::clamp(opt.pixel[0], 0, scene.camera.width - 1);
        st_.selY = std::clamp(opt.pixel[1], 0, scene.camera.height - 1);
    }
    if (!opt.exportFolder.empty()) st_.outDir = opt.exportFolder;
    // --export presses the Export buttons (screenshot mode), after the --click ones.
    clicks_ = opt.clicks;
    if (!opt.exportDir.empty()) {
        st_.outDir = opt.exportDir;
        clicks_.push_back("Export/Current frame");
        clicks_.push_back("Export/Steady state");
    }
    frameRgb_.assign(static_cast<size_t>(scene.camera.width) * scene.camera.height * 3, 0.0f);
    image_.upload(scene.camera.width, scene.camera.height, frameRgb_.data());
}

Viewer::~Viewer() {
    // Helper threads first (they only read the film); the session then finishes a checkpoint being
    // written, cancels an export and stops the render; the GL objects (members declared after the
    // session) are deleted first, while the context still exists.
    bpCancel_ = true;
    if (bpJob_.valid()) bpJob_.wait();
    if (profileJob_.valid()) profileJob_.wait();
    if (binEnergyJob_.valid()) binEnergyJob_.wait();
}

void Viewer::saveSnapshot(int fbWidth, int fbHeight) {
    snapRequested_ = false;
    char name[48];
    std::snprintf(name, sizeof name, "/window_%03d.png", ++snapCount_);
    const std::string dir = st_.outDir.empty() ? "." : st_.outDir;
    try {
        ensureWritableDir(dir);
        writePng8(dir + name, fbWidth, fbHeight, readBackBuffer(fbWidth, fbHeight));
        session_.setStatus("saved " + dir + name);
        std::printf("saved %s%s\n", dir.c_str(), name);
        std::fflush(stdout);
    } catch (const std::exception& e) {
        session_.setStatus(e.what());
    }
}

bool Viewer::waitForFilm() {
    // The window is open: show what is being prepared while the film is allocated (and a
    // checkpoint read) on a helper thread, instead of a black window for seconds.
    using namespace std::chrono_literals;
    while (!session_.filmReady()) {
        if (glfwWindowShouldClose(window_) || gCloseSignal.load() != 0) return false;
        glfwPollEvents();
        int fbw = 0, fbh = 0;
        glfwGetFramebufferSize(window_, &fbw, &fbh);
        if (fbw > 0 && fbh > 0) {
            ImGui_ImplOpenGL3_NewFrame();
            ImGui_ImplGlfw_NewFrame();
            ImGui::NewFrame();
            updatePreparingImage();
            drawPreparing();
            ImGui::Render();
            glViewport(0, 0, fbw, fbh);
            glClearColor(0.06f, 0.06f, 0.07f, 1.0f);
            glClear(GL_COLOR_BUFFER_BIT);
            ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
            glfwSwapBuffers(window_);
            if (windowShownSec_ < 0.0) windowShownSec_ = nowSec() - opt_.launchedAt;
        }
        std::this_thread::sleep_for(100ms);  // a few frames a second: the cores are the allocation's
    }
    adopted("", session_.adoptFirst());
    filmReadySec_ = nowSec() - opt_.launchedAt;
    std::printf("film ready %.2f s after the launch (window shown after %.2f s)\n", filmReadySec_, windowShownSec_);
    std::fflush(stdout);
    return true;
}

void Viewer::run() {
    const bool shot = !opt_.screenshot.empty();
    if (!waitForFilm()) {
        if (shot) {
            std::fprintf(stderr, "error: the viewer was closed before the screenshot was taken\n");
            exitCode_ = 1;
        }
        return;
    }
    double last = glfwGetTime();
    int extraFrames = 3;  // after an event, draw a few frames so ImGui settles
    while (!glfwWindowShouldClose(window_) && gCloseSignal.load() == 0) {
        const bool busyDriver = driver().running() && !driver().paused();
        const bool animate = shot || st_.playing || session_.exportJob().busy() || profileJob_.valid() ||
                             binEnergyJob_.valid() || bpJob_.valid() || !frameComplete_;
        if (animate || extraFrames > 0) {
            glfwPollEvents();
            if (extraFrames > 0) --extraFrames;
        } else {
            const double t0 = glfwGetTime();
            glfwWaitEventsTimeout(0.5);  // a finished pass wakes us (glfwPostEmptyEvent)
            if (glfwGetTime() - t0 < 0.45) extraFrames = 3;
        }
        int fbw = 0, fbh = 0;
        glfwGetFramebufferSize(window_, &fbw, &fbh);
        if (fbw <= 0 || fbh <= 0 || glfwGetWindowAttrib(window_, GLFW_ICONIFIED)) {  // minimised: nothing to draw
            session_.pollExport();
            session_.pollCheckpoint();
            glfwWaitEventsTimeout(0.1);
            continue;
        }

        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        if (shot) scriptedInput();  // after the backend has read the real mouse
        ImGui::NewFrame();
        const double now = glfwGetTime();
        const double dt = now - last;
        last = now;
        handleKeys(pressedKeys());
        pressedKeys().clear();
        advancePlayback(dt);
        session_.pollExport();
        session_.pollCheckpoint();
        updateFrame();
        updateProfile();
        updateBinEnergy();
        updateBackprojection();
        drawUi();
        ImGui::Render();

        glViewport(0, 0, fbw, fbh);
        glClearColor(0.06f, 0.06f, 0.07f, 1.0f);
        glClear(GL_COLOR_BUFFER_BIT);
        ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
        if (snapRequested_) saveSnapshot(fbw, fbh);
        if (shot) {
            if (!scriptError_.empty()) {
                std::fprintf(stderr, "error: %s\n", scriptError_.c_str());
                exitCode_ = kViewerExitUserError;
                screenshotTaken_ = true;  // nothing to take: the error says why
                break;
            }
            settleFrames_ = settled() ? settleFrames_ + 1 : 0;
            // Two full frames with the final data drawn, then read this one.
            if (clickIndex_ >= clicks_.size() && settleFrames_ >= 3) {
                endFrameChecks();
                takeScreenshot(fbw, fbh);
                break;
            }
        }
        glfwSwapBuffers(window_);
        if (windowShownSec_ < 0.0) windowShownSec_ = nowSec() - opt_.launchedAt;

        if (animate || extraFrames > 0) {  // cap the frame rate; leave the cores to the workers
            const double frame = busyDriver ? 1.0 / 30.0 : 1.0 / 60.0;
            const double spent = glfwGetTime() - now;
            if (spent < frame) std::this_thread::sleep_for(std::chrono::duration<double>(frame - spent));
        }
    }
    if (shot && !screenshotTaken_) {
        std::fprintf(stderr, "error: the viewer was closed before the screenshot was taken\n");
        const int sig = gCloseSignal.load();
        exitCode_ = sig ? 128 + sig : 1;  // closed by a signal: 128 + it, as a killed process would report
    }
}

void Viewer::finishBeforeClosing(const std::function<int()>& closeSignals) {
    // Closing the window (button, Ctrl-C, SIGTERM, SIGHUP) must not cut an export or a checkpoint
    // short: half the frames with no note, an MP4 dropped without a word. They are finished, with
    // their progress on stderr; a new Ctrl-C or SIGTERM cancels the export (which then names what
    // it did not write). The render stops unless the checkpoint still waits for its pass to end.
    using Stage = ViewerSession::CheckpointStage;
    ExportJob& exp = session_.exportJob();
    if (exp.busy() || session_.checkpointStage() != Stage::Idle) {
        glfwHideWindow(window_);
        const int signalsAtClose = closeSignals();
        std::fprintf(stderr, "closing: finishing the %s before quitting (Ctrl-C again cancels the export)\n",
                     exp.busy() ? ("export (" + exp.progressLabel() + ")").c_str() : "checkpoint");
        bool cancelled = false;
        double lastReport = glfwGetTime();
        while (exp.busy() || session_.checkpointStage() != Stage::Idle) {
            if (session_.checkpointStage() == Stage::Idle) driver().requestStop();
            if (!cancelled && exp.busy() && closeSignals() > signalsAtClose) {
                exp.cancel();
                cancelled = true;
                std::fprintf(stderr, "closing: cancelling the export\n");
            }
            session_.pollCheckpoint();
            if (!driver().running()) session_.abandonCheckpointWait();
            if (exp.busy() && glfwGetTime() - lastReport >= 2.0) {
                lastReport = glfwGetTime();
                std::fprintf(stderr, "closing: %s\n", exp.progressLabel().c_str());
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
    }
    session_.pollExport();  // what the last export wrote, or why it stopped (stdout, stderr)
}

namespace {

// --bin and --time name a bin of the film, or are refused with the film's range (before any window).
void checkShownTime(const ViewOptions& o, const TimeBins& tb) {
    if (o.bin && (*o.bin < 0 || *o.bin >= tb.bins))
        throw UserError("--bin " + std::to_string(*o.bin) + " is outside the film: its bins are 0 to " +
                        std::to_string(tb.bins - 1) + "; pick one of them (or a time with --time in ns)");
    if (!o.timeNs) return;
    char range[128];
    std::snprintf(range, sizeof range, "%.6g to %.6g ns", tb.startOpl / kC_m_per_ns, tb.endOpl() / kC_m_per_ns);
    if (!std::isfinite(*o.timeNs))
        throw UserError(std::string("--time must be a time in ns within the film: ") + range);
    const int k = tb.binOf(*o.timeNs * kC_m_per_ns);
    if (k < 0 || k >= tb.bins) {
        char t[32];
        std::snprintf(t, sizeof t, "%.6g", *o.timeNs);
        throw UserError(std::string("--time ") + t + " ns is outside the film (" + range +
                        "); pick a time in that range (the scene's film.range sets it; `tpb info` prints it)");
    }
}

}  // namespace

int runViewer(const PreparedRender& prepared, const ViewOptions& o, const std::string& resumePath) {
    const Scene* scene = prepared.scene.get();
    RenderSettings ds = prepared.settings;
    const bool shot = !o.screenshot.empty();
    if (shot) {  // run exactly N passes (beyond a resumed checkpoint's), then take the picture
        ds.passes =
            o.afterPasses + (resumePath.empty() ? 0 : static_cast<int64_t>(readCheckpointInfo(resumePath).passes));
        ds.timeBudgetSec = 0.0;
    }
    if (o.windowSize.size() != 2 || o.windowSize[0] < 64 || o.windowSize[1] < 64)
        throw UserError("--window-size needs two sizes >= 64");
    if (o.pixel.size() == 2 &&
        (o.pixel[0] < 0 || o.pixel[1] < 0 || o.pixel[0] >= scene->camera.width || o.pixel[1] >= scene->camera.height))
        throw UserError("--pixel " + std::to_string(o.pixel[0]) + " " + std::to_string(o.pixel[1]) +
                        " is outside the image: X is 0 to " + std::to_string(scene->camera.width - 1) + ", Y 0 to " +
                        std::to_string(scene->camera.height - 1));
    checkShownTime(o, prepared.time);  // --exposure, --after-passes, --time-budget: checked while parsing

    GlfwWindow window(o.windowSize[0], o.windowSize[1], "tpb view - " + prepared.source.path, !shot);
    ImGuiSession gui(window.get());
    const CloseSignals signals;  // Ctrl-C, SIGTERM, SIGHUP close the window like the close button
    int code = 0;
    {
        Viewer viewer(prepared, ds, o, window.get(), resumePath);
        std::printf("window open, rendering %s (close the window or press Ctrl-C to quit)\n",
                    prepared.source.path.c_str());
        std::fflush(stdout);
        viewer.run();
        viewer.finishBeforeClosing([] { return gStopSignals.load(); });
        code = viewer.exitCode();
    }
    // As `tpb render`: 0 after Ctrl-C, 128 + the signal after SIGTERM (143) or SIGHUP (129).
    const int sig = gCloseSignal.load();
    if ((sig == SIGTERM || sig == SIGHUP) && code == 0) code = 128 + sig;
    return code;
    // ~Viewer stopped the driver; ~ImGuiSession and ~GlfwWindow now release ImGui and the window.
}

}  // namespace tpb::app
