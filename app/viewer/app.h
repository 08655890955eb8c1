// The interactive viewer (`tpb view`), in three parts:
//   session.h/.cpp  the render session, no window: drivers, the steady preview, checkpoints, exports;
//   this class      the UI: the window's panels (ui.cpp), the data path from the film to the
//                   textures (data.cpp), the main loop (view.cpp);
//   script.cpp      the screenshot mode's scripted input and report (the tests drive it).
// The UI thread owns everything GL/ImGui; the driver's workers only write the film (and wake the
// UI after each pass); exports and the streak/profile reads run on their own threads and hold the
// driver alive through a shared_ptr.
//
// Its own CMake target (tpb_viewer): no CLI11, no nlohmann, nothing from app/cli. `tpb view`'s
// flags are registered in app/cli/view_command.cpp, which prepares the render (prepareRender)
// and calls runViewer.
#pragma once
#include "render/nlos_backprojection.h"
#include "viewer/session.h"
#include "viewer/gl.h"
#include "viewer/image_view.h"
#include "viewer/instrument.h"

#include <imgui.h>

#include <atomic>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

struct GLFWwindow;

namespace tpb::app {

inline constexpr int kViewerExitUserError = 2;  // the CLI's kExitUserError (view_command.cpp checks)
inline constexpr double kMaxExposureEv = 40.0;  // the Display section's exposure slider spans -40 to 40 EV
inline constexpr int64_t kMaxWindowPx = 16384;  // beyond any OpenGL 3.3 framebuffer
// The automatic bin (the brightest one, chosen while the first passes render) is found from every
// 4th pixel in x and y: its job then reads 1/16 of the film and holds its snapshot 16x shorter (a
// held tile makes the render copy it: with every pixel read, the first seven passes of the default
// scene took 3.7 s instead of 0.9 s, `tpb view ... --screenshot --after-passes 7`, timeline line).
inline constexpr int kAutoBinStride = 4;
inline constexpr float kProfileDecades = 6.0f;  // the profile's log scale spans this far below its peak

// What `tpb view` asks of the viewer beyond the prepared render (plain values, filled by the
// command line: app/cli/view_command.cpp).
struct ViewOptions {
    std::string screenshot, exportDir, exportFolder;
    std::vector<std::string> clicks;  // --click: controls to click before the screenshot, in order
    int64_t afterPasses = 1;
    std::optional<double> timeNs;
    std::optional<int> bin;
    std::optional<double> exposure;
    std::vector<int> pixel;  // x y
    std::vector<int> windowSize{1280, 800};
    bool unwarp = false, realTime = false, continuous = false, delta = false;
    bool falseColor = false, noSrgb = false, steady = false, frame = false;
    // The flags the render runs with, stored in the checkpoints "Save checkpoint" writes (to
    // <export folder>/checkpoint.tpbck: render/checkpoint.h) so `--resume` can reproduce it.
    SettingsOverrides flags;
    std::string pulse = "delta", sensor = "ideal";  // --pulse, --sensor (film/time_response.h; checked)
    std::string counts = "off";                     // --counts (film/photon_counting.h; checked)
    double launchedAt = 0.0;                        // nowSec() when `tpb view` started (the timeline's origin)
};

// What the user looks at (changed by the UI, never by other threads).
struct ViewState {
    int bin = 0;
    TimeAxis axis = TimeAxis::Real;
    EmissionMode mode = EmissionMode::Delta;
    // The pulse shape and sensor response the film is seen with, applied when reading (no re-render),
    // and the widths the View section's inputs hold (ns) while a shape is off.
    TimeResponse response;
    double pulseNs = 0.0, sensorNs = 0.0;
    bool showSteady = false;
    // Opened on the steady image by default (no --bin/--time/--frame/--steady): the first time the
    // user picks a time (slider, keys, Play, a click on the streak or the profile), the frame shows.
    bool steadyUntilTime = false;
    DisplayParams display;
    float evFrame = 0.0f, evSteady = 0.0f;  // exposure per view (frame and streak share evFrame)
    // Auto exposure pending: refitted to every fetch that shows light (the tiles finished so far)
    // until it has been fitted to a complete frame of at least one pass.
    bool autoFrame = true, autoSteady = true;
    // Automatic bin pending (no --bin/--time, the user has not moved the bin): the bin of peak
    // energy, refitted like the exposure until the first pass is complete.
    bool autoBin = true;
    bool playing = false, loop = true;
    bool profileLog = false;  // the pixel profile on a log scale (kProfileDecades below its peak)
    float speed = 8.0f;       // bins per second
    double playAccum = 0.0;
    int selX = 0, selY = 0;  // pixel of the profile; selY is the streak's row
    // Relay-wall scans: the back-projection panel (in place of the streak and profile), its grid
    // and filter (none by default: the Laplacian sharpens a converged capture but, after a few
    // passes, picks noise), and the depth slice shown (voxel index).
    bool showBackprojection = false;
    BackprojectionSettings bp{.flag = "the back-projection's grid"};
    int bpSlice = 0;
    bool bpSliceAuto = true;  // the slice follows the peak until the user moves it
    std::string outDir = "out/view";
    int sheetFrames = 16;  // frames of the contact sheet export
};

// Identifies the film data a buffer was fetched for.
struct FetchKey {
    uint64_t generation = ~0ull, passes = ~0ull;
    int bin = -1, x = -1, y = -1;
    TimeAxis axis = TimeAxis::Real;
    EmissionMode mode = EmissionMode::Delta;
    TimeResponse response;  // pulse shape and sensor response (film/time_response.h)
    bool steady = false;
    bool operator==(const FetchKey&) const = default;
};

struct ProfileResult {
    FetchKey key;
    std::vector<float> profile;  // bins*3
    std::vector<float> streak;   // bins rows x W cols x 3
    int width = 0, bins = 0;     // of the snapshot read
};

// Luminance of each bin (delta pulse, summed over the image) on one axis, for the automatic bin.
struct BinEnergyResult {
    FetchKey key;                // generation, passes, axis
    std::vector<double> energy;  // per bin
    bool complete = false;       // every tile of the snapshot read had the same passes
};

// The back-projection of one snapshot (render/nlos_backprojection.h), made on a helper thread.
struct BackprojectionResult {
    uint64_t generation = ~0ull, passes = ~0ull;  // of the snapshot read
    BackprojectionSettings settings;
    BackprojectionVolume volume;
    BackprojectionImages images;
    int64_t pairs = 0;     // (laser, sensor) pairs summed per voxel
    double seconds = 0.0;  // reading the capture and back-projecting
    std::string error;     // a refused grid (the settings' message)
};
// Same grid and filter (what a new back-projection is needed for).
bool sameBackprojection(const BackprojectionSettings& a, const BackprojectionSettings& b);
// Seconds between two back-projections while the render runs (one also follows the last pass).
inline constexpr double kBackprojectionEverySec = 2.0;

// The bin holding the most light, or -1 if the film is black.
int peakEnergyBin(const std::vector<double>& energy);

// A control as drawn in one frame: its name ("Section/label", the label without its ##id), its
// rectangle (window pixels) and its ImGui ID (0 for plain text).
struct ControlRect {
    std::string name;
    ImVec2 min, max;
    ImGuiID id = 0;
    bool visible = true;  // not scrolled out of view
};

class Viewer {
public:
    // `resumePath`: a checkpoint of this render to go on from (tpb view --resume, checked by
    // prepareResume), read into the first driver's film; "" = none.
    Viewer(const PreparedRender& prepared, const RenderSettings& settings, const ViewOptions& opt, GLFWwindow* window,
           const std::string& resumePath = "");
    ~Viewer();  // stops the driver and joins the helper threads (GL objects go with the members)
    void run();
    // After the window closed: an export or checkpoint in progress (or asked for) is finished, with
    // its progress on stderr; a new Ctrl-C/SIGTERM (closeSignals() grows) cancels the export. What
    // was written, and what was not, is printed.
    void finishBeforeClosing(const std::function<int()>& closeSignals);
    int exitCode() const { return exitCode_; }

private:
    // the render session (session.h) and the data path from its film (data.cpp)
    Driver& driver() { return session_.driver(); }
    const Driver& driver() const { return session_.driver(); }
    void restart(const RenderSettings& s, const std::string& why);
    void adopted(const std::string& why, uint64_t resumedPasses);  // a new driver started: reset the UI's view of it
    void updateFrame();
    void updateProfile();
    void updateBinEnergy();
    void updateBackprojection();  // relay-wall scans, when the panel is shown
    void drawBackprojectionSection();
    void drawBackprojectionPanel();
    bool backprojectionSettled() const;  // shown and up to date with the film and settings (or not shown)
    void fitPendingExposure(const FetchKey& key);
    void fitHiddenFrameExposure();
    void trackNoise(const FetchKey& key);  // after a frame fetch
    void drawTimeResponse();               // View section: pulse shape and sensor response
    void drawCounting();                   // View section: the film as SPAD photon counts
    std::string responseNote() const;
    const char* emissionLabel()
        const;  // "delta pulse", "pulse response" or "continuous emission"  // " (gaussian pulse, FWHM 1 ns; ideal sensor)" or ""

    FetchKey frameKey() const;
    FetchKey profileKey() const;
    FetchKey binEnergyKey() const;
    float binCentreOpl(int bin) const;

    // UI (ui.cpp)
    void drawUi();
    void drawControls();
    void drawImagePanel();
    void drawColourBar(ImVec2 at, float width);  // under the image, with false colour
    void drawTimePanel();
    void drawTimeSection();
    void drawProgressSection();
    void drawNoise();  // the noise indicator row
    void drawSettingsSection();
    bool drawEstimatorSettings();
    void drawExportSection();
    void drawMessages();
    void drawPopups();  // the confirmations: restart the accumulation, quit during an export
    void askRestart(const RenderSettings& s, const std::string& what);  // restart, asking first once passes are in
    void requestQuit();                                                 // Esc / Q
    bool section(const char* label, ImGuiTreeNodeFlags flags = 0);      // a collapsing header, tracked
    void track(const char* label);                  // records the last item as control "<section>/<label>"
    void handleKeys(const std::vector<int>& keys);  // GLFW key codes pressed since the last frame
    void advancePlayback(double dt);
    void setBin(int bin);  // the user's choice: ends the automatic bin
    void showFrameOnce();  // the steady image shown by default gives way to the frame
    void setAutoBin(int bin);

    // main loop (view.cpp); the screenshot-mode script (script.cpp)
    bool waitForFilm();  // draws "preparing" frames until the first driver is made; false: closed
    void drawPreparing();
    bool settled();        // nothing left to fetch, render or export
    void scriptedInput();  // screenshot mode: --click / --export, injected as ImGui mouse input
    void endFrameChecks();
    void takeScreenshot(int fbWidth, int fbHeight);
    void saveSnapshot(int fbWidth, int fbHeight);

    const PreparedRender& prepared_;  // the render as prepared (checkpoints record it)
    const Scene& scene_;
    TimeBins time_;          // the film's time axis
    std::string scenePath_;  // for the title and the info panel
    ViewOptions opt_;
    GLFWwindow* window_;
    ViewState st_;

    ViewerSession session_;
    uint64_t previewFetched_ = 0;  // the preview's passes image_ shows while preparing
    void updatePreparingImage();
    RenderSettings edit_;  // the settings panel's copy

    DisplayProgram program_;
    DisplayImage image_, streak_;
    bool imageDirty_ = true, streakDirty_ = true;
    DisplayParams lastImageParams_, lastStreakParams_;

    std::vector<float> frameRgb_;  // CPU copy of what image_ shows
    FetchKey frameKey_;
    bool frameComplete_ = false;
    double lastFetch_ = 0.0, fetchSec_ = 0.0;  // when and how long the last fetch took
    ExposureFit lastFit_;
    BatchNoise noise_;              // of the picture shown (noiseKey_), from the spread between passes
    FetchKey noiseKey_;             // its key without the passes
    uint64_t hiddenFitPasses_ = 0;  // the passes the frames' exposure was last fitted to behind the steady image

    std::future<BinEnergyResult> binEnergyJob_;
    FetchKey binEnergyRequested_;
    double binEnergyLaunched_ = -1e9, binEnergySec_ = 0.0;

    std::future<BackprojectionResult> bpJob_;
    std::atomic<bool> bpCancel_{false};
    std::optional<BackprojectionResult> bp_;  // the last one finished
    double bpLaunched_ = -1e9;
    DisplayImage bpFront_, bpDepth_, bpSliceImage_, bpTop_;
    ImVec4 bpFrontArea_{0, 0, 0, 0};  // where the front image was drawn (x, y, w, h; screenshot report)
    int bpSliceUploaded_ = -1;        // the slice bpSliceImage_ shows (-1: none since bp_ changed)

    std::future<ProfileResult> profileJob_;
    FetchKey profileRequested_, profileKey_;
    std::vector<float> profileRgb_, profileLum_;

    // The confirmation asked (its popup opens on the next drawUi), and the restart it would do.
    static constexpr const char* kRestartPopup = "Restart the accumulation?";
    static constexpr const char* kQuitPopup = "Quit during the export?";
    const char* openPopup_ = nullptr;
    std::optional<RenderSettings> pendingRestart_;
    std::string pendingWhat_;

    // Controls drawn this frame, and in the first frame (screenshot mode reports both).
    const char* section_ = "";
    std::vector<ControlRect> controls_, firstControls_;
    float controlsMinX_ = 0.0f, controlsMaxX_ = 0.0f;  // the messages' content, window pixels
    bool firstRecorded_ = false;
    uint64_t firstPasses_ = 0;
    bool firstRunning_ = false;
    std::vector<std::string> idClashes_;  // "A" and "B" share an ImGui ID (reported once each)

    // Scripted clicks (screenshot mode): the queue, the click in progress and its phase.
    std::vector<std::string> clicks_;
    size_t clickIndex_ = 0;
    int clickPhase_ = 0;
    ImVec2 clickPos_{0, 0};

    // Where the film image was drawn (framebuffer pixels), for the screenshot report.
    ImVec2 imageMin_{0, 0}, imageSize_{0, 0};
    ImVec2 canvasMin_{0, 0}, canvasSize_{0, 0};  // the panel's area for the image
    float imageZoom_ = 1.0f;
    ImageViewport view_;                                    // fitted, or the user's zoom and pan
    std::vector<AxisTick> streakTicksNs_, profileTicksNs_;  // as drawn (screenshot report)
    std::vector<AxisTick> colourBarTicks_;                  // value: position on the bar (0..1), label: film luminance

    bool snapRequested_ = false;  // F12 / the button: save the window to the export folder
    int snapCount_ = 0;

    // Timeline of the current accumulation (glfwGetTime, s): when it (re)started, when a fetched
    // image first had light in it (-1: not yet), for the Progress section and the screenshot report.
    double startedAt_ = 0.0, firstLightSec_ = -1.0;
    // From the launch of `tpb view` (ViewOptions::launchedAt, steady clock): when the window first
    // showed a frame, and when the film was ready and the passes started (-1: not yet).
    double windowShownSec_ = -1.0, filmReadySec_ = -1.0;

    int settleFrames_ = 0;
    bool screenshotTaken_ = false;
    std::string scriptError_;  // a --click that could not be done
    int exitCode_ = 0;
};

// Keys pressed (GLFW codes) since the UI last handled them: the GLFW key callback's and the
// script's (view.cpp).
std::vector<int>& pressedKeys();

// Opens the window and runs the viewer on a prepared render until it is closed (or, with
// --screenshot, until the picture is taken).
// Returns the exit code: 0, kViewerExitUserError (an export or checkpoint failed, a bad --click),
// 1 (a screenshot not taken, a check failed), 128 + the signal that closed it (SIGTERM, SIGHUP).
int runViewer(const PreparedRender& prepared, const ViewOptions& options, const std::string& resumePath = "");

}  // namespace tpb::app
