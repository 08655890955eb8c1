// NumPy's .npy format, version 1.0, for float32 arrays in C order: what `numpy.load` reads as it
// is (https://numpy.org/doc/stable/reference/generated/numpy.lib.format.html). A file is the magic
// "\x93NUMPY", the version bytes 1 0, the header's length (uint16, little-endian), the header -
// the Python dict literal "{'descr': '<f4', 'fortran_order': False, 'shape': (H, W, B, 3), }"
// padded with spaces and ended by '\n' so that the data starts at a multiple of 64 bytes - then
// the values, little-endian float32, last index fastest.
//
// NpyWriter streams the values (a 12 GiB film is never copied whole) through AtomicFile: the file
// appears under its name only when every value announced by the shape was written.
#pragma once
#include "io/atomic_file.h"

#include <cstdint>
#include <string>
#include <vector>

namespace tpb {

// The magic, version, length and padded header for a float32 C-order array of this shape.
std::string npyHeader(const std::vector<int64_t>& shape);
// Number of values an array of this shape holds (1 for the empty shape, a scalar).
uint64_t npyCount(const std::vector<int64_t>& shape);

class NpyWriter {
public:
    // Creates <path>.tmp-<pid> and writes the header. Throws UserError (atomic_file.h) on failure.
    NpyWriter(const std::string& path, std::vector<int64_t> shape);
    // Appends `count` values (in C order, continuing where the last call stopped).
    void write(const float* values, size_t count);
    // Renames the file into place; a TPB_CHECK failure (a bug) when fewer or more values than the
    // shape holds were written. Without commit() nothing is left (the destructor removes it).
    void commit();
    uint64_t valuesWritten() const { return written_; }

private:
    AtomicFile file_;
    std::vector<int64_t> shape_;
    uint64_t written_ = 0;
};

// One-shot form: `values` holds npyCount(shape) floats.
void writeNpy(const std::string& path, const std::vector<int64_t>& shape, const std::vector<float>& values);

}  // namespace tpb
