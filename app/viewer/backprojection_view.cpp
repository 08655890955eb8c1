// Viewer: the live back-projection of a relay-wall scan (render/nlos_backprojection.h). While the
// panel is shown, the film is read into a capture and back-projected on a helper thread from a
// snapshot, again after new passes (at most every kBackprojectionEverySec while the render runs,
// and once after its last pass) or when the grid or filter is edited. The panel shows the front
// maximum-intensity projection, the depth of that maximum, one depth slice and the top view.
#include "viewer/app.h"

#include "base/error.h"
#include "render/nlos_capture.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace tpb::app {

namespace {

ImTextureID texId(GLuint tex) { return reinterpret_cast<ImTextureID>(static_cast<intptr_t>(tex)); }

// Values over [lo, hi] as a black-red-yellow-white ramp (linear RGB).
float fraction(float value, float lo, float hi) {
    return hi > lo ? std::clamp((value - lo) / (hi - lo), 0.0f, 1.0f) : 0.0f;
}
void heat(float value, float lo, float hi, float* rgb) {
    const float t = fraction(value, lo, hi);
    rgb[0] = std::clamp(3.0f * t, 0.0f, 1.0f);
    rgb[1] = std::clamp(3.0f * t - 1.0f, 0.0f, 1.0f);
    rgb[2] = std::clamp(3.0f * t - 2.0f, 0.0f, 1.0f);
}

// Depth fraction t in [0, 1] as blue (near) - cyan - green - yellow - red (far), times `bright`.
void depthColour(float t, float bright, float* rgb) {
    t = std::clamp(t, 0.0f, 1.0f);
    const float r = std::clamp(2.0f * t - 0.5f, 0.0f, 1.0f);
    const float g = std::clamp(t < 0.5f ? 2.0f * t + 0.25f : 2.0f - 2.0f * t + 0.25f, 0.0f, 1.0f);
    const float b = std::clamp(1.0f - 2.0f * t + 0.25f, 0.0f, 1.0f);
    rgb[0] = r * bright;
    rgb[1] = g * bright;
    rgb[2] = b * bright;
}

// Uploads `rgb` (w x h) and maps it for display as it is (no exposure, no sRGB: already colours).
void show(DisplayImage& img, const DisplayProgram& program, int w, int h, const std::vector<float>& rgb) {
    img.upload(w, h, rgb.data());
    DisplayParams p;
    p.srgb = false;
    program.apply(img, p);
}

}  // namespace

bool sameBackprojection(const BackprojectionSettings& a, const BackprojectionSettings& b) {
    return a.depthMinM == b.depthMinM && a.depthMaxM == b.depthMaxM && a.depths == b.depths &&
           a.lateralX == b.lateralX && a.lateralY == b.lateralY && a.filter == b.filter;
}

void Viewer::updateBackprojection() {
    using namespace std::chrono_literals;
    if (scene_.camera.scan == ScanMode::None) return;
    // --- Collect a finished back-projection and colour its images ---
    if (bpJob_.valid() && bpJob_.wait_for(0s) == std::future_status::ready) {
        BackprojectionResult r = bpJob_.get();
        if (r.generation == session_.generation() && (r.volume.complete || !r.error.empty())) {
            bp_ = std::move(r);
            bpSliceUploaded_ = -1;
            if (bp_->error.empty()) {
                const BackprojectionGrid& g = bp_->volume.grid;
                const int nx = g.nx(), ny = g.ny(), nz = g.nz();
                const BackprojectionImages& im = bp_->images;
                // The images span their own range: an unfiltered sum sits on a broad floor.
                const float peak = bp_->volume.peakValue;
                const float frontLo = *std::min_element(im.front.begin(), im.front.end());
                const float topLo = *std::min_element(im.top.begin(), im.top.end());
                const double d0 = g.depthsM.front(), d1 = g.depthsM.back();
                std::vector<float> front(static_cast<size_t>(nx) * ny * 3), depth(front.size()),
                    top(static_cast<size_t>(nx) * nz * 3);
                for (size_t p = 0; p < im.front.size(); ++p) {
                    heat(im.front[p], frontLo, peak, &front[p * 3]);
                    const float t = d1 > d0 ? static_cast<float>((im.frontDepthM[p] - d0) / (d1 - d0)) : 0.0f;
                    depthColour(t, std::sqrt(fraction(im.front[p], frontLo, peak)), &depth[p * 3]);
                }
                for (size_t p = 0; p < im.top.size(); ++p) heat(im.top[p], topLo, peak, &top[p * 3]);
                show(bpFront_, program_, nx, ny, front);
                show(bpDepth_, program_, nx, ny, depth);
                show(bpTop_, program_, nx, nz, top);
                st_.bpSlice = st_.bpSliceAuto ? bp_->volume.peakK : std::clamp(st_.bpSlice, 0, nz - 1);
            }
        }
    }
    if (!st_.showBackprojection || !session_.hasDriver()) return;

    // --- A new one: after new passes (throttled while rendering) or new settings ---
    const uint64_t gen = session_.generation(), passes = driver().completedPasses();
    const bool newSettings = !bp_ || bp_->generation != gen || !sameBackprojection(bp_->settings, st_.bp);
    const bool newPasses = bp_ && bp_->passes != passes;
    if (!bpJob_.valid() && passes > 0 && (newSettings || newPasses) &&
        (newSettings || !driver().running() || nowSec() - bpLaunched_ >= kBackprojectionEverySec)) {
        bpLaunched_ = nowSec();
        std::shared_ptr<const FilmSnapshot> snap = driver().snapshot();
        bpJob_ = std::async(std::launch::async, [snap = std::move(snap), scene = &scene_, s = st_.bp, gen, passes,
                                                 cancel = &bpCancel_]() mutable {
            BackprojectionResult r;
            r.generation = gen;
            r.passes = passes;
            r.settings = s;
            const double t0 = nowSec();
            try {
                const NlosCapture cap = nlosCaptureData(*snap, *scene);
                snap.reset();  // read: let the render's tiles go
                // One thread: the render's workers have the cores.
                r.pairs = backprojectionPairs(cap);
                r.volume = backproject(cap, s, 1, cancel);
                r.images = backprojectionImages(r.volume);
            } catch (const UserError& e) {
                r.error = e.what();
            }
            r.seconds = nowSec() - t0;
            return r;
        });
    }

    // --- The depth slice shown ---
    if (bp_ && bp_->error.empty() && bpSliceUploaded_ != st_.bpSlice) {
        const BackprojectionVolume& v = bp_->volume;
        const int nx = v.grid.nx(), ny = v.grid.ny();
        std::vector<float> rgb(static_cast<size_t>(nx) * ny * 3);
        const float lo = *std::min_element(v.values.begin(), v.values.end());  // the volume's range
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i)
                heat(v.at(i, j, st_.bpSlice), lo, v.peakValue, &rgb[(static_cast<size_t>(j) * nx + i) * 3]);
        show(bpSliceImage_, program_, nx, ny, rgb);
        bpSliceUploaded_ = st_.bpSlice;
    }
}

bool Viewer::backprojectionSettled() const {
    if (!st_.showBackprojection || scene_.camera.scan == ScanMode::None) return true;
    if (bpJob_.valid()) return false;
    return bp_ && bp_->generation == session_.generation() && bp_->passes == driver().completedPasses() &&
           sameBackprojection(bp_->settings, st_.bp);
}

void Viewer::drawBackprojectionSection() {
    if (scene_.camera.scan == ScanMode::None) return;  // the same rows for the whole session
    if (!section("Back-projection")) return;
    ImGui::Checkbox("Show back-projection", &st_.showBackprojection);
    track("Show back-projection");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("Back-project the capture onto voxels in front of the wall (in place of the streak)");
    ImGui::SameLine();
    bool laplacian = st_.bp.filter == BackprojectionFilter::Laplacian;
    if (ImGui::Checkbox("Laplacian filter", &laplacian))
        st_.bp.filter = laplacian ? BackprojectionFilter::Laplacian : BackprojectionFilter::None;
    track("Laplacian filter");
    // Edits apply on Enter (a half-typed value would start a back-projection per key).
    const ImGuiInputTextFlags enter = ImGuiInputTextFlags_EnterReturnsTrue;
    double dmin = st_.bp.depthMinM, dmax = st_.bp.depthMaxM;
    if (ImGui::InputDouble("depth min (m)", &dmin, 0.0, 0.0, "%.3f", enter)) st_.bp.depthMinM = std::max(dmin, 0.0);
    track("depth min (m)");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Nearest voxel from the wall; 0: one depth step");
    if (ImGui::InputDouble("depth max (m)", &dmax, 0.0, 0.0, "%.3f", enter)) st_.bp.depthMaxM = std::max(dmax, 0.0);
    track("depth max (m)");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Farthest voxel; 0: the deepest the film's last bin sees");
    int depths = st_.bp.depths;
    if (ImGui::InputInt("depths", &depths, 8, 32, enter)) st_.bp.depths = std::clamp(depths, 1, 1024);
    track("depths");
    const int nz = bp_ && bp_->error.empty() ? bp_->volume.grid.nz() : 1;
    const float sliceM =
        bp_ && bp_->error.empty()
            ? static_cast<float>(bp_->volume.grid.depthsM[static_cast<size_t>(std::clamp(st_.bpSlice, 0, nz - 1))])
            : 0.0f;
    char fmt[48];
    std::snprintf(fmt, sizeof fmt, "%%d (%.3f m)", static_cast<double>(sliceM));
    if (ImGui::SliderInt("depth slice", &st_.bpSlice, 0, nz - 1, fmt)) st_.bpSliceAuto = false;
    track("depth slice");
}

void Viewer::drawBackprojectionPanel() {
    if (!bp_) {
        ImGui::TextWrapped("Back-projection: waiting for the first pass ...");
        return;
    }
    if (!bp_->error.empty()) {
        ImGui::TextWrapped("Back-projection refused: %s", bp_->error.c_str());
        return;
    }
    const BackprojectionVolume& v = bp_->volume;
    const BackprojectionGrid& g = v.grid;
    const Vec3 p = g.voxel(v.peakI, v.peakJ, v.peakK);
    ImGui::TextWrapped(
        "Back-projection of %llu passes (luminance, filter %s): %d x %d x %d voxels x %lld pairs in %.0f ms; "
        "peak at depth %.3f m, (%.3f, %.3f, %.3f) m. Depths %.3f - %.3f m.",
        static_cast<unsigned long long>(bp_->passes), backprojectionFilterName(v.filter), g.nx(), g.ny(), g.nz(),
        static_cast<long long>(bp_->pairs), 1000.0 * bp_->seconds, g.depthsM[static_cast<size_t>(v.peakK)], p.x, p.y,
        p.z, g.depthsM.front(), g.depthsM.back());
    // Four images in a row, each fitted to a quarter of the panel, captions above.
    const ImVec2 avail = ImGui::GetContentRegionAvail();
    const float gap = 12.0f, lineH = ImGui::GetTextLineHeightWithSpacing();
    const float cellW = std::max(20.0f, (avail.x - 3.0f * gap) / 4.0f), cellH = std::max(20.0f, avail.y - lineH);
    struct Tile {
        const char* caption;
        const DisplayImage& img;
    };
    char sliceCaption[64];
    std::snprintf(sliceCaption, sizeof sliceCaption, "slice at %.3f m",
                  g.depthsM[static_cast<size_t>(std::clamp(st_.bpSlice, 0, g.nz() - 1))]);
    const Tile tiles[] = {{"front: max over depth", bpFront_},
                          {"depth of the max (blue near, red far)", bpDepth_},
                          {sliceCaption, bpSliceImage_},
                          {"top: max over y (depth down)", bpTop_}};
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    ImDrawList* dl = ImGui::GetWindowDrawList();
    for (int t = 0; t < 4; ++t) {
        const DisplayImage& img = tiles[t].img;
        const float x0 = origin.x + t * (cellW + gap);
        dl->AddText(ImVec2(x0, origin.y), IM_COL32(220, 220, 230, 255), tiles[t].caption);
        if (img.empty()) continue;
        const float zoom = std::min(cellW / img.width(), cellH / img.height());
        const ImVec2 p0(std::floor(x0), std::floor(origin.y + lineH));
        dl->AddImage(texId(img.texture()), p0, ImVec2(p0.x + img.width() * zoom, p0.y + img.height() * zoom));
        if (t == 0) bpFrontArea_ = {p0.x, p0.y, img.width() * zoom, img.height() * zoom};
    }
    ImGui::Dummy(avail);
}

}  // namespace tpb::app
