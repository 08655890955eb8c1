#include "io/image_io.h"

#include "io/atomic_file.h"
#include "base/error.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <half.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string_view>
#include <unistd.h>

#include <stb_image_write.h>

namespace tpb {

namespace fs = std::filesystem;

namespace {

// OpenEXR writes into memory first: its OutputFile destructor writes the line-offset table and
// swallows any error doing so, so writing straight to disk could leave a truncated file that
// looks finished. From memory, the bytes go through AtomicFile, which checks every write.
class MemoryOStream final : public Imf::OStream {
public:
    explicit MemoryOStream(const std::string& name) : Imf::OStream(name.c_str()) {}
    void write(const char c[], int n) override {
        const size_t end = pos_ + static_cast<size_t>(n);
        if (end > bytes_.size()) bytes_.resize(end);
        std::memcpy(bytes_.data() + pos_, c, static_cast<size_t>(n));
        pos_ = end;
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override { pos_ = static_cast<size_t>(pos); }
    std::string_view bytes() const { return {bytes_.data(), bytes_.size()}; }

private:
    std::vector<char> bytes_;
    size_t pos_ = 0;
};

}  // namespace

float linearToSrgb(float v) {
    if (!(v > 0.0f)) return 0.0f;
    if (v >= 1.0f) return 1.0f;
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

void ensureWritableDir(const std::string& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
        throw UserError(dir, 0, "",
                        "cannot create the output folder: " + (ec ? ec.message() : "not a folder") +
                            "; choose another folder with -o");
    if (::access(dir.c_str(), W_OK) != 0)
        throw UserError(dir, 0, "", "the output folder is not writable; choose another folder with -o");
}

int64_t writeExr(const std::string& path, int width, int height, const std::vector<float>& rgb, ExrPixel type) {
    TPB_CHECK(rgb.size() == static_cast<size_t>(width) * height * 3);
    // The film never holds NaN/Inf (film.cpp guards every sum): a non-finite texel here is a bug,
    // and it is refused rather than written.
    for (size_t i = 0; i < rgb.size(); ++i)
        if (!std::isfinite(rgb[i]))
            throw std::logic_error("internal error (bug): non-finite texel at pixel (" +
                                   std::to_string((i / 3) % width) + ", " + std::to_string(i / 3 / width) + ") for " +
                                   path + "; nothing was written");
    int64_t clamped = 0;
    MemoryOStream mem(path);
    try {
        Imf::Header header(width, height);
        const Imf::PixelType pt = type == ExrPixel::Half ? Imf::HALF : Imf::FLOAT;
        header.channels().insert("R", Imf::Channel(pt));
        header.channels().insert("G", Imf::Channel(pt));
        header.channels().insert("B", Imf::Channel(pt));
        Imf::FrameBuffer fb;
        std::vector<half> h;
        if (type == ExrPixel::Half) {
            h.resize(rgb.size());
            // Half holds at most 65504: larger values are clamped (and counted), never turned into Inf.
            constexpr float kHalfMax = 65504.0f;
            for (size_t i = 0; i < rgb.size(); ++i) {
                const float v = std::clamp(rgb[i], -kHalfMax, kHalfMax);
                clamped += v != rgb[i];
                h[i] = half(v);
            }
            char* base = reinterpret_cast<char*>(h.data());
            const size_t xs = 3 * sizeof(half), ys = xs * width;
            fb.insert("R", Imf::Slice(Imf::HALF, base, xs, ys));
            fb.insert("G", Imf::Slice(Imf::HALF, base + sizeof(half), xs, ys));
            fb.insert("B", Imf::Slice(Imf::HALF, base + 2 * sizeof(half), xs, ys));
        } else {
            char* base = const_cast<char*>(reinterpret_cast<const char*>(rgb.data()));
            const size_t xs = 3 * sizeof(float), ys = xs * width;
            fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
            fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
            fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
        }
        {
            Imf::OutputFile file(mem, header);
            file.setFrameBuffer(fb);
            file.writePixels(height);
        }
    } catch (const std::exception& e) {
        throw UserError(path, 0, "", std::string("cannot encode EXR: ") + e.what());
    }
    writeFileAtomic(path, mem.bytes());
    return clamped;
}

void readExr(const std::string& path, int& width, int& height, std::vector<float>& rgb) {
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        width = dw.max.x - dw.min.x + 1;
        height = dw.max.y - dw.min.y + 1;
        rgb.assign(static_cast<size_t>(width) * height * 3, 0.0f);
        char* base = reinterpret_cast<char*>(rgb.data()) -
                     (static_cast<ptrdiff_t>(dw.min.x) + static_cast<ptrdiff_t>(dw.min.y) * width) * 3 * sizeof(float);
        const size_t xs = 3 * sizeof(float), ys = xs * width;
        Imf::FrameBuffer fb;
        fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
        fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
        fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
    } catch (const std::exception& e) {
        throw UserError(path, 0, "", std::string("cannot read EXR: ") + e.what());
    }
}

void writePng8(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb) {
    TPB_CHECK(rgb.size() == static_cast<size_t>(width) * height * 3);
    // Encoded in memory (stbi_write_png does not check its fwrite), written through AtomicFile.
    std::string png;
    const auto append = [](void* ctx, void* data, int size) {
        static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), static_cast<size_t>(size));
    };
    if (!stbi_write_png_to_func(append, &png, width, height, 3, rgb.data(), width * 3))
        throw UserError(path, 0, "", "cannot encode PNG (out of memory)");
    writeFileAtomic(path, png);
}

void writePngPreview(const std::string& path, int width, int height, const std::vector<float>& rgb, double exposureEv) {
    const float scale = static_cast<float>(std::exp2(exposureEv));
    std::vector<unsigned char> px(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i)
        px[i] = static_cast<unsigned char>(std::lround(255.0f * linearToSrgb(rgb[i] * scale)));
    writePng8(path, width, height, px);
}

void writeTextFile(const std::string& path, const std::string& text) { writeFileAtomic(path, text); }

}  // namespace tpb
