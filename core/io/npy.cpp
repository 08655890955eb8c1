#include "io/npy.h"

#include "base/error.h"

#include <bit>

namespace tpb {

static_assert(std::endian::native == std::endian::little, "the .npy writer writes the host's floats as '<f4'");

uint64_t npyCount(const std::vector<int64_t>& shape) {
    uint64_t n = 1;
    for (int64_t d : shape) {
        TPB_CHECK(d >= 0);
        n *= static_cast<uint64_t>(d);
    }
    return n;
}

std::string npyHeader(const std::vector<int64_t>& shape) {
    std::string dims;
    for (size_t i = 0; i < shape.size(); ++i) dims += (i ? ", " : "") + std::to_string(shape[i]);
    if (shape.size() == 1) dims += ",";  // a Python 1-tuple
    std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + dims + "), }";
    // magic (6) + version (2) + header length (2) + dict + padding + '\n': a multiple of 64.
    const size_t unpadded = 10 + dict.size() + 1;
    dict.append((64 - unpadded % 64) % 64, ' ');
    dict += '\n';
    TPB_CHECK(dict.size() <= 65535);
    std::string out = "\x93NUMPY";
    out += '\x01';
    out += '\x00';
    out += static_cast<char>(dict.size() & 0xff);
    out += static_cast<char>(dict.size() >> 8);
    return out + dict;
}

NpyWriter::NpyWriter(const std::string& path, std::vector<int64_t> shape) : file_(path), shape_(std::move(shape)) {
    file_.write(npyHeader(shape_));
}

void NpyWriter::write(const float* values, size_t count) {
    file_.write(values, count * sizeof(float));
    written_ += count;
}

void NpyWriter::commit() {
    TPB_CHECK(written_ == npyCount(shape_));
    file_.commit();
}

void writeNpy(const std::string& path, const std::vector<int64_t>& shape, const std::vector<float>& values) {
    NpyWriter w(path, shape);
    w.write(values.data(), values.size());
    w.commit();
}

}  // namespace tpb
