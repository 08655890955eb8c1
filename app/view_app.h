// The interactive viewer (`tpb view`): a Driver renders in the background while the UI thread
// shows the film. The UI thread owns everything GL/ImGui; the driver's workers only write the film
// (and wake the UI with glfwPostEmptyEvent after each pass); exports and the streak/profile reads
// run on their own threads and hold the driver alive through a shared_ptr.
#pragma once
#include "cli_common.h"
#include "driver.h"
#include "view_export.h"
#include "view_gl.h"

#include <imgui.h>

#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

struct GLFWwindow;

namespace tpb::app {

struct ViewOptions {
    std::string scene;
    RenderOverrides ov;
    std::string screenshot, exportDir;
    int64_t afterPasses = 1;
    std::optional<double> timeNs;
    std::optional<int> bin;
    std::optional<double> exposure;
    std::vector<int> pixel;  // x y
    std::vector<int> windowSize{1280, 800};
    bool unwarp = false, realTime = false, continuous = false, delta = false;
    bool falseColor = false, noSrgb = false, steady = false;
};

// What the user looks at (changed by the UI, never by other threads).
struct ViewState {
    int bin = 0;
    TimeAxis axis = TimeAxis::Real;
    EmissionMode mode = EmissionMode::Delta;
    bool showSteady = false;
    DisplayParams display;
    float evFrame = 0.0f, evSteady = 0.0f;  // exposure per view (frame and streak share evFrame)
    bool autoFrame = true, autoSteady = true;  // auto exposure pending
    bool playing = false, loop = true;
    float speed = 8.0f;  // bins per second
    double playAccum = 0.0;
    int selX = 0, selY = 0;  // pixel of the profile; selY is the streak's row
    std::string outDir = "out/view";
};

// Identifies the film data a buffer was fetched for.
struct FetchKey {
    uint64_t generation = ~0ull, passes = ~0ull;
    int bin = -1, x = -1, y = -1;
    TimeAxis axis = TimeAxis::Real;
    EmissionMode mode = EmissionMode::Delta;
    bool steady = false;
    bool operator==(const FetchKey&) const = default;
};

struct ProfileResult {
    FetchKey key;
    std::vector<float> profile;  // bins*3
    std::vector<float> streak;   // bins rows x W cols x 3
};

class Viewer {
public:
    Viewer(const Scene& scene, const DriverSettings& settings, const ViewOptions& opt, GLFWwindow* window);
    ~Viewer();  // stops the driver and joins the helper threads (GL objects go with the members)
    void run();

private:
    // session (view_data.cpp)
    void restart(const DriverSettings& s, const std::string& why);
    void updateFrame();
    void updateProfile();
    void pollExport();
    void startExport(const ExportRequest& req);
    FetchKey frameKey() const;
    FetchKey profileKey() const;
    float binCentreOpl(int bin) const;

    // UI (view_ui.cpp)
    void drawUi();
    void drawControls();
    void drawImagePanel();
    void drawTimePanel();
    void drawTimeSection();
    void drawProgressSection();
    void drawSettingsSection();
    void drawExportSection();
    void handleKeys(const std::vector<int>& keys);  // GLFW key codes pressed since the last frame
    void advancePlayback(double dt);
    void setBin(int bin);

    // main loop (view_main.cpp)
    bool screenshotReady();
    void takeScreenshot(int fbWidth, int fbHeight);
    void saveSnapshot(int fbWidth, int fbHeight);

    const Scene& scene_;
    ViewOptions opt_;
    GLFWwindow* window_;
    ViewState st_;

    std::shared_ptr<Driver> driver_;
    uint64_t generation_ = 0;
    DriverSettings edit_;  // the settings panel's copy
    std::string status_;

    DisplayProgram program_;
    DisplayImage image_, streak_;
    bool imageDirty_ = true, streakDirty_ = true;
    DisplayParams lastImageParams_, lastStreakParams_;

    std::vector<float> frameRgb_;  // CPU copy of what image_ shows
    FetchKey frameKey_;
    bool frameComplete_ = false;
    double lastFetch_ = 0.0;

    std::future<ProfileResult> profileJob_;
    FetchKey profileRequested_, profileKey_;
    std::vector<float> profileRgb_, profileLum_;

    ExportJob export_;
    bool exportRequested_ = false, exportDone_ = false;  // --export (screenshot mode)
    std::vector<std::string> exportLog_;
    std::string exportError_;

    // Where the film image was drawn (framebuffer pixels), for the screenshot report.
    ImVec2 imageMin_{0, 0}, imageSize_{0, 0};
    float imageZoom_ = 1.0f;

    bool snapRequested_ = false;  // F12 / the button: save the window to the export folder
    int snapCount_ = 0;

    int settleFrames_ = 0;
    bool screenshotTaken_ = false;
    int exitCode_ = 0;
};

float autoExposureEv(const std::vector<float>& rgb, bool& found);

}  // namespace tpb::app
