#include "viewer/gl.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tpb::app {

namespace {

std::string readShader(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw std::runtime_error("cannot read shader " + path + " (is TPB_SHADER_DIR right?)");
    std::ostringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

GLuint compile(GLenum type, const std::string& src, const std::string& name) {
    const GLuint s = glCreateShader(type);
    const char* p = src.c_str();
    glShaderSource(s, 1, &p, nullptr);
    glCompileShader(s);
    GLint ok = GL_FALSE;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
        GLint len = 0;
        glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
        std::string log(static_cast<size_t>(std::max(len, 1)), '\0');
        glGetShaderInfoLog(s, len, nullptr, log.data());
        glDeleteShader(s);
        throw std::runtime_error("shader " + name + " does not compile:\n" + log);
    }
    return s;
}

// Saves and restores the GL state the display pass changes.
struct StateGuard {
    GLint fbo = 0, program = 0, vao = 0, tex = 0, active = 0, viewport[4] = {0, 0, 0, 0};
    GLboolean blend = GL_FALSE, scissor = GL_FALSE, depth = GL_FALSE;
    StateGuard() {
        glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &fbo);
        glGetIntegerv(GL_CURRENT_PROGRAM, &program);
        glGetIntegerv(GL_VERTEX_ARRAY_BINDING, &vao);
        glGetIntegerv(GL_ACTIVE_TEXTURE, &active);
        glActiveTexture(GL_TEXTURE0);
        glGetIntegerv(GL_TEXTURE_BINDING_2D, &tex);
        glGetIntegerv(GL_VIEWPORT, viewport);
        blend = glIsEnabled(GL_BLEND);
        scissor = glIsEnabled(GL_SCISSOR_TEST);
        depth = glIsEnabled(GL_DEPTH_TEST);
    }
    ~StateGuard() {
        glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(fbo));
        glUseProgram(static_cast<GLuint>(program));
        glBindVertexArray(static_cast<GLuint>(vao));
        glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(tex));
        glActiveTexture(static_cast<GLenum>(active));
        glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
        if (blend) glEnable(GL_BLEND);
        if (scissor) glEnable(GL_SCISSOR_TEST);
        if (depth) glEnable(GL_DEPTH_TEST);
    }
};

void setTextureParams(GLint filter) {
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

}  // namespace

// ---- DisplayImage ------------------------------------------------------------------------------

DisplayImage::~DisplayImage() { release(); }

void DisplayImage::release() {
    if (fbo_) glDeleteFramebuffers(1, &fbo_);
    if (raw_) glDeleteTextures(1, &raw_);
    if (out_) glDeleteTextures(1, &out_);
    fbo_ = raw_ = out_ = 0;
    width_ = height_ = 0;
}

void DisplayImage::upload(int width, int height, const float* rgb) {
    GLint prevTex = 0, prevFbo = 0;
    glGetIntegerv(GL_TEXTURE_BINDING_2D, &prevTex);
    glGetIntegerv(GL_FRAMEBUFFER_BINDING, &prevFbo);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    if (width != width_ || height != height_ || !raw_) {
        release();
        width_ = width;
        height_ = height;
        glGenTextures(1, &raw_);
        glBindTexture(GL_TEXTURE_2D, raw_);
        setTextureParams(GL_NEAREST);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, width, height, 0, GL_RGB, GL_FLOAT, rgb);
        glGenTextures(1, &out_);
        glBindTexture(GL_TEXTURE_2D, out_);
        setTextureParams(GL_NEAREST);  // magnified pixels stay crisp
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        glGenFramebuffers(1, &fbo_);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, out_, 0);
        const GLenum st = glCheckFramebufferStatus(GL_FRAMEBUFFER);
        glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(prevFbo));
        if (st != GL_FRAMEBUFFER_COMPLETE) {
            glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(prevTex));
            release();
            throw std::runtime_error("OpenGL: display framebuffer incomplete");
        }
    } else {
        glBindTexture(GL_TEXTURE_2D, raw_);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGB, GL_FLOAT, rgb);
    }
    glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(prevTex));
}

// ---- DisplayProgram ----------------------------------------------------------------------------

DisplayProgram::~DisplayProgram() {
    if (program_) glDeleteProgram(program_);
    if (vao_) glDeleteVertexArrays(1, &vao_);
}

void DisplayProgram::load(const std::string& dir) {
    const GLuint vs = compile(GL_VERTEX_SHADER, readShader(dir + "/display.vert"), "display.vert");
    GLuint fs = 0;
    try {
        fs = compile(GL_FRAGMENT_SHADER, readShader(dir + "/display.frag"), "display.frag");
    } catch (...) {
        glDeleteShader(vs);
        throw;
    }
    const GLuint prog = glCreateProgram();
    glAttachShader(prog, vs);
    glAttachShader(prog, fs);
    glLinkProgram(prog);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = GL_FALSE;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE) {
        GLint len = 0;
        glGetProgramiv(prog, GL_INFO_LOG_LENGTH, &len);
        std::string log(static_cast<size_t>(std::max(len, 1)), '\0');
        glGetProgramInfoLog(prog, len, nullptr, log.data());
        glDeleteProgram(prog);
        throw std::runtime_error("display shaders do not link:\n" + log);
    }
    if (program_) glDeleteProgram(program_);
    program_ = prog;
    uImage_ = glGetUniformLocation(prog, "uImage");
    uScale_ = glGetUniformLocation(prog, "uScale");
    uSrgb_ = glGetUniformLocation(prog, "uSrgb");
    uFalseColor_ = glGetUniformLocation(prog, "uFalseColor");
    uDecades_ = glGetUniformLocation(prog, "uDecades");
    if (!vao_) glGenVertexArrays(1, &vao_);  // core profile: a draw needs a bound VAO
}

void DisplayProgram::apply(DisplayImage& img, const DisplayParams& p) const {
    if (img.empty() || !program_) return;
    StateGuard guard;
    glBindFramebuffer(GL_FRAMEBUFFER, img.fbo_);
    glViewport(0, 0, img.width_, img.height_);
    glDisable(GL_BLEND);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_DEPTH_TEST);
    glUseProgram(program_);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, img.raw_);
    glUniform1i(uImage_, 0);
    glUniform1f(uScale_, std::exp2(p.exposureEv));
    glUniform1i(uSrgb_, p.srgb ? 1 : 0);
    glUniform1i(uFalseColor_, p.falseColor ? 1 : 0);
    glUniform1f(uDecades_, p.decades);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
}

int maxTextureSize() {
    GLint n = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &n);
    return n;
}

std::vector<unsigned char> readBackBuffer(int width, int height) {
    std::vector<unsigned char> flipped(static_cast<size_t>(width) * height * 3);
    if (width <= 0 || height <= 0) return flipped;
    std::vector<unsigned char> px(flipped.size());
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, px.data());
    const size_t row = static_cast<size_t>(width) * 3;
    for (int y = 0; y < height; ++y)
        std::memcpy(&flipped[static_cast<size_t>(y) * row], &px[static_cast<size_t>(height - 1 - y) * row], row);
    return flipped;
}

}  // namespace tpb::app
