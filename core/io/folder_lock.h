// The lock a tpb process holds on a folder while it writes into it: `tpb render`/`converge` for
// their whole run (app/cli's OutputFolder), the viewer for each export and "Save checkpoint". Two
// writers in one folder would mix their files (and the second could remove the first one's).
//
// flock(2) on <dir>/.tpb.lock, exclusive and non-blocking: the kernel releases it when the process
// ends, a crash included. The lock file holds the holder's description ("tpb render, pid 123"),
// which a refused writer names. Within one process the same folder gives the same lock (shared):
// the viewer's export and its checkpoint may run at once. A file system without locks (some
// network mounts) gives a warning on stderr and no lock.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

namespace tpb {

inline constexpr const char* kFolderLockName = ".tpb.lock";

class FolderLock {
public:
    // Creates `dir` if needed and locks it for `holder` ("tpb render"). Throws UserError "<dir>:
    // another tpb run (<its holder>) is writing into this folder; two runs in one folder would mix
    // their files: wait for it to end, or <otherFolder>" when another process holds it.
    static std::shared_ptr<FolderLock> acquire(const std::string& dir, const std::string& holder,
                                               const std::string& otherFolder = "give this one another folder with -o");
    ~FolderLock();  // releases the lock; the lock file stays (unlinking it would race)
    FolderLock(const FolderLock&) = delete;
    FolderLock& operator=(const FolderLock&) = delete;

private:
    explicit FolderLock(std::pair<uint64_t, uint64_t> key) : key_(key) {}
    std::pair<uint64_t, uint64_t> key_;  // the folder's (device, inode)
};

}  // namespace tpb
