// Viewer: the ImGui panels (controls on the left, the film image top right, the streak image and
// the selected pixel's time profile bottom right). Layout follows the window size.
#include "viewer/app.h"

#include "render/auto_radius.h"

#include "base/error.h"
#include "estimators/estimator_names.h"

#include <imgui_internal.h>  // ImGui::GetItemID (public from ImGui 1.88)
#include <imgui_stdlib.h>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>  // key codes (ImGui 1.86 indexes keys by the backend's codes)

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>

namespace tpb::app {

namespace {

constexpr ImGuiWindowFlags kPanel = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                                    ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoBringToFrontOnFocus;

constexpr ImU32 kTickColour = IM_COL32(200, 200, 210, 220);  // axis ticks and their labels

ImTextureID texId(GLuint tex) { return reinterpret_cast<ImTextureID>(static_cast<intptr_t>(tex)); }

void hint(const char* text) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
    ImGui::TextWrapped("%s", text);
    ImGui::PopStyleColor();
}

void wrappedColored(const ImVec4& colour, const std::string& text) {
    ImGui::PushStyleColor(ImGuiCol_Text, colour);
    ImGui::TextWrapped("%s", text.c_str());
    ImGui::PopStyleColor();
}

// What the user reads on a control: the label without its "##id" / "###id" suffix.
// (An unlabelled control, e.g. "##prev", is named by its ID.)
std::string visibleLabel(const char* label) {
    const std::string s(label);
    const size_t hash = s.find("##");
    if (hash == 0) return s.substr(s.find_first_not_of('#'));
    return s.substr(0, hash);
}

const char* axisName(TimeAxis a) { return a == TimeAxis::Real ? "real time" : "camera-unwarped time"; }

}  // namespace

void Viewer::setBin(int bin) {
    st_.bin = std::clamp(bin, 0, time_.bins - 1);
    st_.autoBin = false;  // the user chose a time: no more automatic bin
    showFrameOnce();
}

void Viewer::showFrameOnce() {
    if (!st_.steadyUntilTime) return;
    st_.steadyUntilTime = false;
    st_.showSteady = false;
}

void Viewer::setAutoBin(int bin) { st_.bin = std::clamp(bin, 0, time_.bins - 1); }

bool Viewer::section(const char* label, ImGuiTreeNodeFlags flags) {
    const bool open = ImGui::CollapsingHeader(label, flags);
    section_ = "";
    track(label);
    section_ = label;
    return open;
}

void Viewer::track(const char* label) {
    ControlRect c;
    c.name = section_[0] ? visibleLabel(section_) + "/" + visibleLabel(label) : visibleLabel(label);
    c.min = ImGui::GetItemRectMin();
    c.max = ImGui::GetItemRectMax();
    c.id = ImGui::GetItemID();
    c.visible = ImGui::IsItemVisible();
    // Two widgets of one window with the same ID share their hover/click state: the second one
    // never fires (the "Steady state" export button did nothing that way). Report each clash once.
    if (c.id != 0)
        for (const ControlRect& o : controls_)
            if (o.id == c.id) {
                const std::string clash = "'" + o.name + "' and '" + c.name + "'";
                if (std::find(idClashes_.begin(), idClashes_.end(), clash) == idClashes_.end()) {
                    idClashes_.push_back(clash);
                    std::fprintf(stderr, "internal error (bug): the viewer's controls %s share an ImGui ID\n",
                                 clash.c_str());
                }
            }
    controls_.push_back(std::move(c));
}

void Viewer::handleKeys(const std::vector<int>& keys) {
    if (ImGui::GetIO().WantTextInput) return;  // typing in a field
    for (int key : keys) {
        switch (key) {
            case GLFW_KEY_LEFT: setBin(st_.bin - 1); break;
            case GLFW_KEY_RIGHT: setBin(st_.bin + 1); break;
            case GLFW_KEY_HOME: setBin(0); break;
            case GLFW_KEY_END: setBin(time_.bins - 1); break;
            case GLFW_KEY_SPACE: st_.playing = !st_.playing; break;
            case GLFW_KEY_F12: snapRequested_ = true; break;
            case GLFW_KEY_F: view_ = ImageViewport{}; break;
            case GLFW_KEY_ESCAPE:
            case GLFW_KEY_Q:
                if (!ImGui::IsPopupOpen(nullptr, ImGuiPopupFlags_AnyPopupId)) requestQuit();
                break;
            case GLFW_KEY_1:
                view_ = oneToOne(scene_.camera.width, scene_.camera.height, ImGui::GetIO().DisplayFramebufferScale.x);
                break;
            default: break;
        }
    }
}

void Viewer::advancePlayback(double dt) {
    if (!st_.playing) {
        st_.playAccum = 0.0;
        return;
    }
    st_.autoBin = false;
    showFrameOnce();
    st_.playAccum += std::min(dt, 0.25) * st_.speed;
    while (st_.playAccum >= 1.0) {
        st_.playAccum -= 1.0;
        if (st_.bin + 1 < time_.bins) {
            ++st_.bin;
        } else if (st_.loop) {
            st_.bin = 0;
        } else {
            st_.playing = false;
            st_.playAccum = 0.0;
            break;
        }
    }
}

void Viewer::drawUi() {
    const ImVec2 ds = ImGui::GetIO().DisplaySize;
    const float left = std::floor(std::min(std::clamp(ds.x * 0.3f, 300.0f, 420.0f), ds.x * 0.5f));
    const float topH = std::floor(ds.y * 0.6f);

    controls_.clear();
    ImGui::SetNextWindowPos(ImVec2(0, 0));
    ImGui::SetNextWindowSize(ImVec2(left, ds.y));
    if (ImGui::Begin("Controls", nullptr, kPanel | ImGuiWindowFlags_NoScrollbar)) {
        // The controls scroll; below them, always in view and always the same size, the messages
        // (wrapped, scrolling when long), so a message never moves a control.
        const ImGuiStyle& style = ImGui::GetStyle();
        const float messagesH = 3.0f * ImGui::GetTextLineHeightWithSpacing() + 2.0f * style.WindowPadding.y;
        ImGui::BeginChild("##controls", ImVec2(0, -(messagesH + style.ItemSpacing.y)), false,
                          ImGuiWindowFlags_AlwaysVerticalScrollbar);
        drawControls();
        ImGui::EndChild();
        ImGui::BeginChild("##messages", ImVec2(0, messagesH), true);
        section_ = "Messages";
        drawMessages();
        controlsMinX_ = ImGui::GetWindowPos().x + ImGui::GetWindowContentRegionMin().x;
        controlsMaxX_ = ImGui::GetWindowPos().x + ImGui::GetWindowContentRegionMax().x;
        ImGui::EndChild();
    }
    ImGui::End();

    ImGui::SetNextWindowPos(ImVec2(left, 0));
    ImGui::SetNextWindowSize(ImVec2(ds.x - left, topH));
    section_ = "Image";
    if (ImGui::Begin("Image", nullptr, kPanel | ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse))
        drawImagePanel();
    ImGui::End();

    ImGui::SetNextWindowPos(ImVec2(left, topH));
    ImGui::SetNextWindowSize(ImVec2(ds.x - left, ds.y - topH));
    if (st_.showBackprojection && scene_.camera.scan != ScanMode::None) {
        section_ = "Back-projection panel";
        if (ImGui::Begin("Back-projection panel", nullptr, kPanel | ImGuiWindowFlags_NoScrollbar))
            drawBackprojectionPanel();
    } else {
        section_ = "Streak and pixel profile";
        if (ImGui::Begin("Streak and pixel profile", nullptr, kPanel | ImGuiWindowFlags_NoScrollbar)) drawTimePanel();
    }
    ImGui::End();
    drawPopups();
    if (!firstRecorded_) {  // the layout the user first aims at (screenshot mode reports it)
        firstRecorded_ = true;
        firstControls_ = controls_;
        firstPasses_ = driver().completedPasses();
        firstRunning_ = driver().running();
    }
}

void Viewer::drawPreparing() {
    // The window before the film exists: what is being prepared, so it is never a black window.
    const ImVec2 ds = ImGui::GetIO().DisplaySize;
    ImGui::SetNextWindowPos(ImVec2(0, 0));
    ImGui::SetNextWindowSize(ds);
    if (ImGui::Begin("Preparing", nullptr, kPanel | ImGuiWindowFlags_NoTitleBar)) {
        const int w = scene_.camera.width, h = scene_.camera.height;
        const bool picture = previewFetched_ > 0;
        if (!picture) ImGui::SetCursorPos(ImVec2(std::floor(ds.x * 0.3f), std::floor(ds.y * 0.4f)));
        ImGui::BeginGroup();
        ImGui::Text("%s", scenePath_.c_str());
        if (picture)
            ImGui::Text("Steady state (all time), %llu passes: a preview while the time-resolved film is prepared",
                        static_cast<unsigned long long>(previewFetched_));
        ImGui::Text("preparing the film: %d x %d px, %d bins (%s) ...", w, h, time_.bins,
                    humanBytes(filmBytes(w, h, time_.bins)).c_str());
        ImGui::TextDisabled("the time frames, the streak and the controls come as soon as it is allocated (%.1f s)",
                            nowSec() - opt_.launchedAt);
        ImGui::EndGroup();
        if (picture) {  // the preview, fitted to the rest of the window
            const ImVec2 c0 = ImGui::GetCursorScreenPos();
            const ImVec2 avail = ImGui::GetContentRegionAvail();
            const ImagePlacement pl = placeImage(ImageViewport{}, avail.x, avail.y, w, h);
            const ImVec2 p0(c0.x + pl.x, c0.y + pl.y);
            ImGui::GetWindowDrawList()->AddImage(texId(image_.texture()), p0,
                                                 ImVec2(p0.x + w * pl.zoom, p0.y + h * pl.zoom));
        }
    }
    ImGui::End();
}

// Layout rule: what render progress changes (pass statistics, the render finishing, messages)
// never changes the number of rows above a control, so a click aimed during the render lands on
// the same control after it. Rows that come and go are reserved (shown disabled or as "-"), and
// messages of any length go to the fixed-size, wrapped messages box below the controls (drawUi).
void Viewer::drawControls() {
    const TimeBins& tb = time_;
    ImGui::PushItemWidth(-ImGui::GetFontSize() * 11.0f);  // room for the labels
    ImGui::TextWrapped("%s", scenePath_.c_str());
    ImGui::TextWrapped("%d x %d px, %d bins, %.3f - %.3f ns", scene_.camera.width, scene_.camera.height, tb.bins,
                       tb.startOpl / kC_m_per_ns, tb.endOpl() / kC_m_per_ns);
    drawTimeSection();

    if (section("View", ImGuiTreeNodeFlags_DefaultOpen)) {
        int show = st_.showSteady ? 1 : 0;
        ImGui::RadioButton("Time frame", &show, 0);
        track("Time frame");
        ImGui::SameLine();
        ImGui::RadioButton("Steady state##view", &show, 1);  // unique ID: the Export section has one too
        track("Steady state##view");
        if (st_.showSteady != (show == 1)) st_.steadyUntilTime = false;  // the user's choice from now on
        st_.showSteady = show == 1;
        bool unwarp = st_.axis == TimeAxis::Unwarped;
        if (ImGui::Checkbox("Camera unwarping", &unwarp)) st_.axis = unwarp ? TimeAxis::Unwarped : TimeAxis::Real;
        track("Camera unwarping");
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("Time since emission without the path to the camera");
        ImGui::SameLine();  // one row for both (the Export buttons stay in view in an 800-pixel window)
        bool cont = st_.mode == EmissionMode::Continuous;
        if (ImGui::Checkbox("Continuous emission", &cont)) {
            st_.mode = cont ? EmissionMode::Continuous : EmissionMode::Delta;
            // A running sum and a pulse response differ by orders of magnitude: fit the exposure again.
            st_.autoFrame = true;
        }
        track("Continuous emission");
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip("Light on from the pulse instant (running sum of the delta response)");
        drawTimeResponse();
        drawCounting();
    }

    if (section("Display", ImGuiTreeNodeFlags_DefaultOpen)) {
        float& ev = st_.showSteady ? st_.evSteady : st_.evFrame;
        if (ImGui::SliderFloat("exposure (EV)", &ev, -40.0f, 40.0f, "%.2f"))
            (st_.showSteady ? st_.autoSteady : st_.autoFrame) = false;  // the user's exposure from now on
        track("exposure (EV)");
        if (ImGui::Button("Auto exposure")) {
            (st_.showSteady ? st_.autoSteady : st_.autoFrame) = true;
            frameKey_ = FetchKey{};  // fetch again: the exposure is computed from a fresh frame
        }
        track("Auto exposure");
        ImGui::SameLine();
        ImGui::Checkbox("sRGB", &st_.display.srgb);
        track("sRGB");
        ImGui::SameLine();
        ImGui::Checkbox("False colour", &st_.display.falseColor);
        track("False colour");
        if (st_.display.falseColor) {
            ImGui::SliderFloat("decades", &st_.display.decades, 1.0f, 12.0f, "%.1f");
            track("decades");
            hint(
                "log10 luminance over the decades below the white point: blue (dim) to red; "
                "white = clipped, black = no energy");
        }
    }
    drawBackprojectionSection();
    drawProgressSection();
    drawSettingsSection();
    drawExportSection();
    ImGui::PopItemWidth();
}

void Viewer::drawTimeSection() {
    if (!section("Time", ImGuiTreeNodeFlags_DefaultOpen)) return;
    const TimeBins& tb = time_;
    int bin = st_.bin;
    if (ImGui::SliderInt("bin", &bin, 0, tb.bins - 1)) setBin(bin);
    track("bin");
    const double opl = binCentreOpl(st_.bin);
    ImGui::Text("t = %.4f ns  |  %.4f m of OPL", opl / kC_m_per_ns, opl);
    ImGui::TextDisabled("(bin centre, %s)", axisName(st_.axis));
    ImGui::TextDisabled("bin width %.4f ns = %.4f m", tb.binWidth / kC_m_per_ns, tb.binWidth);
    if (ImGui::ArrowButton("##prev", ImGuiDir_Left)) setBin(st_.bin - 1);
    track("##prev");
    ImGui::SameLine();
    // "###": one ID whatever the label says (and not the Progress section's "Pause").
    const char* play = st_.playing ? "Pause###playback" : "Play###playback";
    if (ImGui::Button(play, ImVec2(60, 0))) st_.playing = !st_.playing;
    track(play);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("keys: Left/Right one bin, Home/End, Space play/pause");
    ImGui::SameLine();
    if (ImGui::ArrowButton("##next", ImGuiDir_Right)) setBin(st_.bin + 1);
    track("##next");
    ImGui::SameLine();
    ImGui::Checkbox("loop", &st_.loop);
    track("loop");
    ImGui::SliderFloat("speed (bins/s)", &st_.speed, 0.5f, 120.0f, "%.1f", ImGuiSliderFlags_Logarithmic);
    track("speed (bins/s)");
}

namespace {

// The film's bookkeeping, on the displayed axis: the energy that missed the time range, split into
// before and after it (they call for opposite fixes of film.start), and the estimates the film
// dropped (non-finite ones, pixel sums that would overflow its floats), a warning when any.
// Always two one-line rows (the details are in tooltips), so nothing below them ever moves and
// the Export buttons stay in view in an 800-pixel window.
void drawFilmStats(const FilmStats& fs, TimeAxis shownAxis) {
    const long long rejected = static_cast<long long>(fs.rejectedSamples.load());
    const long long overflowed = static_cast<long long>(fs.overflowedPixels.load());
    if (overflowed > 0 || rejected > 0) {
        ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.2f, 1.0f), "warning: %lld rejected, %lld overflowed (hover)", rejected,
                           overflowed);
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip(
                "%lld non-finite (NaN/Inf) estimates were rejected (they are not in the film).\n"
                "%lld pixel sums would have exceeded the film's float images (3.4e38) and were dropped\n"
                "from their passes (those pixels are too dark): lower the lights' power (the\n"
                "film scales with it).",
                rejected, overflowed);
    } else {
        ImGui::TextDisabled("rejected samples 0, overflowed pixels 0");
    }
    const int a = static_cast<int>(shownAxis);
    const double in = fs.inside[a].load(), out = fs.outside[a].load(), before = fs.before[a].load();
    const double total = in + out;
    if (total > 0) {
        const double beforePct = 100.0 * before / total, afterPct = 100.0 * std::max(0.0, out - before) / total;
        ImGui::Text("outside the film %.2g %% (%.2g before, %.2g after)", 100.0 * out / total, beforePct, afterPct);
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip(
                "Of the energy that reached the camera, on the %s axis:\n%.3g %% arrived before the "
                "film's start, %.3g %% after its end.",
                shownAxis == TimeAxis::Real ? "real-time" : "camera-unwarped", beforePct, afterPct);
    } else {
        ImGui::TextDisabled("outside the film -");
    }
}

}  // namespace

void Viewer::drawProgressSection() {
    if (!section("Progress", ImGuiTreeNodeFlags_DefaultOpen)) return;
    const RenderSettings& s = driver().settings();
    const uint64_t done = driver().completedPasses();
    const PassStats last = driver().lastPass();
    const bool running = driver().running();
    const bool failed = !running && driver().failure();
    const char* state = failed              ? "stopped by an error, see below"
                        : !running          ? "finished"
                        : driver().paused() ? "paused"
                                            : "rendering";
    if (s.passes > 0)
        ImGui::Text("pass %llu / %lld  (%s)", static_cast<unsigned long long>(done), static_cast<long long>(s.passes),
                    state);
    else
        ImGui::Text("pass %llu  (%s)", static_cast<unsigned long long>(done), state);
    ImGui::SameLine();  // on the pass row: the Export buttons stay in view in an 800-pixel window
    drawNoise();
    if (s.passes > 0)
        ImGui::ProgressBar(static_cast<float>(done) / static_cast<float>(s.passes), ImVec2(-1, 0));
    else
        ImGui::ProgressBar(0.0f, ImVec2(-1, 0), "no pass limit");
    // Always these rows, with "-" until the first pass is in.
    if (s.method == Method::PathTracer) {
        ImGui::Text("path tracer: %d sample%s per pixel per pass", s.samplesPerPixel,
                    s.samplesPerPixel == 1 ? "" : "s");
        if (done > 0)
            ImGui::Text("camera paths per pass %lld  (%lld connections)",
                        static_cast<long long>(last.paths.cameraPaths), static_cast<long long>(last.paths.shadowRays));
        else
            ImGui::TextDisabled("camera paths per pass -");
    } else if (s.method == Method::Preview) {
        ImGui::Text("geometry preview (steady image only)");
        ImGui::TextDisabled(" ");
    } else if (done > 0) {
        // During the warm-up (render_settings.h) the last pass traced fewer photons: say so.
        const bool warmup = last.pass <= static_cast<uint64_t>(s.warmupPasses);
        ImGui::Text("kernel radius %.4g m (surface %.4g m)", last.beamRadius, last.surfaceRadius);
        char photons[64];
        if (warmup)
            std::snprintf(photons, sizeof photons, "%lld photons, warm-up %llu/%d",
                          static_cast<long long>(last.photons), static_cast<unsigned long long>(last.pass),
                          s.warmupPasses);
        else
            std::snprintf(photons, sizeof photons, "%lld photons", static_cast<long long>(last.photons));
        // What the volume estimator gathers from: beams, photon points (point2d/point3d) or both.
        if (last.points > 0 && last.beams == 0)
            ImGui::Text("points per pass %lld  (%s)", static_cast<long long>(last.points), photons);
        else if (last.points > 0)
            ImGui::Text("beams %lld, points %lld per pass  (%s)", static_cast<long long>(last.beams),
                        static_cast<long long>(last.points), photons);
        else
            ImGui::Text("beams per pass %lld  (%s)", static_cast<long long>(last.beams), photons);
        if (warmup && ImGui::IsItemHovered())
            ImGui::SetTooltip(
                "the first %d passes trace photons/2^%d ... photons/2 for a first picture sooner\n"
                "(Render settings: warm-up passes; --warmup)",
                s.warmupPasses, s.warmupPasses);
    } else {
        ImGui::TextDisabled(failed ? "kernel radius -" : "kernel radius -  (first pass in progress...)");
        ImGui::TextDisabled("stored per pass -");
    }
    if (done > 0) {
        ImGui::Text("time per pass %.3f s", last.passSec);
        ImGui::TextDisabled("trace %.2f s, build %.2f s, camera %.2f s", last.photonSec, last.buildSec, last.cameraSec);
        // How fast the picture came (issue 15): the first fetched image with light in it.
        if (firstLightSec_ >= 0.0)
            ImGui::Text("total time %.2f s  (first light after %.2f s)", last.elapsedSec, firstLightSec_);
        else
            ImGui::Text("total time %.2f s", last.elapsedSec);
    } else {
        ImGui::TextDisabled("time per pass -");
        ImGui::TextDisabled("trace -, build -, camera -");
        ImGui::TextDisabled("total time -");
    }
    drawFilmStats(driver().film().stats, st_.axis);
    // Pause/Resume stays (disabled) when the render has finished, so the rows below keep their place.
    const char* pause = running && driver().paused() ? "Resume###render" : "Pause###render";
    ImGui::BeginDisabled(!running);
    if (ImGui::Button(pause, ImVec2(80, 0))) {
        if (driver().paused())
            driver().resume();
        else
            driver().pause();
    }
    ImGui::EndDisabled();
    track(pause);
    if (running && ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
        ImGui::SetTooltip("takes effect between passes");
    ImGui::SameLine();
    if (ImGui::Button("Restart", ImVec2(80, 0))) restart(driver().settings(), "accumulation restarted");
    track("Restart");
    ImGui::SameLine();
    // Any progressive method (the preview's one pass is its answer: nothing to resume).
    ImGui::BeginDisabled(session_.checkpointStage() != ViewerSession::CheckpointStage::Idle ||
                         driver().settings().method == Method::Preview);
    if (ImGui::Button("Save checkpoint")) session_.requestCheckpoint(st_.outDir);
    ImGui::EndDisabled();
    track("Save checkpoint");
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
        ImGui::SetTooltip(
            "the film and its passes to <export folder>/checkpoint.tpbck, between passes;\n"
            "go on later with tpb render --resume FOLDER or tpb view --resume FOLDER");
}

void Viewer::drawNoise() {
    // One row, always: how far the picture shown is from converged, as far as its noise tells.
    const double e = noise_.relativeError();
    if (e < 0.0) {
        ImGui::TextDisabled("noise -");
    } else {
        // Colour: red above 10 %, yellow above 2 %, green below (a clean picture to the eye).
        const ImVec4 c = e > 0.10   ? ImVec4(1.0f, 0.45f, 0.4f, 1.0f)
                         : e > 0.02 ? ImVec4(1.0f, 0.85f, 0.3f, 1.0f)
                                    : ImVec4(0.5f, 0.9f, 0.5f, 1.0f);
        ImGui::TextColored(c, "noise %.*f %%", e < 0.1 ? 1 : 0, 100.0 * e);
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "%d batches of passes so far (known from 2 on).\n"
            "The picture's relative standard error: RMS over the pixels of the standard error of\n"
            "each pixel's value, over the mean pixel value (luminance). Estimated from the spread of\n"
            "the batches of passes this picture was read at (restarts on a change of time, axis,\n"
            "emission or view). It falls as 1/sqrt(passes); the kernels' blur (bias) is not in it.",
            noise_.batches());
}

// Pulse shape and sensor response (film/time_response.h): a convolution along time applied when
// the film is read, so a change shows at once, with no re-render. Widths in ns.
const char* Viewer::emissionLabel() const {
    if (st_.mode == EmissionMode::Continuous) return "continuous emission";
    return st_.response.pulse == PulseShape::Delta ? "delta pulse" : "pulse response";
}

std::string Viewer::responseNote() const {
    return st_.response.identity() ? std::string() : " (" + describe(st_.response) + ")";
}

void Viewer::drawTimeResponse() {
    TimeResponse r = st_.response;
    const double defaultNs = 4.0 * time_.binWidth / kC_m_per_ns;  // four bins, when a shape is first picked
    if (st_.pulseNs <= 0.0) st_.pulseNs = defaultNs;
    if (st_.sensorNs <= 0.0) st_.sensorNs = defaultNs;
    // One row: [pulse][width] [sensor][width], the widths (ns) only for a shape that has one.
    const char* pulses[] = {"delta pulse", "gauss pulse", "square pulse"};
    int p = static_cast<int>(r.pulse);
    ImGui::SetNextItemWidth(104);
    if (ImGui::Combo("##pulse", &p, pulses, 3)) r.pulse = static_cast<PulseShape>(p);
    track("pulse");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "the source's pulse: gaussian (FWHM in ns, centred on the emission instant) or square (on\n"
            "for WIDTH ns from the emission instant); the delta response convolved along time, no re-render");
    if (r.pulse != PulseShape::Delta) {
        ImGui::SameLine(0, 2);
        ImGui::SetNextItemWidth(56);
        ImGui::InputDouble("##pulsens", &st_.pulseNs, 0.0, 0.0, "%.3g");
        track("pulse ns");
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("pulse width, ns (gaussian: FWHM)");
        st_.pulseNs = std::clamp(st_.pulseNs, 1e-6, 1e6);
    }
    const char* sensors[] = {"ideal sensor", "gauss jitter", "exp decay"};
    int q = static_cast<int>(r.sensor);
    ImGui::SameLine();
    ImGui::SetNextItemWidth(104);
    if (ImGui::Combo("##sensor", &q, sensors, 3)) r.sensor = static_cast<SensorShape>(q);
    track("sensor");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "the detector's time response: gaussian timing jitter (FWHM in ns) or exponential decay (TAU in ns)");
    if (r.sensor != SensorShape::Ideal) {
        ImGui::SameLine(0, 2);
        ImGui::SetNextItemWidth(56);
        ImGui::InputDouble("##sensorns", &st_.sensorNs, 0.0, 0.0, "%.3g");
        track("sensor ns");
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("sensor width, ns (gaussian: FWHM; exponential: decay time)");
        st_.sensorNs = std::clamp(st_.sensorNs, 1e-6, 1e6);
    }
    r.pulseWidth = r.pulse == PulseShape::Delta ? 0.0 : st_.pulseNs * kC_m_per_ns;
    r.sensorWidth = r.sensor == SensorShape::Ideal ? 0.0 : st_.sensorNs * kC_m_per_ns;
    // A span wider than kMaxResponseBins bins is refused (time_response.h; binKernel would throw):
    // keep the last response and say why.
    if (const double span = responseSpanBins(r, time_.binWidth); !(span <= kMaxResponseBins)) {
        char b[200];
        std::snprintf(b, sizeof b,
                      "pulse/sensor not applied: it spans %.3g bins of this film, the limit is 2^20; "
                      "narrow it (or render with fewer --bins)",
                      span);
        session_.setStatus(b);
        return;
    }
    if (!(r == st_.response)) {
        st_.response = r;
        st_.autoFrame = true;  // a blurred pulse is dimmer at its peak: fit the exposure again
    }
}

// Photon counts (film/photon_counting.h), applied when the film is read like the pulse: [counts]
// after the pulse and sensor, then (when on) a row of the budget, dark and ambient rates, cycles,
// pile-up, Coates and the seed. The efficiency and afterpulses come from --counts.
void Viewer::drawCounting() {
    PhotonCounting m = st_.response.counting;
    ImGui::SameLine();  // on the pulse/sensor row if it fits; its parameters on a row of their own
    const float boxWidth =
        ImGui::GetFrameHeight() + ImGui::GetStyle().ItemInnerSpacing.x + ImGui::CalcTextSize("counts").x;
    if (ImGui::GetContentRegionAvail().x < boxWidth) ImGui::NewLine();
    ImGui::Checkbox("counts", &m.enabled);
    track("counts");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "the film read as SPAD photon counts per bin (grey): Poisson, or first-photon TCSPC with pile-up;\n"
            "no re-render; off: the noise-free film");
    if (m.enabled) {
        bool first = true;
        const auto number = [&](const char* id, double& v, double lo, double hi, const char* tip) {
            if (!first) ImGui::SameLine(0, 2);
            first = false;
            ImGui::SetNextItemWidth(60);
            ImGui::InputDouble(id, &v, 0.0, 0.0, "%.3g");
            track(id);
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", tip);
            v = std::clamp(v, lo, hi);
        };
        number("##photons", m.photons, 1e-6, 1e15, "signal photons a mean pixel expects over the time axis");
        number("##dark", m.darkHz, 0.0, 1e12, "dark count rate, Hz");
        number("##ambient", m.ambientHz, 0.0, 1e12, "detected ambient photon rate, Hz");
        number("##cycles", m.cycles, 1.0, 1e15, "laser cycles in the acquisition");
        m.cycles = std::floor(m.cycles);
        ImGui::SameLine();
        ImGui::Checkbox("pile-up", &m.pileup);
        track("pile-up");
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("first photon per cycle (TCSPC with dead time)");
        if (m.pileup) {
            ImGui::SameLine();
            ImGui::Checkbox("Coates", &m.coates);
            track("Coates");
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("the piled-up histogram corrected (Coates 1968)");
        } else {
            m.coates = false;
        }
        int seed = static_cast<int>(std::min<uint64_t>(m.seed, INT_MAX));
        ImGui::SameLine();
        ImGui::SetNextItemWidth(70);
        if (ImGui::InputInt("##seed", &seed)) m.seed = static_cast<uint64_t>(std::max(seed, 0));
        track("seed");
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("seed of the counts (the same seed, the same counts)");
    }
    if (!(m == st_.response.counting)) {
        st_.response.counting = m;
        st_.autoFrame = true;  // counts and radiance differ by orders of magnitude: fit the exposure again
    }
}

// The photon-beams estimators (estimators/estimator_names.h) and the progressive time kernel: a
// change restarts the accumulation (an average over passes of different estimators means nothing)
// and says so. Returns true when it restarted.
bool Viewer::drawEstimatorSettings() {
    const RenderSettings& cur = driver().settings();
    const std::vector<std::string>& names = volumeEstimatorNames();
    int e = 0;
    for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == cur.volumeEstimator) e = static_cast<int>(i);
    std::vector<const char*> labels;
    for (const std::string& n : names) labels.push_back(n.c_str());
    SettingsOverrides o;
    std::string what;
    if (ImGui::Combo("volume estimator", &e, labels.data(), static_cast<int>(labels.size())) &&
        names[e] != cur.volumeEstimator) {
        o.volumeEstimator = names[e];
        what = "estimator " + names[e];
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "beam1d / beam2d: beams x camera ray with a 1D / 2D kernel; point2d / point3d: photon points\n"
            "with a 2D kernel across the ray / a 3D kernel (docs/user/estimators.md)");
    track("volume estimator");
    const char* kernels[] = {"none", "box"};
    int k = cur.timeKernel.kind == TimeKernelKind::Box ? 1 : 0;
    if (ImGui::Combo("time kernel", &k, kernels, 2) && (k == 1) != (cur.timeKernel.kind == TimeKernelKind::Box)) {
        o.timeKernel = k == 1 ? TimeKernelSettings{TimeKernelKind::Box, edit_.timeKernel.width} : TimeKernelSettings{};
        what = std::string("time kernel ") + kernels[k];
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "smooths every estimate along time with a box whose width shrinks with the radius\n"
            "(docs/theory/derivations.md)");
    track("time kernel");
    if (cur.timeKernel.kind == TimeKernelKind::Box) {
        ImGui::InputDouble("time kernel width (m)", &edit_.timeKernel.width, 0.0, 0.0, "%.6g");
        if (ImGui::IsItemDeactivatedAfterEdit() && edit_.timeKernel.width != cur.timeKernel.width) {
            o.timeKernel = TimeKernelSettings{TimeKernelKind::Box, edit_.timeKernel.width};
            what = "time kernel width " + shortNumber(edit_.timeKernel.width) + " m";
        }
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("full width of pass 1's kernel in m of OPL; 0 = from the scene");
        track("time kernel width (m)");
    }
    if (what.empty()) return false;
    RenderSettings s = cur;
    s.apply(o);
    try {
        const double diag = scene_.bounds.diagonal() > 0.0 ? scene_.bounds.diagonal() : 1.0;
        for (const std::string& w : s.validate({nullptr, &o, diag})) std::fprintf(stderr, "warning: %s\n", w.c_str());
        const TimeBins& t = driver().film().time();
        s.validateAgainstFilm(t.binWidth * t.bins, {nullptr, &o, diag});
    } catch (const UserError& err) {
        session_.setStatus(std::string("invalid setting: ") + err.what() + ": not applied");
        edit_.timeKernel = cur.timeKernel;
        return false;
    }
    edit_.volumeEstimator = s.volumeEstimator;
    edit_.timeKernel = s.timeKernel;
    askRestart(s, what);
    return true;
}

void Viewer::drawSettingsSection() {
    if (!section("Render settings")) return;
    hint("a change (Enter or leaving the field) restarts the accumulation, asking first once passes are in");
    // The integrator (render_settings.h Method): any of them runs in the same Driver, so the
    // scrubbing, toggles and exports work the same for each.
    const Method methods[] = {Method::Beams, Method::PathTracer, Method::Preview};
    const char* methodLabels[] = {"photon beams", "path tracer", "geometry preview"};
    int m = static_cast<int>(driver().settings().method);
    if (ImGui::Combo("method", &m, methodLabels, 3) && methods[m] != driver().settings().method) {
        RenderSettings s = driver().settings();
        s.method = methods[m];
        edit_.method = s.method;
        askRestart(s, std::string("method ") + methodName(s.method));
        return;
    }
    track("method");
    if (driver().settings().method == Method::Beams && drawEstimatorSettings()) return;
    bool apply = false;
    const int64_t step = 1000, stepFast = 10000;
    ImGui::InputScalar("photons / pass", ImGuiDataType_S64, &edit_.photonsPerPass, &step, &stepFast);
    apply |= ImGui::IsItemDeactivatedAfterEdit();
    track("photons / pass");
    int warm = edit_.warmupPasses;
    ImGui::InputInt("warm-up passes", &warm, 1, 1);
    edit_.warmupPasses = std::clamp(warm, 0, kMaxWarmupPasses);
    apply |= ImGui::IsItemDeactivatedAfterEdit();
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("the first W passes trace photons/2^W ... photons/2 (as --warmup); 0 = none");
    track("warm-up passes");
    ImGui::InputDouble("alpha", &edit_.alpha, 0.05, 0.1, "%.3f");
    apply |= ImGui::IsItemDeactivatedAfterEdit();
    track("alpha");
    ImGui::InputDouble("initial radius (m)", &edit_.beamRadius0, 0.0, 0.0, "%.6g");
    apply |= ImGui::IsItemDeactivatedAfterEdit();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("beam kernel radius of pass 1 (as --radius)");
    track("initial radius (m)");
    // From the photon density of a pilot pass (render/auto_radius.h, as --auto-radius): one photon
    // pass on this thread, tens of milliseconds.
    if (ImGui::Button("auto radius")) {
        const RadiusPilot rp = pilotRadius(scene_, edit_);
        if (rp.measured) {
            edit_.beamRadius0 = std::min(rp.radius, kMaxRadiusFraction * scene_.bounds.diagonal());
            apply = true;
        }
        session_.setStatus("auto radius: " + rp.why);
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "the initial radius from a pilot pass's photon density: a camera ray through the\n"
            "medium gathers about %.0f beams (%.0f photon points) per pass (--auto-radius)",
            kAutoBeamsPerRay, kAutoPointsPerRay);
    track("auto radius");
    const int64_t one = 1, ten = 10;
    ImGui::InputScalar("pass limit (0: none)", ImGuiDataType_S64, &edit_.passes, &one, &ten);
    apply |= ImGui::IsItemDeactivatedAfterEdit();
    track("pass limit (0: none)");
    if (!apply) return;
    const RenderSettings& cur = driver().settings();
    if (edit_.photonsPerPass == cur.photonsPerPass && edit_.warmupPasses == cur.warmupPasses &&
        edit_.alpha == cur.alpha && edit_.beamRadius0 == cur.beamRadius0 && edit_.passes == cur.passes)
        return;
    // The edited fields as overrides, checked by the one validate() (render_settings.h); everything
    // else (seed, threads, surface radius...) as before.
    SettingsOverrides o;
    o.photons = edit_.photonsPerPass;
    o.warmup = edit_.warmupPasses;
    o.alpha = edit_.alpha;
    o.radius = edit_.beamRadius0;
    o.passes = edit_.passes;
    RenderSettings s = cur;
    s.apply(o);
    std::vector<std::string> warnings;
    try {
        const double diag = scene_.bounds.diagonal() > 0.0 ? scene_.bounds.diagonal() : 1.0;
        warnings = s.validate({nullptr, &o, diag});
    } catch (const UserError& e) {
        session_.setStatus(std::string("invalid setting: ") + e.what() + ": not applied");
        edit_ = cur;
        return;
    }
    for (const std::string& w : warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    askRestart(s, "settings changed");
}

void Viewer::askRestart(const RenderSettings& s, const std::string& what) {
    // Nothing to lose yet: restart at once. Otherwise ask (drawPopups): the passes are discarded.
    if (driver().completedPasses() == 0) {
        restart(s, what + ": accumulation restarted");
        return;
    }
    pendingRestart_ = s;
    pendingWhat_ = what;
    openPopup_ = kRestartPopup;
}

void Viewer::requestQuit() {
    // A keyboard quit (Esc, Q): at once, unless an export would be cut short.
    if (session_.exportJob().busy()) {
        openPopup_ = kQuitPopup;
        std::printf("quit: asked first, an export is running\n");
        std::fflush(stdout);
        return;
    }
    std::printf("quit: by the keyboard\n");
    std::fflush(stdout);
    glfwSetWindowShouldClose(window_, GLFW_TRUE);
}

void Viewer::drawPopups() {
    if (openPopup_) {
        ImGui::OpenPopup(openPopup_);
        openPopup_ = nullptr;
    }
    if (ImGui::BeginPopupModal(kRestartPopup, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
        section_ = kRestartPopup;
        const unsigned long long done = driver().completedPasses();
        ImGui::Text("%s: this restarts the accumulation.", pendingWhat_.c_str());
        ImGui::Text("The %llu pass%s rendered so far will be discarded.", done, done == 1 ? "" : "es");
        if (ImGui::Button("Restart##confirm")) {
            if (pendingRestart_) restart(*pendingRestart_, pendingWhat_ + ": accumulation restarted");
            pendingRestart_.reset();
            ImGui::CloseCurrentPopup();
        }
        track("Restart##confirm");
        ImGui::SameLine();
        if (ImGui::Button("Keep the accumulation") || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape))) {
            pendingRestart_.reset();
            edit_ = driver().settings();
            session_.setStatus(pendingWhat_ + ": not applied, the accumulation is kept");
            ImGui::CloseCurrentPopup();
        }
        track("Keep the accumulation");
        ImGui::EndPopup();
    }
    if (ImGui::BeginPopupModal(kQuitPopup, nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
        section_ = kQuitPopup;
        ImGui::Text("An export is running (%s).", session_.exportJob().progressLabel().c_str());
        if (ImGui::Button("Quit after the export")) {  // finishBeforeClosing finishes it
            ImGui::CloseCurrentPopup();
            glfwSetWindowShouldClose(window_, GLFW_TRUE);
        }
        track("Quit after the export");
        ImGui::SameLine();
        if (ImGui::Button("Cancel it and quit")) {  // a cancelled MP4 or volume leaves no file
            session_.exportJob().cancel();
            ImGui::CloseCurrentPopup();
            glfwSetWindowShouldClose(window_, GLFW_TRUE);
        }
        track("Cancel it and quit");
        ImGui::SameLine();
        if (ImGui::Button("Keep exporting") || !session_.exportJob().busy()) ImGui::CloseCurrentPopup();
        track("Keep exporting");
        ImGui::EndPopup();
    }
    section_ = "";
}

void Viewer::drawExportSection() {
    if (!section("Export", ImGuiTreeNodeFlags_DefaultOpen)) return;
    ImGui::InputText("folder", &st_.outDir);
    // The axis and emission of the exports are the ones shown (the image's title says which; the
    // file names carry them): a tooltip, so that every Export button stays in view in an 800-pixel
    // window with the volume/MP4/contact sheet row.
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("exports are in %s time, %s%s (as shown)", st_.axis == TimeAxis::Real ? "real" : "unwarped",
                          emissionLabel(), responseNote().c_str());
    track("folder");
    ExportRequest r;
    r.dir = st_.outDir.empty() ? "." : st_.outDir;
    r.bin = st_.bin;
    r.row = st_.selY;
    r.x = st_.selX;
    r.y = st_.selY;
    r.axis = st_.axis;
    r.mode = st_.mode;
    r.tone = st_.display;  // the MP4 and the contact sheet as the screen shows the frames
    r.tone.exposureEv = st_.evFrame;
    r.sheetFrames = st_.sheetFrames;
    r.scenePath = scenePath_;
    r.response = st_.response;
    const bool busy = session_.exportJob().busy();
    ImGui::BeginDisabled(busy);
    bool go = false;
    if (ImGui::Button("Current frame")) go = r.frame = true;
    track("Current frame");
    ImGui::SameLine();
    if (ImGui::Button("All frames")) go = r.allFrames = true;
    track("All frames");
    ImGui::SameLine();
    if (ImGui::Button("Steady state##export")) go = r.steady = true;  // unique ID: the View section has one too
    track("Steady state##export");
    if (ImGui::Button("Streak (selected row)")) go = r.streak = true;
    track("Streak (selected row)");
    ImGui::SameLine();
    if (ImGui::Button("Pixel profile (CSV)")) go = r.profile = true;
    track("Pixel profile (CSV)");
    if (ImGui::Button("Volume (.npy)")) go = r.volume = true;
    track("Volume (.npy)");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "transient.npy (H x W x bins x 3 float32) + steady/before/after.npy and transient.json\n"
            "(time axis, render) for numpy.load, in volume_<axis>_<emission>/");
    ImGui::SameLine();
    if (ImGui::Button("MP4")) go = r.mp4 = true;
    track("MP4");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("every frame at 24 fps with this exposure and colour map (ffmpeg)");
    ImGui::SameLine();
    if (ImGui::Button("Contact sheet")) go = r.contactSheet = true;
    track("Contact sheet");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("%d frames over the lit part of the time axis in a grid, labelled with their time (PNG)",
                          st_.sheetFrames);
    ImGui::EndDisabled();
    if (ImGui::Button("Window screenshot (F12)")) snapRequested_ = true;
    track("Window screenshot (F12)");
    if (go) session_.startExport(r);  // its progress bar and Cancel button are in the messages, below
}

void Viewer::drawMessages() {
    // The export in progress, the render's error, the last action's status, the last export.
    if (session_.exportJob().busy()) {
        ImGui::ProgressBar(session_.exportJob().progress(), ImVec2(-70, 0),
                           session_.exportJob().progressLabel().c_str());
        ImGui::SameLine();
        if (ImGui::Button("Cancel")) session_.exportJob().cancel();
        track("Cancel");
    }
    if (!driver().running() && driver().failure()) {
        // The render thread caught it (core/render/driver.h): the finished passes stay on screen.
        wrappedColored(ImVec4(1.0f, 0.4f, 0.35f, 1.0f), "error: " + driver().failureMessage());
        track("error");
    }
    if (!session_.status().empty()) {
        wrappedColored(ImVec4(1.0f, 0.85f, 0.3f, 1.0f), session_.status());
        track("status");
    }
    if (!session_.exportError().empty() && !session_.exportJob().busy()) {
        wrappedColored(ImVec4(1.0f, 0.4f, 0.4f, 1.0f), session_.exportError());
        track("export error");
    }
    for (const std::string& w : session_.exportLog()) ImGui::TextWrapped("wrote %s", w.c_str());
}

void Viewer::drawImagePanel() {
    const int w = scene_.camera.width, h = scene_.camera.height;
    // The title row: what is shown, and the zoom buttons at its right end.
    const float buttonsW =
        ImGui::CalcTextSize("Fit 1:1").x + 4.0f * ImGui::GetStyle().FramePadding.x + ImGui::GetStyle().ItemSpacing.x;
    ImGui::PushTextWrapPos(ImGui::GetContentRegionMax().x - buttonsW - ImGui::GetStyle().ItemSpacing.x);
    if (st_.showSteady) {
        const bool fromPreview = session_.preview() && frameKey_.passes > driver().completedPasses();
        ImGui::TextWrapped("Steady state (all time), %llu passes%s%s",
                           static_cast<unsigned long long>(frameKey_.passes),
                           fromPreview ? " (the preview's, until the film catches up)" : "",
                           st_.steadyUntilTime ? "  -  pick a time (slider, Left/Right, Play) to see the pulse" : "");
    } else {
        const double opl = binCentreOpl(st_.bin);
        ImGui::TextWrapped("bin %d: t = %.4f ns (%.4f m), %s, %s%s", st_.bin, opl / kC_m_per_ns, opl,
                           axisName(st_.axis), emissionLabel(), responseNote().c_str());
    }
    ImGui::PopTextWrapPos();
    ImGui::SameLine(ImGui::GetContentRegionMax().x - buttonsW);
    if (ImGui::SmallButton("Fit")) view_ = ImageViewport{};
    track("Fit");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("fit the image to the panel (key F); wheel: zoom, right-drag: pan");
    ImGui::SameLine();
    if (ImGui::SmallButton("1:1")) view_ = oneToOne(w, h, ImGui::GetIO().DisplayFramebufferScale.x);
    track("1:1");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("one screen pixel per film pixel (key 1)");

    // The canvas: the rest of the panel. The image is placed by the viewport (fitted unless the
    // user zoomed or panned) and clipped to the canvas.
    ImVec2 avail = ImGui::GetContentRegionAvail();
    // False colour: a colour bar under the image says which luminance each colour is.
    const float barH = st_.display.falseColor ? 2.0f * ImGui::GetTextLineHeightWithSpacing() + 6.0f : 0.0f;
    avail.y = std::max(avail.y - barH, 1.0f);
    const ImVec2 c0 = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton(
        "##canvas", ImVec2(std::max(avail.x, 1.0f), std::max(avail.y, 1.0f)),
        ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight | ImGuiButtonFlags_MouseButtonMiddle);
    const bool hovered = ImGui::IsItemHovered();
    const ImagePlacement pl = placeImage(view_, avail.x, avail.y, w, h);
    const ImVec2 p0(c0.x + pl.x, c0.y + pl.y);
    const float zoom = pl.zoom;
    const ImVec2 size(w * zoom, h * zoom);
    ImGuiIO& io = ImGui::GetIO();
    if (hovered && io.MouseWheel != 0.0f)  // zoom about the pointer
        view_ = zoomAbout(pl, std::pow(1.25f, io.MouseWheel), io.MousePos.x - c0.x, io.MousePos.y - c0.y);
    if (ImGui::IsItemActive() &&
        (ImGui::IsMouseDragging(ImGuiMouseButton_Right) || ImGui::IsMouseDragging(ImGuiMouseButton_Middle))) {
        view_ = panBy(pl, io.MouseDelta.x, io.MouseDelta.y);
    }
    ImDrawList* dl = ImGui::GetWindowDrawList();
    dl->PushClipRect(c0, ImVec2(c0.x + avail.x, c0.y + avail.y), true);
    dl->AddImage(texId(image_.texture()), p0, ImVec2(p0.x + size.x, p0.y + size.y));
    const ImVec2 scale = io.DisplayFramebufferScale;
    imageMin_ = ImVec2(p0.x * scale.x, p0.y * scale.y);
    imageSize_ = ImVec2(size.x * scale.x, size.y * scale.y);
    imageZoom_ = zoom * scale.x;
    canvasMin_ = ImVec2(c0.x * scale.x, c0.y * scale.y);
    canvasSize_ = ImVec2(avail.x * scale.x, avail.y * scale.y);

    if (hovered) {
        const ImVec2 m = io.MousePos;
        const int x = static_cast<int>(std::floor((m.x - p0.x) / zoom));
        const int y = static_cast<int>(std::floor((m.y - p0.y) / zoom));
        if (x >= 0 && y >= 0 && x < w && y < h) {
            const size_t i = (static_cast<size_t>(y) * w + x) * 3;
            if (i + 2 < frameRgb_.size())
                ImGui::SetTooltip("pixel (%d, %d)\nRGB %.4g %.4g %.4g\nclick: profile + streak row", x, y, frameRgb_[i],
                                  frameRgb_[i + 1], frameRgb_[i + 2]);
            if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
                st_.selX = x;
                st_.selY = y;
            }
        }
    }
    // Selection markers: the pixel's outline and ticks beside the image for the streak row.
    const ImU32 col = IM_COL32(255, 200, 40, 255);
    const float sx = p0.x + st_.selX * zoom, sy = p0.y + st_.selY * zoom;
    dl->AddRect(ImVec2(sx - 1, sy - 1), ImVec2(sx + zoom + 1, sy + zoom + 1), col);
    const float cy = sy + 0.5f * zoom;
    dl->AddTriangleFilled(ImVec2(p0.x - 8, cy - 4), ImVec2(p0.x - 8, cy + 4), ImVec2(p0.x - 2, cy), col);
    dl->AddTriangleFilled(ImVec2(p0.x + size.x + 8, cy - 4), ImVec2(p0.x + size.x + 8, cy + 4),
                          ImVec2(p0.x + size.x + 2, cy), col);
    dl->PopClipRect();
    colourBarTicks_.clear();
    if (st_.display.falseColor) drawColourBar(ImVec2(c0.x, c0.y + avail.y + 4.0f), avail.x);
}

void Viewer::drawColourBar(ImVec2 at, float width) {
    // The false-colour ramp as the shader maps it (toneMapPixel: the same mapping on the CPU), with
    // the film luminance of each decade: after the exposure, white is 1, so a luminance L shows as
    // 10^-k of white at L = 2^-EV 10^-k.
    DisplayParams p = st_.display;
    p.exposureEv = st_.showSteady ? st_.evSteady : st_.evFrame;
    const float decades = std::max(p.decades, 0.1f);
    const float barH = ImGui::GetTextLineHeight();
    const float labelW = ImGui::CalcTextSize("clipped").x + barH + 12.0f;
    const float x0 = at.x + labelW, x1 = at.x + std::max(width - labelW, labelW + 40.0f);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const int segments = 96;
    for (int i = 0; i < segments; ++i) {
        const float t = (i + 0.5f) / segments;
        const float lum = std::exp2(-p.exposureEv) * std::pow(10.0f, (t - 1.0f) * decades);
        const float rgb[3] = {lum, lum, lum};
        unsigned char c[3];
        toneMapPixel(rgb, p, c);
        const float xa = x0 + (x1 - x0) * i / segments, xb = x0 + (x1 - x0) * (i + 1) / segments;
        dl->AddRectFilled(ImVec2(xa, at.y), ImVec2(xb + 0.5f, at.y + barH), IM_COL32(c[0], c[1], c[2], 255));
    }
    dl->AddRectFilled(ImVec2(at.x, at.y), ImVec2(at.x + barH, at.y + barH), IM_COL32(0, 0, 0, 255));
    dl->AddText(ImVec2(at.x + barH + 4.0f, at.y), kTickColour, "none");
    dl->AddRectFilled(ImVec2(x1 + 4.0f, at.y), ImVec2(x1 + 4.0f + barH, at.y + barH), IM_COL32(255, 255, 255, 255));
    dl->AddText(ImVec2(x1 + 8.0f + barH, at.y), kTickColour, "clipped");
    const int n = static_cast<int>(std::floor(decades));
    const int every = std::max(1, static_cast<int>(std::ceil((n + 1) * 70.0f / std::max(x1 - x0, 1.0f))));
    for (int k = 0; k <= n; k += every) {  // k decades below white
        const float t = 1.0f - k / decades;
        const float x = x0 + (x1 - x0) * t;
        char label[32];
        std::snprintf(label, sizeof label, "%.2g", std::exp2(-p.exposureEv) * std::pow(10.0f, -static_cast<float>(k)));
        dl->AddLine(ImVec2(x, at.y + barH), ImVec2(x, at.y + barH + 3.0f), kTickColour);
        const float lw = ImGui::CalcTextSize(label).x;
        dl->AddText(ImVec2(std::clamp(x - 0.5f * lw, x0, x1 - lw), at.y + barH + 3.0f), kTickColour, label);
        colourBarTicks_.push_back({t, label});
    }
    if (ImGui::IsMouseHoveringRect(ImVec2(x0, at.y), ImVec2(x1, at.y + barH)))
        ImGui::SetTooltip(
            "false colour: log10 luminance (film units) over %.1f decades below the white point;\n"
            "black = no energy, white = clipped (above the white point)",
            static_cast<double>(decades));
}

namespace {

// Ticks of a vertical time axis beside [top, bottom]: at x, pointing left (side < 0, labels to the
// left) or right; value -> y by the axis' range. Labels at most every lineH pixels.
void verticalTicks(ImDrawList* dl, const std::vector<AxisTick>& ticks, double lo, double hi, float top, float bottom,
                   float x, float side) {
    for (const AxisTick& t : ticks) {
        const float y = top + static_cast<float>((t.value - lo) / (hi - lo)) * (bottom - top);
        dl->AddLine(ImVec2(x, y), ImVec2(x + side * 5.0f, y), kTickColour);
        const ImVec2 sz = ImGui::CalcTextSize(t.label.c_str());
        const float lx = side < 0 ? x - 7.0f - sz.x : x + 7.0f;
        dl->AddText(ImVec2(lx, std::clamp(y - 0.5f * sz.y, top - 0.5f * sz.y, bottom - 0.5f * sz.y)), kTickColour,
                    t.label.c_str());
    }
}

// Ticks of a horizontal time axis under [left, right] at y.
void horizontalTicks(ImDrawList* dl, const std::vector<AxisTick>& ticks, double lo, double hi, float left, float right,
                     float y) {
    for (const AxisTick& t : ticks) {
        const float x = left + static_cast<float>((t.value - lo) / (hi - lo)) * (right - left);
        dl->AddLine(ImVec2(x, y), ImVec2(x, y + 4.0f), kTickColour);
        const ImVec2 sz = ImGui::CalcTextSize(t.label.c_str());
        dl->AddText(ImVec2(std::clamp(x - 0.5f * sz.x, left, right - sz.x), y + 4.0f), kTickColour, t.label.c_str());
    }
}

}  // namespace

void Viewer::drawTimePanel() {
    const int w = scene_.camera.width, bins = time_.bins;
    // The time axis of both plots: the film's range, in ns (labelled) and in m of optical path.
    const double lo = time_.startOpl, hi = time_.endOpl();
    const double loNs = lo / kC_m_per_ns, hiNs = hi / kC_m_per_ns;
    ImGui::TextWrapped("Streak image of row %d (x across, time down: ns left, m of OPL right), %s, %s%s", st_.selY,
                       axisName(st_.axis), emissionLabel(), responseNote().c_str());
    const ImVec2 avail = ImGui::GetContentRegionAvail();
    const float lineH = ImGui::GetTextLineHeightWithSpacing();
    const float margin = ImGui::CalcTextSize("000.00").x + 10.0f;  // tick labels beside the streak
    const float plotH = std::max(60.0f, std::min(140.0f, avail.y * 0.4f));
    const float streakH = std::max(20.0f, avail.y - plotH - 3.0f * lineH - 8.0f);
    const ImVec2 size(std::max(avail.x - 2.0f * margin, 20.0f), streakH);
    ImGui::SetCursorPosX(ImGui::GetCursorPosX() + margin);
    const ImVec2 p0 = ImGui::GetCursorScreenPos();
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const int maxTicks = std::max(2, static_cast<int>(streakH / (1.2f * lineH)));
    streakTicksNs_ = niceTicks(loNs, hiNs, maxTicks);
    if (!streak_.empty()) {
        ImGui::Image(texId(streak_.texture()), size);
        const float zx = size.x / w, zy = size.y / bins;
        if (ImGui::IsItemHovered()) {
            const ImVec2 m = ImGui::GetIO().MousePos;
            const int x = std::clamp(static_cast<int>((m.x - p0.x) / zx), 0, w - 1);
            const int k = std::clamp(static_cast<int>((m.y - p0.y) / zy), 0, bins - 1);
            const double opl = binCentreOpl(k);
            ImGui::SetTooltip("x %d, bin %d (%.4f ns, %.4f m)\nclick: go to this time and pixel", x, k,
                              opl / kC_m_per_ns, opl);
            if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
                st_.selX = x;
                setBin(k);
            }
        }
        const float y = p0.y + (st_.bin + 0.5f) * zy;
        dl->AddLine(ImVec2(p0.x, y), ImVec2(p0.x + size.x, y), IM_COL32(255, 200, 40, 160));
        const float x = p0.x + (st_.selX + 0.5f) * zx;
        dl->AddLine(ImVec2(x, p0.y), ImVec2(x, p0.y + size.y), IM_COL32(255, 200, 40, 90));
    } else {
        ImGui::Dummy(size);
    }
    verticalTicks(dl, streakTicksNs_, loNs, hiNs, p0.y, p0.y + size.y, p0.x - 1.0f, -1.0f);
    verticalTicks(dl, niceTicks(lo, hi, maxTicks), lo, hi, p0.y, p0.y + size.y, p0.x + size.x + 1.0f, 1.0f);

    ImGui::Text("Time profile of pixel (%d, %d), luminance", st_.selX, st_.selY);
    ImGui::SameLine();
    ImGui::Checkbox("log scale", &st_.profileLog);
    track("log scale");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("log10 of the luminance over %.0f decades below the pixel's peak", kProfileDecades);
    if (profileLum_.empty()) return;
    const float peak = *std::max_element(profileLum_.begin(), profileLum_.end());
    char overlay[128];
    const float at = st_.bin < static_cast<int>(profileLum_.size()) ? profileLum_[st_.bin] : 0.0f;
    if (st_.profileLog)
        std::snprintf(overlay, sizeof overlay, "log scale, %.0f decades; peak %.4g, bin %d: %.4g", kProfileDecades,
                      peak, st_.bin, at);
    else
        std::snprintf(overlay, sizeof overlay, "peak %.4g, bin %d: %.4g", peak, st_.bin, at);
    ImGui::SetCursorPosX(ImGui::GetCursorPosX() + margin);
    if (st_.profileLog) {
        const std::vector<float> shown = logScale(profileLum_, kProfileDecades);
        ImGui::PlotLines("##profile", shown.data(), static_cast<int>(shown.size()), 0, overlay, 0.0f, 1.05f,
                         ImVec2(size.x, plotH));
    } else {
        ImGui::PlotLines("##profile", profileLum_.data(), static_cast<int>(profileLum_.size()), 0, overlay, 0.0f,
                         peak > 0 ? peak * 1.05f : 1.0f, ImVec2(size.x, plotH));
    }
    const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
    const float pad = ImGui::GetStyle().FramePadding.x;
    // PlotLines puts value k at k / (count - 1) of the inner frame; the ticks follow the bin centres.
    const float span = std::max(1.0f, b.x - a.x - 2.0f * pad);
    const float x = a.x + pad + (bins > 1 ? static_cast<float>(st_.bin) / (bins - 1) : 0.5f) * span;
    dl->AddLine(ImVec2(x, a.y), ImVec2(x, b.y), IM_COL32(255, 200, 40, 200));
    const bool hovered = ImGui::IsItemHovered();
    if (hovered && ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
        const float t = (ImGui::GetIO().MousePos.x - a.x - pad) / span;
        setBin(static_cast<int>(std::lround(t * (bins - 1))));
    }
    const double c0 = binCentreOpl(0) / kC_m_per_ns, c1 = binCentreOpl(bins - 1) / kC_m_per_ns;
    profileTicksNs_ = niceTicks(loNs, hiNs, std::max(2, static_cast<int>(span / 70.0f)));
    std::vector<AxisTick> inside;
    for (const AxisTick& t : profileTicksNs_)
        if (t.value >= c0 && t.value <= c1) inside.push_back(t);
    horizontalTicks(dl, inside, c0, c1 > c0 ? c1 : c0 + 1.0, a.x + pad, a.x + pad + span, b.y);
    dl->AddText(ImVec2(a.x - margin + 4.0f, b.y + 4.0f), kTickColour, "ns");
}

}  // namespace tpb::app
