// The binary container of tpb's film files, checkpoints (.tpbck, render/checkpoint.h) and
// references (.tpbref, eval/reference.h): one layout, written and read here.
//
//   8 bytes   magic, naming the format ("TPBCKPT\n", "TPBREF1\n")
//   8 bytes   n, the header's length (uint64, little-endian)
//   n bytes   the header: JSON text describing the payload (its format, version and arrays)
//   payload   the arrays the header describes, raw little-endian numbers, in its order
//   8 bytes   (sealed files) a hash of the payload: FNV-1a over its 64-bit words
//
// The writer goes through AtomicFile (the file appears whole or not at all). The reader checks the
// magic, the header's length against the file, and (readSeal) the hash; every failure goes to the
// format's `fail`, which throws the format's own error (naming the file and the fix).
#pragma once
#include "io/atomic_file.h"

#include <cstdint>
#include <fstream>
#include <functional>
#include <string>
#include <string_view>

namespace tpb {

inline constexpr uint64_t kMaxContainerHeaderBytes = uint64_t(64) << 20;

// FNV-1a over 64-bit words, a tail of 1-7 bytes zero-padded to a word (the writer and the reader
// pass the same pieces: one array at a time).
struct WordHash {
    uint64_t h = 0xcbf29ce484222325ull;
    void add(const void* data, size_t bytes);
};

class FilmContainerWriter {
public:
    FilmContainerWriter(const std::string& path, std::string_view magic, std::string_view header);
    void write(const void* data, size_t bytes);  // payload (hashed)
    // Writes the hash of the payload (sealed files) and puts the file in place.
    void commit(bool seal);

private:
    AtomicFile file_;
    WordHash hash_;
};

class FilmContainerReader {
public:
    using Fail = std::function<void(const std::string& why)>;  // throws; called with what is wrong
    // Opens `path` and reads its header; `fail` for a missing magic or a header the file cannot hold.
    // A file that cannot be opened is the caller's to report (opened() false).
    FilmContainerReader(const std::string& path, std::string_view magic, Fail fail);
    bool opened() const { return opened_; }
    const std::string& header() const { return header_; }
    uint64_t fileBytes() const { return fileBytes_; }
    uint64_t payloadOffset() const { return 16 + header_.size(); }
    // The next `bytes` of the payload ("truncated <what>" when the file ends first).
    void read(void* data, size_t bytes, const char* what = "payload");
    // The hash after the payload equals the one of what read() returned.
    void readSeal();

private:
    [[noreturn]] void fail(const std::string& why) const;
    std::string path_;
    Fail fail_;
    std::ifstream in_;
    bool opened_ = false;
    std::string header_;
    uint64_t fileBytes_ = 0;
    WordHash hash_;
};

}  // namespace tpb
