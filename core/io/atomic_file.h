// Writing a file so that it is either complete under its final name or not there at all.
//
// The bytes go to "<path>.tmp-<pid>" in the same folder with checked POSIX writes (every short
// write, EINTR, ENOSPC/EFBIG/EIO and the error close() may report are seen); only when all of it
// is written and the file is closed is it renamed over `path`. On any failure the temporary file
// is removed, an existing file at `path` is left as it was, and a UserError names `path` and the
// system's reason ("No space left on device", "Permission denied"...) with the fix.
//
// Used by every writer of the project (EXR/PNG in image_io, text files, .tpbref references) and
// meant for checkpoints later: a checkpoint interrupted by a full disk or Ctrl-C must never
// replace the previous good one.
#pragma once
#include <cstddef>
#include <string>
#include <string_view>

namespace tpb {

class AtomicFile {
public:
    // Opens the temporary file; throws UserError if it cannot be created.
    explicit AtomicFile(std::string path);
    // Removes the temporary file unless commit() succeeded.
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    // Appends bytes; throws UserError (and removes the temporary file) on failure.
    void write(const void* data, size_t bytes);
    void write(std::string_view s) { write(s.data(), s.size()); }
    // Closes the file and renames it into place; throws UserError on failure.
    void commit();

    const std::string& path() const { return path_; }
    size_t bytesWritten() const { return written_; }

private:
    [[noreturn]] void fail(const std::string& what, int err);
    void discard();

    std::string path_, tmp_;
    int fd_ = -1;
    size_t written_ = 0;
    bool committed_ = false;
};

// One-shot form: the whole file at once.
void writeFileAtomic(const std::string& path, std::string_view bytes);

// The name of the temporary file AtomicFile uses for `path` in this process.
std::string atomicTmpName(const std::string& path);

// The fix to add to a failed write's message for the system error `err` ("; free space on that
// disk..."), or "" when there is none to suggest. Shared with writers that cannot go through
// AtomicFile (the HDF5 library writes its file by name: nlos_hdf5.cpp).
std::string atomicFailureFix(int err);

}  // namespace tpb
