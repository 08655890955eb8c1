#include "io/atomic_file.h"

#include "base/error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

namespace tpb {

std::string atomicFailureFix(int err) {
    switch (err) {
        case ENOSPC:
        case EDQUOT: return "; free space on that disk or write somewhere else (tpb render -o DIR)";
        case EFBIG: return "; the file is larger than this process may write (ulimit -f) or the file system allows";
        case EACCES:
        case EPERM:
        case EROFS: return "; the folder is not writable: choose another one (tpb render -o DIR)";
        case ENOENT:
        case ENOTDIR: return "; the folder does not exist";
        default: return "";
    }
}

std::string atomicTmpName(const std::string& path) { return path + ".tmp-" + std::to_string(::getpid()); }

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)), tmp_(atomicTmpName(path_)) {
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) {
        const int err = errno;
        throw UserError(path_, 0, "",
                        std::string("cannot create the file: ") + std::strerror(err) + atomicFailureFix(err));
    }
}

AtomicFile::~AtomicFile() {
    if (!committed_) discard();
}

void AtomicFile::discard() {
    if (fd_ >= 0) {
        ::close(fd_);
        fd_ = -1;
    }
    if (!tmp_.empty()) ::unlink(tmp_.c_str());
}

void AtomicFile::fail(const std::string& what, int err) {
    discard();
    committed_ = true;  // nothing left to clean up
    throw UserError(
        path_, 0, "",
        what + ": " + std::strerror(err) + atomicFailureFix(err) + " (nothing was written under this name)");
}

void AtomicFile::write(const void* data, size_t bytes) {
    TPB_CHECK(fd_ >= 0 && !committed_);
    const char* p = static_cast<const char*>(data);
    while (bytes > 0) {
        const ssize_t n = ::write(fd_, p, bytes);
        if (n < 0) {
            if (errno == EINTR) continue;
            fail("cannot write the file after " + std::to_string(written_) + " bytes", errno);
        }
        if (n == 0) fail("cannot write the file after " + std::to_string(written_) + " bytes", EIO);
        p += n;
        bytes -= static_cast<size_t>(n);
        written_ += static_cast<size_t>(n);
    }
}

void AtomicFile::commit() {
    TPB_CHECK(fd_ >= 0 && !committed_);
    // close() is where network and some local file systems report deferred write errors.
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail("cannot finish writing the file", errno);
    if (::rename(tmp_.c_str(), path_.c_str()) != 0) fail("cannot move the finished file into place", errno);
    committed_ = true;
}

void writeFileAtomic(const std::string& path, std::string_view bytes) {
    AtomicFile f(path);
    f.write(bytes);
    f.commit();
}

}  // namespace tpb
