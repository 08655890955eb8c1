// Image output: OpenEXR (this file's .cpp is the only user of OpenEXR) and 8-bit PNG previews.
// Images are encoded in memory and written through AtomicFile (atomic_file.h): an interrupted or
// failed write (full disk, unwritable folder, Ctrl-C) never leaves a half file under the final
// name. Failures throw UserError naming the path and the system's reason.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace tpb {

enum class ExrPixel { Float, Half };

// rgb: width*height*3 floats, row-major from the top row, all finite (a NaN/Inf texel throws
// std::logic_error: the film never holds one, so it is a bug). Returns the number of values clamped
// to half's range (|v| <= 65504) when type is Half, 0 for Float.
int64_t writeExr(const std::string& path, int width, int height, const std::vector<float>& rgb,
                 ExrPixel type = ExrPixel::Float);
// Reads an RGB(A) EXR into rgb (width*height*3). Throws UserError on failure.
void readExr(const std::string& path, int& width, int& height, std::vector<float>& rgb);

// sRGB PNG of linear rgb * 2^exposure, clamped.
void writePngPreview(const std::string& path, int width, int height, const std::vector<float>& rgb,
                     double exposureEv = 0.0);
// Raw 8-bit RGB PNG (e.g. a screenshot).
void writePng8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb);

// Writes `text` to path atomically (tmp + rename). Throws UserError on failure.
void writeTextFile(const std::string& path, const std::string& text);
// Creates a folder (and parents); throws UserError if it cannot, or if it is not writable.
void ensureWritableDir(const std::string& dir);

// Linear -> sRGB-encoded [0,1].
float linearToSrgb(float v);

}  // namespace tpb
