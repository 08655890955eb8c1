#include "io/video_encoder.h"

#include "base/error.h"
#include "io/atomic_file.h"

#include <cerrno>
#include <cstdint>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

#include <fcntl.h>
#include <pthread.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace tpb {

namespace {

std::string fmtNumber(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v);
    return b;
}

// write() to ffmpeg's stdin without the process-wide SIGPIPE a dead reader raises: SIGPIPE is
// blocked in this thread for the call, and one it raised is consumed before unblocking.
bool writeAll(int fd, const unsigned char* p, size_t n) {
    sigset_t pipeSet, old;
    sigemptyset(&pipeSet);
    sigaddset(&pipeSet, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &pipeSet, &old);
    bool ok = true;
    while (n > 0) {
        const ssize_t w = ::write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            ok = false;
            break;
        }
        p += w;
        n -= static_cast<size_t>(w);
    }
    if (!ok) {
        const timespec zero{0, 0};
        sigtimedwait(&pipeSet, nullptr, &zero);  // the pending SIGPIPE of this write, if any
    }
    pthread_sigmask(SIG_SETMASK, &old, nullptr);
    return ok;
}

// One ISO BMFF box header read at `at`: its type and total size (0 when unreadable).
struct Box {
    char type[5] = {};
    uint64_t size = 0, header = 0;
};
Box readBox(int fd, uint64_t at, uint64_t end) {
    Box b;
    unsigned char h[16];
    if (end - at < 8 || ::pread(fd, h, 8, static_cast<off_t>(at)) != 8) return b;
    std::memcpy(b.type, h + 4, 4);
    const auto be = [&](int i, int n) {
        uint64_t v = 0;
        for (int k = 0; k < n; ++k) v = (v << 8) | h[i + k];
        return v;
    };
    b.size = be(0, 4);
    b.header = 8;
    if (b.size == 1) {  // 64-bit size after the type
        if (end - at < 16 || ::pread(fd, h + 8, 8, static_cast<off_t>(at + 8)) != 8) return Box{};
        b.size = be(8, 8);
        b.header = 16;
    } else if (b.size == 0) {  // "to the end of the file"
        b.size = end - at;
    }
    if (b.size < b.header || b.size > end - at) b.size = 0;
    return b;
}

// The sample count of the first track's sample size table (moov/trak/mdia/minf/stbl/stsz), -1 if absent.
int64_t sampleCount(int fd, uint64_t from, uint64_t end) {
    for (uint64_t at = from; at < end;) {
        const Box b = readBox(fd, at, end);
        if (b.size == 0) return -1;
        const std::string type(b.type);
        if (type == "trak" || type == "mdia" || type == "minf" || type == "stbl")
            return sampleCount(fd, at + b.header, at + b.size);
        if (type == "stsz") {  // version/flags (4), sample_size (4), sample_count (4)
            unsigned char c[4];
            if (b.size < b.header + 12 || ::pread(fd, c, 4, static_cast<off_t>(at + b.header + 8)) != 4) return -1;
            return (int64_t(c[0]) << 24) | (int64_t(c[1]) << 16) | (int64_t(c[2]) << 8) | int64_t(c[3]);
        }
        at += b.size;
    }
    return -1;
}

}  // namespace

std::string mp4Problem(const std::string& path, int frames) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return std::string("it cannot be opened: ") + std::strerror(errno);
    struct stat st {};
    const uint64_t end = ::fstat(fd, &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
    std::string problem;
    bool moov = false, mdat = false;
    int64_t samples = -1;
    for (uint64_t at = 0; at < end && problem.empty();) {
        const Box b = readBox(fd, at, end);
        if (b.size == 0) {
            problem = "it is cut short: a box at byte " + std::to_string(at) + " of " + std::to_string(end) +
                      " runs past the end of the file";
            break;
        }
        const std::string type(b.type);
        if (at == 0 && type != "ftyp") problem = "it does not start with an MP4 header (ftyp)";
        if (type == "mdat") mdat = true;
        if (type == "moov") {
            moov = true;
            samples = sampleCount(fd, at + b.header, at + b.size);
        }
        at += b.size;
    }
    ::close(fd);
    if (!problem.empty()) return problem;
    if (end == 0) return "it is empty";
    if (!mdat) return "it holds no video data (no mdat box)";
    if (!moov) return "its index (the moov box, written last) is missing: ffmpeg did not finish it";
    if (samples != frames)
        return "it indexes " + std::to_string(samples) + " frames of the " + std::to_string(frames) + " sent";
    return "";
}

std::string findExecutable(const std::string& name) {
    const char* path = std::getenv("PATH");
    if (!path) return "";
    const std::string p(path);
    size_t start = 0;
    for (;;) {
        const size_t end = p.find(':', start);
        const std::string dir = p.substr(start, end == std::string::npos ? std::string::npos : end - start);
        const std::string full = (dir.empty() ? std::string(".") : dir) + "/" + name;  // "" = the current folder
        struct stat st {};
        if (::stat(full.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(full.c_str(), X_OK) == 0) return full;
        if (end == std::string::npos) return "";
        start = end + 1;
    }
}

std::string requireFfmpeg(const std::string& flag) {
    const std::string exe = findExecutable("ffmpeg");
    if (exe.empty())
        throw UserError("ffmpeg not found on PATH: install it with apt-get install ffmpeg, or drop " + flag);
    return exe;
}

VideoEncoder::VideoEncoder(const std::string& path, int width, int height, double fps, const std::string& flag)
    : path_(path),
      tmp_(atomicTmpName(path)),
      width_(width),
      height_(height),
      w2_(width + (width & 1)),
      h2_(height + (height & 1)) {
    TPB_CHECK(width > 0 && height > 0 && fps > 0.0);
    const std::string exe = requireFfmpeg(flag);
    // ffmpeg's stderr: an unlinked temporary file (read back for the error message; no pipe to
    // drain while we write frames).
    FILE* log = std::tmpfile();
    if (!log)
        throw UserError(path, 0, "",
                        std::string("cannot create a temporary file for ffmpeg's messages: ") + std::strerror(errno));
    stderrFd_ = ::fcntl(::fileno(log), F_DUPFD_CLOEXEC, 0);
    std::fclose(log);
    int pipeFds[2];
    if (::pipe2(pipeFds, O_CLOEXEC) != 0) {
        ::close(stderrFd_);
        throw UserError(path, 0, "", std::string("cannot create a pipe to ffmpeg: ") + std::strerror(errno));
    }
    const std::string size = std::to_string(w2_) + "x" + std::to_string(h2_);
    std::vector<std::string> args = {exe,        "-hide_banner", "-loglevel", "error", "-nostats", "-y",
                                     "-f",       "rawvideo",     "-pix_fmt",  "rgb24", "-s",       size,
                                     "-r",       fmtNumber(fps), "-i",        "-",     "-c:v",     "libx264",
                                     "-pix_fmt", "yuv420p",      "-f",        "mp4",   tmp_};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, pipeFds[0], 0);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, stderrFd_, 2);
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    // Its own process group (no terminal Ctrl-C), default signal dispositions and mask.
    sigset_t none, all;
    sigemptyset(&none);
    sigfillset(&all);
    posix_spawnattr_setpgroup(&attr, 0);
    posix_spawnattr_setsigmask(&attr, &none);
    posix_spawnattr_setsigdefault(&attr, &all);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    const int rc = posix_spawn(&pid_, exe.c_str(), &fa, &attr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&attr);
    ::close(pipeFds[0]);
    if (rc != 0) {
        ::close(pipeFds[1]);
        ::close(stderrFd_);
        pid_ = -1;
        throw UserError(path, 0, "", "cannot start " + exe + ": " + std::strerror(rc));
    }
    stdinFd_ = pipeFds[1];
}

VideoEncoder::~VideoEncoder() {
    if (!done_) abort();
    if (stderrFd_ >= 0) ::close(stderrFd_);
}

int VideoEncoder::waitChild() {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {}
    pid_ = -1;
    return status;
}

std::string VideoEncoder::stderrTail() const {
    if (stderrFd_ < 0) return "";
    const off_t size = ::lseek(stderrFd_, 0, SEEK_END);
    const off_t from = size > 2000 ? size - 2000 : 0;
    std::string s(static_cast<size_t>(size - from), '\0');
    const ssize_t n = ::pread(stderrFd_, s.data(), s.size(), from);
    s.resize(n > 0 ? static_cast<size_t>(n) : 0);
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    if (from > 0) {
        const size_t nl = s.find('\n');
        s = "..." + (nl == std::string::npos ? s : s.substr(nl + 1));
    }
    return s.empty() ? "(ffmpeg printed nothing)" : s;
}

void VideoEncoder::addFrame(const unsigned char* rgb) {
    TPB_CHECK(!done_ && stdinFd_ >= 0);
    std::vector<unsigned char> padded;
    const unsigned char* data = rgb;
    if (w2_ != width_ || h2_ != height_) {
        padded.assign(static_cast<size_t>(w2_) * h2_ * 3, 0);
        for (int y = 0; y < height_; ++y)
            std::memcpy(&padded[static_cast<size_t>(y) * w2_ * 3], rgb + static_cast<size_t>(y) * width_ * 3,
                        static_cast<size_t>(width_) * 3);
        data = padded.data();
    }
    if (!writeAll(stdinFd_, data, static_cast<size_t>(w2_) * h2_ * 3)) {
        const int status = (::close(stdinFd_), stdinFd_ = -1, waitChild());
        done_ = true;
        ::unlink(tmp_.c_str());
        throw UserError(path_, 0, "",
                        "ffmpeg stopped reading frames after " + std::to_string(frames_) + " (" +
                            (WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                               : "signal " + std::to_string(WTERMSIG(status))) +
                            "): " + stderrTail() + " (nothing was written under this name)");
    }
    ++frames_;
}

void VideoEncoder::finish() {
    TPB_CHECK(!done_);
    done_ = true;
    ::close(stdinFd_);
    stdinFd_ = -1;
    const int status = waitChild();
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        ::unlink(tmp_.c_str());
        throw UserError(path_, 0, "",
                        "ffmpeg failed (" +
                            (WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                               : "killed by signal " + std::to_string(WTERMSIG(status))) +
                            "): " + stderrTail() + " (nothing was written under this name)");
    }
    // ffmpeg can exit with 0 after failing to write its trailer (a full disk): the file is checked
    // before it gets its final name.
    const std::string problem = mp4Problem(tmp_, frames_);
    if (!problem.empty()) {
        ::unlink(tmp_.c_str());
        const std::string said = stderrTail();
        throw UserError(path_, 0, "",
                        "ffmpeg exited with 0 but the video it wrote is not playable: " + problem +
                            (said == "(ffmpeg printed nothing)" ? "" : "; ffmpeg said: " + said) +
                            " (a full disk? nothing was written under this name)");
    }
    if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
        const int err = errno;
        ::unlink(tmp_.c_str());
        throw UserError(path_, 0, "", std::string("cannot move the finished video into place: ") + std::strerror(err));
    }
}

void VideoEncoder::abort() {
    done_ = true;
    if (stdinFd_ >= 0) {
        ::close(stdinFd_);
        stdinFd_ = -1;
    }
    if (pid_ > 0) {
        ::kill(pid_, SIGKILL);
        waitChild();
    }
    ::unlink(tmp_.c_str());
}

}  // namespace tpb
