#include "io/video_encoder.h"

#include "base/error.h"
#include "io/atomic_file.h"

#include <cerrno>
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

}  // namespace

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
    : path_(path), tmp_(atomicTmpName(path)), width_(width), height_(height), w2_(width + (width & 1)),
      h2_(height + (height & 1)) {
    TPB_CHECK(width > 0 && height > 0 && fps > 0.0);
    const std::string exe = requireFfmpeg(flag);
    // ffmpeg's stderr: an unlinked temporary file (read back for the error message; no pipe to
    // drain while we write frames).
    FILE* log = std::tmpfile();
    if (!log) throw UserError(path, 0, "", std::string("cannot create a temporary file for ffmpeg's messages: ") + std::strerror(errno));
    stderrFd_ = ::fcntl(::fileno(log), F_DUPFD_CLOEXEC, 0);
    std::fclose(log);
    int pipeFds[2];
    if (::pipe2(pipeFds, O_CLOEXEC) != 0) {
        ::close(stderrFd_);
        throw UserError(path, 0, "", std::string("cannot create a pipe to ffmpeg: ") + std::strerror(errno));
    }
    const std::string size = std::to_string(w2_) + "x" + std::to_string(h2_);
    std::vector<std::string> args = {exe, "-hide_banner", "-loglevel", "error", "-nostats", "-y",
                                     "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", size, "-r", fmtNumber(fps),
                                     "-i", "-", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "mp4", tmp_};
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
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
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
