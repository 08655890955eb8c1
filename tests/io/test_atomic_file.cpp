// AtomicFile (core/io/atomic_file.h): a file is complete under its final name or not there at all.
// Write failures are provoked for real: RLIMIT_FSIZE in a forked child makes write() fail with
// EFBIG part-way through, exactly as a full disk fails it with ENOSPC (the CLI test
// CliErrors.DiskFullDuringExport does the latter on a small tmpfs).
#include "io/atomic_file.h"
#include "base/error.h"
#include "io/image_io.h"
#include "support/temp_dir.h"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <functional>
#include <memory>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace tpb;

namespace {

std::string slurp(const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

int countTmpFiles(const fs::path& dir) {
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir))
        n += e.path().filename().string().find(".tmp-") != std::string::npos;
    return n;
}

class AtomicFileTest : public ::testing::Test {
protected:
    void SetUp() override {
        tmp_ = std::make_unique<test::TempDir>(
            "atomic_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        dir_ = tmp_->path();
    }
    void TearDown() override { tmp_.reset(); }
    // Runs `body` in a child process whose files may not grow beyond `limitBytes` (SIGXFSZ ignored,
    // so write() returns EFBIG instead of killing it). The child's exit code is the result: 0 when
    // `body` returned true.
    int inChildWithFileSizeLimit(rlim_t limitBytes, const std::function<bool()>& body) {
        const pid_t pid = ::fork();
        if (pid == 0) {
            std::signal(SIGXFSZ, SIG_IGN);
            rlimit rl{limitBytes, limitBytes};
            if (::setrlimit(RLIMIT_FSIZE, &rl) != 0) ::_exit(3);
            bool ok = false;
            try {
                ok = body();
            } catch (...) {
                ::_exit(4);
            }
            ::_exit(ok ? 0 : 1);
        }
        int status = 0;
        ::waitpid(pid, &status, 0);
        return WIFEXITED(status) ? WEXITSTATUS(status) : 100 + WTERMSIG(status);
    }
    std::unique_ptr<test::TempDir> tmp_;
    fs::path dir_;
};

TEST_F(AtomicFileTest, WritesTheBytesAndLeavesNoTemporaryFile) {
    const fs::path p = dir_ / "a.bin";
    std::string bytes(100000, '\0');
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 2654435761u >> 24);
    writeFileAtomic(p.string(), bytes);
    EXPECT_EQ(slurp(p), bytes);
    EXPECT_EQ(countTmpFiles(dir_), 0);
    // Replacing an existing file.
    writeFileAtomic(p.string(), "short");
    EXPECT_EQ(slurp(p), "short");
    EXPECT_EQ(countTmpFiles(dir_), 0);
}

TEST_F(AtomicFileTest, AbandonedWriterRemovesItsTemporaryFileAndKeepsTheOldOne) {
    const fs::path p = dir_ / "keep.txt";
    writeFileAtomic(p.string(), "old");
    {
        AtomicFile f(p.string());
        f.write("new content that is never committed");
        EXPECT_EQ(countTmpFiles(dir_), 1);
    }
    EXPECT_EQ(countTmpFiles(dir_), 0);
    EXPECT_EQ(slurp(p), "old");
}

TEST_F(AtomicFileTest, MissingOrUnwritableFolderNamesThePath) {
    const std::string p = (dir_ / "no" / "such" / "folder" / "x.txt").string();
    try {
        writeFileAtomic(p, "x");
        FAIL() << "no error";
    } catch (const UserError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind(p + ": ", 0), 0u) << what;
        EXPECT_NE(what.find("No such file or directory"), std::string::npos) << what;
    }
}

// A write that fails part-way (the file system refuses more bytes) throws, names the path and the
// system's reason, removes the temporary file, and leaves the previous file untouched.
TEST_F(AtomicFileTest, FailedWritePartWayKeepsThePreviousFile) {
    const fs::path p = dir_ / "data.bin";
    writeFileAtomic(p.string(), "previous good version");
    const std::string big(64 * 1024, 'x');
    std::string message;
    const int code = inChildWithFileSizeLimit(16 * 1024, [&] {
        try {
            writeFileAtomic(p.string(), big);
        } catch (const UserError& e) {
            const std::string what = e.what();
            // The child reports through its exit code: each check is one bit.
            return what.rfind(p.string() + ": ", 0) == 0 && what.find("File too large") != std::string::npos &&
                   what.find("after 16384 bytes") != std::string::npos;
        }
        return false;
    });
    EXPECT_EQ(code, 0) << "the child did not see the expected UserError (exit " << code << ")";
    EXPECT_EQ(slurp(p), "previous good version");
    EXPECT_EQ(countTmpFiles(dir_), 0);
}

// The image writers encode in memory and go through AtomicFile: an EXR or PNG that does not fit
// fails cleanly instead of leaving a truncated file that looks finished.
TEST_F(AtomicFileTest, ImagesThatDoNotFitAreNotLeftTruncated) {
    const int w = 128, h = 128;
    std::vector<float> rgb(static_cast<size_t>(w) * h * 3);
    std::mt19937 rng(7);  // noise: neither format can compress it below the limit
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (float& v : rgb) v = u(rng);
    const fs::path exr = dir_ / "img.exr", png = dir_ / "img.png";
    const int code = inChildWithFileSizeLimit(8 * 1024, [&] {
        int failures = 0;
        try {
            writeExr(exr.string(), w, h, rgb);
        } catch (const UserError&) {
            ++failures;
        }
        try {
            writePngPreview(png.string(), w, h, rgb);
        } catch (const UserError&) {
            ++failures;
        }
        return failures == 2;
    });
    EXPECT_EQ(code, 0);
    EXPECT_FALSE(fs::exists(exr));
    EXPECT_FALSE(fs::exists(png));
    EXPECT_EQ(countTmpFiles(dir_), 0);
    // Without the limit the same images are written and read back exactly.
    writeExr(exr.string(), w, h, rgb);
    int rw = 0, rh = 0;
    std::vector<float> back;
    readExr(exr.string(), rw, rh, back);
    ASSERT_EQ(rw, w);
    ASSERT_EQ(rh, h);
    EXPECT_EQ(back, rgb);
}

}  // namespace
