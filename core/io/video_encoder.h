// MP4 (H.264) encoding by ffmpeg run as a child process: the only place in tpb that starts
// ffmpeg. Frames go to ffmpeg's stdin as raw rgb24 (`-f rawvideo -pix_fmt rgb24 -s WxH -r FPS -i -
// -c:v libx264 -pix_fmt yuv420p`); an odd width or height is padded with black to an even one
// (yuv420p needs even dimensions). The video is written to "<path>.tmp-<pid>" (atomic_file.h's
// name) and renamed to `path` only after ffmpeg exited with 0 and the file was checked (mp4Problem:
// ffmpeg exits with 0 even when a full disk cut its trailer), so a failed, cancelled or
// interrupted encoding never leaves a half-written .mp4. ffmpeg runs in its own process group: a
// Ctrl-C at the terminal reaches tpb only, which decides (abort() kills ffmpeg and removes the
// temporary file).
#pragma once
#include <string>
#include <sys/types.h>

namespace tpb {

// The full path of `name` found in $PATH (an executable regular file), or "" when absent.
std::string findExecutable(const std::string& name);
// findExecutable("ffmpeg"), or a UserError "ffmpeg not found on PATH: install it with apt-get
// install ffmpeg, or drop <flag>" naming the flag or button that asked for it.
std::string requireFfmpeg(const std::string& flag);

// Why the MP4 file at `path` is not a complete video of `frames` frames, or "" when it is: its
// top-level boxes must tile the file exactly (ftyp first, then mdat and moov), and the track's
// sample size table (moov/trak/mdia/minf/stbl/stsz) must count `frames` samples. Reads box
// headers and a few bytes only (no decoding).
std::string mp4Problem(const std::string& path, int frames);

class VideoEncoder {
public:
    // Starts ffmpeg for frames of width x height at `fps` frames per second. Throws UserError
    // when ffmpeg is missing or cannot be started.
    VideoEncoder(const std::string& path, int width, int height, double fps, const std::string& flag = "--mp4");
    // abort() unless finish() succeeded.
    ~VideoEncoder();
    VideoEncoder(const VideoEncoder&) = delete;
    VideoEncoder& operator=(const VideoEncoder&) = delete;

    // One frame, width*height*3 bytes (rgb24, top row first). Throws UserError (with the tail
    // of ffmpeg's stderr) when ffmpeg has stopped reading.
    void addFrame(const unsigned char* rgb);
    // Closes ffmpeg's input, waits for it, checks the file (mp4Problem) and renames the video into
    // place. Throws UserError naming the file, with the exit status or the problem found and the
    // tail of ffmpeg's stderr, when ffmpeg failed (nothing is left).
    void finish();
    // Kills ffmpeg, waits for it, removes the temporary file.
    void abort();

    int framesWritten() const { return frames_; }
    int paddedWidth() const { return w2_; }
    int paddedHeight() const { return h2_; }

private:
    int waitChild();                 // exit status as from waitpid
    std::string stderrTail() const;  // the last lines ffmpeg printed

    std::string path_, tmp_;
    int width_, height_, w2_, h2_;
    pid_t pid_ = -1;
    int stdinFd_ = -1, stderrFd_ = -1;
    int frames_ = 0;
    bool done_ = false;
};

}  // namespace tpb
