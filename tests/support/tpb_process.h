// The built `tpb` binary run as a user runs it, for the command-line tests: spawned with its
// stdout/stderr in files of a test folder, waited for with a timeout (then killed), its exit code
// or signal and its output returned. TPB_BINARY (set per test executable by CMakeLists.txt), or
// $TPB_TEST_BINARY to run the tests against another build (e.g. to see a new test fail on an old one).
#pragma once
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace tpb::test {

struct Proc {
    int code = -1;   // exit code, -1 when killed by a signal
    int signal = 0;  // terminating signal, 0 when it exited
    bool timedOut = false;
    std::string out, err;
    double seconds = 0.0;  // from the spawn to the end
};

inline std::string slurp(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

inline double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

inline const char* tpbBinary() {
    const char* e = std::getenv("TPB_TEST_BINARY");
    return e && *e ? e : TPB_BINARY;
}

// Starts tpb with `args`, stdin from /dev/null, stdout/stderr to `dir`/stdout.txt and stderr.txt;
// `env` entries "NAME=value" replace or add to the environment. -1 (and a test failure) if it cannot.
inline pid_t spawnTpb(const std::vector<std::string>& args, const std::filesystem::path& dir,
                      const std::vector<std::string>& env = {}) {
    std::vector<std::string> argv{tpbBinary()};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<char*> cargv;
    for (std::string& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    std::vector<std::string> envs;
    for (char** e = environ; *e; ++e) {
        const std::string kv(*e);
        bool replaced = false;
        for (const std::string& x : env) replaced |= kv.compare(0, x.find('=') + 1, x, 0, x.find('=') + 1) == 0;
        if (!replaced) envs.push_back(kv);
    }
    envs.insert(envs.end(), env.begin(), env.end());
    std::vector<char*> cenv;
    for (std::string& e : envs) cenv.push_back(e.data());
    cenv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, (dir / "stdout.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, (dir / "stderr.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = -1;
    const int rc = posix_spawn(&pid, cargv[0], &fa, nullptr, cargv.data(), cenv.data());
    posix_spawn_file_actions_destroy(&fa);
    EXPECT_EQ(rc, 0) << std::strerror(rc);
    return rc == 0 ? pid : -1;
}

// Waits for `pid` (spawned at `t0`, now()) to end, killing it after `timeoutSec`; its output from `dir`.
inline Proc waitTpb(pid_t pid, const std::filesystem::path& dir, double t0, double timeoutSec) {
    Proc p;
    int status = 0;
    for (;;) {
        if (waitpid(pid, &status, WNOHANG) == pid) break;
        if (now() - t0 > timeoutSec) {
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            p.timedOut = true;
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    p.seconds = now() - t0;
    if (WIFEXITED(status)) p.code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) p.signal = WTERMSIG(status);
    p.out = slurp(dir / "stdout.txt");
    p.err = slurp(dir / "stderr.txt");
    return p;
}

inline Proc runTpb(const std::vector<std::string>& args, const std::filesystem::path& dir,
                   const std::vector<std::string>& env = {}, double timeoutSec = 60.0) {
    const double t0 = now();
    const pid_t pid = spawnTpb(args, dir, env);
    if (pid < 0) return {};
    return waitTpb(pid, dir, t0, timeoutSec);
}

}  // namespace tpb::test
