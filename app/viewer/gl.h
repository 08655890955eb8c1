// OpenGL side of the viewer: the display shader (shaders/display.*, loaded at run time), the
// images it maps (raw linear float texture in, 8-bit display texture out, drawn by ImGui) and the
// back-buffer read for screenshots. Only the UI thread calls into this file.
#pragma once
#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1  // Mesa/glvnd's libGL exports the GL 3.3 core entry points
#endif
#include <GL/gl.h>
#include <GL/glext.h>

#include "film/tone_map.h"

#include <string>
#include <vector>

namespace tpb::app {

// Exposure, sRGB, false colour: the CPU tone map's parameters (core/film/tone_map.h), applied by
// the shader (shaders/display.frag) the same way.
using DisplayParams = ToneMap;

// A film-sized image: raw linear RGB floats (GL_RGB32F) and the display-mapped result (RGBA8,
// rendered through an FBO, one fragment per pixel). texture() is what ImGui::Image draws.
class DisplayImage {
public:
    DisplayImage() = default;
    DisplayImage(const DisplayImage&) = delete;
    DisplayImage& operator=(const DisplayImage&) = delete;
    ~DisplayImage();

    // rgb: width*height*3 linear floats, row 0 = top row of the picture.
    void upload(int width, int height, const float* rgb);
    int width() const { return width_; }
    int height() const { return height_; }
    bool empty() const { return width_ == 0 || height_ == 0; }
    GLuint texture() const { return out_; }

private:
    friend class DisplayProgram;
    void release();
    GLuint raw_ = 0, out_ = 0, fbo_ = 0;
    int width_ = 0, height_ = 0;
};

class DisplayProgram {
public:
    DisplayProgram() = default;
    DisplayProgram(const DisplayProgram&) = delete;
    DisplayProgram& operator=(const DisplayProgram&) = delete;
    ~DisplayProgram();

    // Compiles <dir>/display.vert + display.frag. Throws std::runtime_error (missing file, compile
    // or link log).
    void load(const std::string& shaderDir);
    // Maps img's raw texture into its display texture. Restores the viewport and framebuffer.
    void apply(DisplayImage& img, const DisplayParams& p) const;

private:
    GLuint program_ = 0, vao_ = 0;
    GLint uImage_ = -1, uScale_ = -1, uSrgb_ = -1, uFalseColor_ = -1, uDecades_ = -1;
};

int maxTextureSize();

// The current framebuffer's back buffer as 8-bit RGB, top row first (flipped from GL's order).
std::vector<unsigned char> readBackBuffer(int width, int height);

}  // namespace tpb::app
