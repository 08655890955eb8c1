#include "io/folder_lock.h"

#include "base/error.h"
#include "io/image_io.h"

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <utility>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace tpb {

namespace {

// The locks this process holds, by the folder's (device, inode): a second acquire shares the first.
// The count of holders is kept here, under the mutex, so that the last release closes the file
// before another acquire can look (a weak_ptr would expire before its object's destructor ran).
struct Held {
    int fd = -1;
    int holders = 0;
};
std::mutex gHeldMutex;
std::map<std::pair<uint64_t, uint64_t>, Held> gHeld;

}  // namespace

std::shared_ptr<FolderLock> FolderLock::acquire(const std::string& dir, const std::string& holder,
                                                const std::string& otherFolder) {
    ensureWritableDir(dir);
    struct stat st {};
    if (::stat(dir.c_str(), &st) != 0)
        throw UserError(dir, 0, "", std::string("cannot read the folder: ") + std::strerror(errno));
    const std::pair<uint64_t, uint64_t> key{st.st_dev, st.st_ino};
    const std::lock_guard<std::mutex> guard(gHeldMutex);
    if (const auto mine = gHeld.find(key); mine != gHeld.end()) {
        ++mine->second.holders;
        return std::shared_ptr<FolderLock>(new FolderLock(key));
    }

    const std::string lockPath = (std::filesystem::path(dir) / kFolderLockName).string();
    const int fd = ::open(lockPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
        throw UserError(dir, 0, "",
                        std::string("cannot create the lock file ") + kFolderLockName + ": " + std::strerror(errno) +
                            "; " + otherFolder);
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        const int err = errno;
        if (err == EWOULDBLOCK) {
            char buf[256] = {};
            const ssize_t n = ::pread(fd, buf, sizeof buf - 1, 0);
            std::string other = n > 0 ? std::string(buf, static_cast<size_t>(n)) : std::string();
            while (!other.empty() && (other.back() == '\n' || other.back() == ' ')) other.pop_back();
            ::close(fd);
            throw UserError(dir, 0, "",
                            "another tpb run (" + (other.empty() ? std::string("unknown process") : other) +
                                ") is writing into this folder; two runs in one folder would mix their files: wait "
                                "for it to end, or " +
                                otherFolder);
        }
        // A file system without locks: go on, but say what is not detected.
        std::fprintf(stderr, "warning: %s: cannot lock the folder (%s): a second run into it would not be detected\n",
                     dir.c_str(), std::strerror(err));
    }
    const std::string text = holder + ", pid " + std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd, 0) == 0) {
        [[maybe_unused]] const ssize_t n = ::pwrite(fd, text.data(), text.size(), 0);
    }
    gHeld[key] = Held{fd, 1};
    return std::shared_ptr<FolderLock>(new FolderLock(key));
}

FolderLock::~FolderLock() {
    const std::lock_guard<std::mutex> guard(gHeldMutex);
    const auto held = gHeld.find(key_);
    if (held == gHeld.end() || --held->second.holders > 0) return;
    ::close(held->second.fd);  // releases the lock
    gHeld.erase(held);
}

}  // namespace tpb
