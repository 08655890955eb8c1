// The viewer's exports, run on a background thread so the window keeps drawing: the current
// frame, all frames, the steady-state image, the streak image of a row, a pixel's profile, the
// whole volume for NumPy, an MP4 of the frames and a contact sheet (tone-mapped as shown), in
// the time axis and emission mode shown. The job reads one snapshot of the film (film_snapshot.h),
// taken when it starts, so its files show the same passes and a restart or closing the window never
// frees the data under it. Only film_export.h is called from the thread.
#pragma once
#include "render/driver.h"
#include "film/film_export.h"
#include "film/output_names.h"
#include "film/tone_map.h"

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace tpb::app {

struct ExportRequest {
    std::string dir = "out/view";
    bool frame = false, allFrames = false, steady = false, streak = false, profile = false;
    bool volume = false;        // volume_<tag>/: transient.npy & co (film/volume_export.h)
    bool mp4 = false;           // transient_<tag>.mp4 (film/picture_export.h, ffmpeg)
    bool contactSheet = false;  // contact_sheet_<tag>.png
    int bin = 0, row = 0, x = 0, y = 0;
    TimeAxis axis = TimeAxis::Real;
    EmissionMode mode = EmissionMode::Delta;
    ToneMap tone;  // the MP4's and contact sheet's mapping: what the screen shows
    double fps = 24.0;
    int sheetFrames = 16;
    std::string scenePath;  // for transient.json
    TimeResponse response;  // pulse shape and sensor response shown (film/time_response.h)
};

// File names: film/output_names.h, each tagged with outputTag(axis, mode, response).
// "All frames" cut short (Cancel, or a second Ctrl-C while the viewer closes) leaves this note in
// the frames' folder, saying how many of them this export wrote; a complete export removes it.
inline constexpr const char* kIncompleteName = "INCOMPLETE.txt";
void markFramesComplete(const std::string& dir, int written, int total);

// The job locks its folder (io/folder_lock.h) while it writes: an export into the folder a `tpb
// render` writes into is refused with the render's pid, and the render is refused meanwhile.
class ExportJob {
public:
    ExportJob() = default;
    ExportJob(const ExportJob&) = delete;
    ExportJob& operator=(const ExportJob&) = delete;
    ~ExportJob() { cancelAndJoin(); }

    // Starts the export (returns false if one is already running).
    bool start(std::shared_ptr<const Driver> driver, const ExportRequest& req);
    bool busy() const { return running_.load(); }
    // Joins a finished thread; true once per finished job (then result()/error() describe it).
    bool collect();
    float progress() const;
    std::string progressLabel() const;
    std::vector<std::string> written() const;
    std::string error() const;
    void cancel() { cancel_ = true; }
    void cancelAndJoin();

private:
    void run(std::shared_ptr<const Driver> driver, ExportRequest req);

    std::thread thread_;
    std::atomic<bool> running_{false}, cancel_{false};
    std::atomic<int> done_{0}, total_{0};
    mutable std::mutex mutex_;
    std::string stage_, error_;
    std::vector<std::string> written_;
};

}  // namespace tpb::app
