#include "io/film_container.h"

#include "base/error.h"

#include <bit>
#include <cstring>
#include <filesystem>

namespace tpb {

static_assert(std::endian::native == std::endian::little, "tpb's film files are little-endian");

void WordHash::add(const void* data, size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    size_t i = 0;
    for (; i + 8 <= bytes; i += 8) {
        uint64_t w;
        std::memcpy(&w, p + i, 8);
        h = (h ^ w) * 0x100000001b3ull;
    }
    if (i < bytes) {  // a tail of 1-7 bytes (float32 arrays of odd length), zero-padded to a word
        uint64_t w = 0;
        std::memcpy(&w, p + i, bytes - i);
        h = (h ^ w) * 0x100000001b3ull;
    }
}

FilmContainerWriter::FilmContainerWriter(const std::string& path, std::string_view magic, std::string_view header)
    : file_(path) {
    TPB_CHECK(magic.size() == 8);
    const uint64_t n = header.size();
    file_.write(magic.data(), 8);
    file_.write(&n, 8);
    file_.write(header);
}

void FilmContainerWriter::write(const void* data, size_t bytes) {
    hash_.add(data, bytes);
    file_.write(data, bytes);
}

void FilmContainerWriter::commit(bool seal) {
    if (seal) file_.write(&hash_.h, 8);
    file_.commit();
}

FilmContainerReader::FilmContainerReader(const std::string& path, std::string_view magic, Fail fail)
    : path_(path), fail_(std::move(fail)) {
    TPB_CHECK(magic.size() == 8);
    in_.open(path, std::ios::binary);
    if (!in_) return;
    opened_ = true;
    std::error_code ec;
    fileBytes_ = std::filesystem::file_size(path, ec);
    if (ec) this->fail("its size cannot be read (" + ec.message() + ")");
    char m[8];
    if (!in_.read(m, 8) || std::memcmp(m, magic.data(), 8) != 0)
        this->fail("wrong magic bytes, expected \"" + std::string(magic.substr(0, 7)) + "\"");
    uint64_t n = 0;
    if (!in_.read(reinterpret_cast<char*>(&n), 8)) this->fail("truncated header");
    if (n == 0 || n > kMaxContainerHeaderBytes || n > fileBytes_ - 16)
        this->fail("truncated or oversized header (" + std::to_string(n) + " bytes announced)");
    header_.assign(n, '\0');
    if (!in_.read(header_.data(), static_cast<std::streamsize>(n))) this->fail("truncated header");
}

void FilmContainerReader::read(void* data, size_t bytes, const char* what) {
    if (!in_.read(static_cast<char*>(data), static_cast<std::streamsize>(bytes)))
        fail(std::string("truncated ") + what);
    hash_.add(data, bytes);
}

void FilmContainerReader::readSeal() {
    uint64_t stored = 0;
    if (!in_.read(reinterpret_cast<char*>(&stored), 8)) fail("truncated (no payload hash)");
    if (stored != hash_.h) fail("the payload's hash does not match (the file is corrupted)");
}

void FilmContainerReader::fail(const std::string& why) const {
    fail_(why);
    throw UserError(path_, 0, "", why);  // (a `fail` that returned)
}

}  // namespace tpb
