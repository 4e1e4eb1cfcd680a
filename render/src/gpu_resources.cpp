#include <burnish/render/gpu_resources.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>

namespace burnish::render {

namespace {

GLenum internalFormat(ColorFormat format) {
    switch (format) {
    case ColorFormat::Rgba8:
        return GL_RGBA8;
    case ColorFormat::Rgba16f:
        return GL_RGBA16F;
    case ColorFormat::Rgba32f:
        return GL_RGBA32F;
    }
    return GL_RGBA8;
}

std::string framebufferStatusName(GLenum status) {
    switch (status) {
    case GL_FRAMEBUFFER_UNDEFINED:
        return "GL_FRAMEBUFFER_UNDEFINED";
    case GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT:
        return "GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT";
    case GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT:
        return "GL_FRAMEBUFFER_INCOMPLETE_MISSING_ATTACHMENT";
    case GL_FRAMEBUFFER_UNSUPPORTED:
        return "GL_FRAMEBUFFER_UNSUPPORTED";
    case GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE:
        return "GL_FRAMEBUFFER_INCOMPLETE_MULTISAMPLE";
    default:
        return "status " + std::to_string(status);
    }
}

void drainGlErrors() {
    // Bounded: a lost context can report errors forever. 64 is far more than GL ever queues.
    for (int i = 0; i < 64 && glGetError() != GL_NO_ERROR; ++i) {
    }
}

// Restores the framebuffer bindings on scope exit: the host's (the studio's) framebuffer stays bound.
class FramebufferBindingGuard {
public:
    FramebufferBindingGuard() {
        glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &m_draw);
        glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &m_read);
    }
    ~FramebufferBindingGuard() {
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, GLuint(m_draw));
        glBindFramebuffer(GL_READ_FRAMEBUFFER, GLuint(m_read));
    }
    FramebufferBindingGuard(const FramebufferBindingGuard&) = delete;
    FramebufferBindingGuard& operator=(const FramebufferBindingGuard&) = delete;

private:
    GLint m_draw = 0;
    GLint m_read = 0;
};

// Rows of `rowBytes` bytes, bottom-up as GL returns them, reordered top-down in place.
void flipRows(void* data, size_t rowBytes, int rows) {
    auto* bytes = static_cast<unsigned char*>(data);
    std::vector<unsigned char> scratch(rowBytes);
    for (int top = 0, bottom = rows - 1; top < bottom; ++top, --bottom) {
        unsigned char* a = bytes + size_t(top) * rowBytes;
        unsigned char* b = bytes + size_t(bottom) * rowBytes;
        std::memcpy(scratch.data(), a, rowBytes);
        std::memcpy(a, b, rowBytes);
        std::memcpy(b, scratch.data(), rowBytes);
    }
}

} // namespace

// ---------------------------------------------------------------------------------------------
// Framebuffer

Framebuffer::~Framebuffer() {
    release();
}

void Framebuffer::release() {
    if (m_fbo) glDeleteFramebuffers(1, &m_fbo);
    if (m_resolveFbo) glDeleteFramebuffers(1, &m_resolveFbo);
    if (m_samples > 1) {
        if (m_color) glDeleteRenderbuffers(1, &m_color);
    } else if (m_color) {
        glDeleteTextures(1, &m_color);
    }
    if (m_resolveColor) glDeleteTextures(1, &m_resolveColor);
    if (m_depth) glDeleteRenderbuffers(1, &m_depth);
    m_fbo = m_color = m_depth = m_resolveFbo = m_resolveColor = 0;
}

Framebuffer::Framebuffer(Framebuffer&& other) noexcept {
    *this = std::move(other);
}

Framebuffer& Framebuffer::operator=(Framebuffer&& other) noexcept {
    if (this != &other) {
        release();
        m_width = std::exchange(other.m_width, 0);
        m_height = std::exchange(other.m_height, 0);
        m_format = other.m_format;
        m_samples = std::exchange(other.m_samples, 1);
        m_fbo = std::exchange(other.m_fbo, 0u);
        m_color = std::exchange(other.m_color, 0u);
        m_depth = std::exchange(other.m_depth, 0u);
        m_resolveFbo = std::exchange(other.m_resolveFbo, 0u);
        m_resolveColor = std::exchange(other.m_resolveColor, 0u);
    }
    return *this;
}

Result<Framebuffer> Framebuffer::create(int width, int height, ColorFormat format, bool depth, int samples) {
    GLint maxRenderbuffer = 0;
    GLint maxTexture = 0;
    GLint maxSamples = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &maxRenderbuffer);
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxTexture);
    glGetIntegerv(GL_MAX_SAMPLES, &maxSamples);
    const int maxSize = std::min(maxRenderbuffer, maxTexture);
    if (width <= 0 || height <= 0 || width > maxSize || height > maxSize) {
        return Error{"framebuffer size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1.." + std::to_string(maxSize)};
    }
    if (samples < 1 || samples > std::max(maxSamples, 1)) {
        return Error{"framebuffer samples " + std::to_string(samples) + " is outside 1.." +
                     std::to_string(std::max(maxSamples, 1))};
    }
    drainGlErrors();
    FramebufferBindingGuard bindingGuard;
    GLint previousTexture = 0;
    glGetIntegerv(GL_TEXTURE_BINDING_2D, &previousTexture);

    Framebuffer fb;
    fb.m_width = width;
    fb.m_height = height;
    fb.m_format = format;
    fb.m_samples = samples;
    const GLenum internal = internalFormat(format);

    // A colour texture that can be sampled: the target itself, or the resolve target of an MSAA one.
    auto makeColorTexture = [&](GLuint& texture) {
        glGenTextures(1, &texture);
        glBindTexture(GL_TEXTURE_2D, texture);
        glTexImage2D(GL_TEXTURE_2D, 0, GLint(internal), width, height, 0, GL_RGBA, GL_FLOAT, nullptr);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    };

    glGenFramebuffers(1, &fb.m_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fb.m_fbo);
    if (samples > 1) {
        glGenRenderbuffers(1, &fb.m_color);
        glBindRenderbuffer(GL_RENDERBUFFER, fb.m_color);
        glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, internal, width, height);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, fb.m_color);
    } else {
        makeColorTexture(fb.m_color);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, fb.m_color, 0);
    }
    if (depth) {
        glGenRenderbuffers(1, &fb.m_depth);
        glBindRenderbuffer(GL_RENDERBUFFER, fb.m_depth);
        glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples > 1 ? samples : 0, GL_DEPTH_COMPONENT24,
                                         width, height);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, fb.m_depth);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, 0);
    GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status == GL_FRAMEBUFFER_COMPLETE && samples > 1) {
        makeColorTexture(fb.m_resolveColor);
        glGenFramebuffers(1, &fb.m_resolveFbo);
        glBindFramebuffer(GL_FRAMEBUFFER, fb.m_resolveFbo);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, fb.m_resolveColor, 0);
        status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    }
    glBindTexture(GL_TEXTURE_2D, GLuint(previousTexture));
    if (const GLenum error = glGetError(); error == GL_OUT_OF_MEMORY) {
        return Error{"framebuffer " + std::to_string(width) + "x" + std::to_string(height) +
                     ": out of GPU memory"};
    }
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        return Error{"framebuffer " + std::to_string(width) + "x" + std::to_string(height) +
                     " is incomplete: " + framebufferStatusName(status)};
    }
    return fb;
}

void Framebuffer::bind() const {
    glBindFramebuffer(GL_FRAMEBUFFER, m_fbo);
    glViewport(0, 0, m_width, m_height);
}

void Framebuffer::resolve() const {
    if (m_samples <= 1 || !m_fbo) return;
    FramebufferBindingGuard bindingGuard;
    glBindFramebuffer(GL_READ_FRAMEBUFFER, m_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, m_resolveFbo);
    // A multisample resolve blit must be 1:1 and nearest (the average of the samples per pixel).
    glBlitFramebuffer(0, 0, m_width, m_height, 0, 0, m_width, m_height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
}

unsigned Framebuffer::colorTexture() const {
    return m_samples > 1 ? m_resolveColor : m_color;
}

namespace {

template <class T> std::vector<T> readPixels(unsigned fbo, int width, int height, GLenum type) {
    std::vector<T> pixels(size_t(width) * size_t(height) * 4);
    if (pixels.empty()) return pixels;
    FramebufferBindingGuard bindingGuard;
    GLint previousAlignment = 4;
    glGetIntegerv(GL_PACK_ALIGNMENT, &previousAlignment);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGBA, type, pixels.data());
    glPixelStorei(GL_PACK_ALIGNMENT, previousAlignment);
    flipRows(pixels.data(), size_t(width) * 4 * sizeof(T), height);
    return pixels;
}

} // namespace

std::vector<float> Framebuffer::readRgbaFloat() const {
    resolve();
    return readPixels<float>(m_samples > 1 ? m_resolveFbo : m_fbo, m_width, m_height, GL_FLOAT);
}

std::vector<std::uint8_t> Framebuffer::readRgba8() const {
    resolve();
    return readPixels<std::uint8_t>(m_samples > 1 ? m_resolveFbo : m_fbo, m_width, m_height,
                                    GL_UNSIGNED_BYTE);
}

// ---------------------------------------------------------------------------------------------
// Texture2D

Texture2D::~Texture2D() {
    if (m_id) glDeleteTextures(1, &m_id);
}

Texture2D::Texture2D(Texture2D&& other) noexcept
    : m_id(std::exchange(other.m_id, 0u))
    , m_width(std::exchange(other.m_width, 0))
    , m_height(std::exchange(other.m_height, 0))
    , m_levels(std::exchange(other.m_levels, 0))
    , m_channels(std::exchange(other.m_channels, 0))
    , m_half(std::exchange(other.m_half, false)) {}

Texture2D& Texture2D::operator=(Texture2D&& other) noexcept {
    if (this != &other) {
        if (m_id) glDeleteTextures(1, &m_id);
        m_id = std::exchange(other.m_id, 0u);
        m_width = std::exchange(other.m_width, 0);
        m_height = std::exchange(other.m_height, 0);
        m_levels = std::exchange(other.m_levels, 0);
        m_channels = std::exchange(other.m_channels, 0);
        m_half = std::exchange(other.m_half, false);
    }
    return *this;
}

Result<Texture2D> Texture2D::create(const std::vector<TextureLevel>& levels, int channels,
                                    TextureFilter filter, bool wrapRepeat, bool half) {
    if (levels.empty()) return Error{"texture: no levels given"};
    if (channels < 1 || channels > 4) {
        return Error{"texture: " + std::to_string(channels) + " channels (1 to 4 are supported)"};
    }
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxSize);
    const int width = levels[0].width;
    const int height = levels[0].height;
    if (width <= 0 || height <= 0 || width > maxSize || height > maxSize) {
        return Error{"texture size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside 1.." + std::to_string(maxSize)};
    }
    // The full chain: down to 1×1, each level ⌊w/2⌋×⌊h/2⌋ (at least 1).
    const int chainLength = int(std::floor(std::log2(double(std::max(width, height))))) + 1;
    if (int(levels.size()) > chainLength) {
        return Error{"texture: " + std::to_string(levels.size()) + " levels given, a " +
                     std::to_string(width) + "x" + std::to_string(height) + " chain has " +
                     std::to_string(chainLength)};
    }
    // Largest finite half float: larger texels would turn into Inf on upload.
    constexpr float kHalfMax = 65504.0f;
    int expectedWidth = width;
    int expectedHeight = height;
    for (size_t i = 0; i < levels.size(); ++i) {
        const TextureLevel& level = levels[i];
        const std::string which = "texture level " + std::to_string(i);
        if (level.width != expectedWidth || level.height != expectedHeight) {
            return Error{which + " is " + std::to_string(level.width) + "x" + std::to_string(level.height) +
                         ", expected " + std::to_string(expectedWidth) + "x" +
                         std::to_string(expectedHeight)};
        }
        const size_t expectedCount = size_t(level.width) * size_t(level.height) * size_t(channels);
        if (level.texels.size() != expectedCount) {
            return Error{which + " has " + std::to_string(level.texels.size()) + " floats, expected " +
                         std::to_string(expectedCount)};
        }
        for (const float texel : level.texels) {
            if (!std::isfinite(texel)) return Error{which + " has a non-finite texel"};
            if (half && std::abs(texel) > kHalfMax) {
                return Error{which + " has a texel beyond the half-float range (" + std::to_string(texel) +
                             ")"};
            }
        }
        expectedWidth = std::max(1, expectedWidth / 2);
        expectedHeight = std::max(1, expectedHeight / 2);
    }

    static constexpr GLenum kFormats[] = {GL_RED, GL_RG, GL_RGB, GL_RGBA};
    static constexpr GLenum kFloat32[] = {GL_R32F, GL_RG32F, GL_RGB32F, GL_RGBA32F};
    static constexpr GLenum kFloat16[] = {GL_R16F, GL_RG16F, GL_RGB16F, GL_RGBA16F};
    const GLenum format = kFormats[channels - 1];
    const GLenum internal = half ? kFloat16[channels - 1] : kFloat32[channels - 1];

    drainGlErrors();
    GLint previousTexture = 0;
    GLint previousAlignment = 4;
    glGetIntegerv(GL_TEXTURE_BINDING_2D, &previousTexture);
    glGetIntegerv(GL_UNPACK_ALIGNMENT, &previousAlignment);

    Texture2D texture;
    texture.m_width = width;
    texture.m_height = height;
    texture.m_channels = channels;
    texture.m_half = half;
    glGenTextures(1, &texture.m_id);
    glBindTexture(GL_TEXTURE_2D, texture.m_id);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    std::vector<float> flipped;
    for (size_t i = 0; i < levels.size(); ++i) {
        const TextureLevel& level = levels[i];
        // Image row 0 (the top) goes to the top of the texture, v = 1: GL's first row is v = 0.
        const float* rows = level.texels.data();
        if (!level.bottomFirst) {
            flipped = level.texels;
            flipRows(flipped.data(), size_t(level.width) * size_t(channels) * sizeof(float), level.height);
            rows = flipped.data();
        }
        glTexImage2D(GL_TEXTURE_2D, GLint(i), GLint(internal), level.width, level.height, 0, format, GL_FLOAT,
                     rows);
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, previousAlignment);

    const bool generate = filter == TextureFilter::LinearMipLinear && levels.size() == 1;
    texture.m_levels = generate ? chainLength : int(levels.size());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 0);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, texture.m_levels - 1);
    if (generate) glGenerateMipmap(GL_TEXTURE_2D);
    const GLint minFilter = filter == TextureFilter::Nearest  ? GL_NEAREST
                            : filter == TextureFilter::Linear ? GL_LINEAR
                                                              : GL_LINEAR_MIPMAP_LINEAR;
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, minFilter);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER,
                    filter == TextureFilter::Nearest ? GL_NEAREST : GL_LINEAR);
    const GLint wrap = wrapRepeat ? GL_REPEAT : GL_CLAMP_TO_EDGE;
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrap);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrap);
    // Anisotropic filtering off (1 = isotropic): the methods under test are measured against
    // trilinear filtering, and the driver default must not change the result.
    if (epoxy_gl_version() >= 46 || epoxy_has_gl_extension("GL_EXT_texture_filter_anisotropic") ||
        epoxy_has_gl_extension("GL_ARB_texture_filter_anisotropic")) {
        glTexParameterf(GL_TEXTURE_2D, GL_TEXTURE_MAX_ANISOTROPY_EXT, 1.0f);
    }
    glBindTexture(GL_TEXTURE_2D, GLuint(previousTexture));
    if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
        char code[16];
        std::snprintf(code, sizeof(code), "0x%04x", error);
        return Error{"texture " + std::to_string(width) + "x" + std::to_string(height) +
                     ": upload failed (GL error " + code + ")"};
    }
    return texture;
}

Status Texture2D::updateRegion(int level, int x, int y, int width, int height,
                               const std::vector<float>& texels) {
    if (!m_id) return Error{"texture update: no texture"};
    if (level < 0 || level >= m_levels)
        return Error{"texture update: level " + std::to_string(level) + " outside 0.." +
                     std::to_string(m_levels - 1)};
    const int levelWidth = std::max(1, m_width >> level), levelHeight = std::max(1, m_height >> level);
    if (width <= 0 || height <= 0 || x < 0 || y < 0 || x + width > levelWidth || y + height > levelHeight)
        return Error{"texture update: rectangle " + std::to_string(x) + "," + std::to_string(y) + " " +
                     std::to_string(width) + "x" + std::to_string(height) + " outside level " +
                     std::to_string(level) + "'s " + std::to_string(levelWidth) + "x" +
                     std::to_string(levelHeight)};
    const size_t row = size_t(width) * size_t(m_channels);
    if (texels.size() != row * size_t(height))
        return Error{"texture update: " + std::to_string(texels.size()) + " floats for " +
                     std::to_string(width) + "x" + std::to_string(height) + " texels of " +
                     std::to_string(m_channels) + " channels"};
    constexpr float kHalfMax = 65504.0f;
    for (const float t : texels)
        if (!std::isfinite(t) || (m_half && std::abs(t) > kHalfMax))
            return Error{"texture update: a texel is non-finite or beyond the storage's range"};
    // Image rows top first; GL's rows bottom first: the rectangle's bottom row goes first, at
    // GL row levelHeight - (y + height).
    std::vector<float> flipped(texels);
    flipRows(flipped.data(), row * sizeof(float), height);
    static constexpr GLenum kFormats[] = {GL_RED, GL_RG, GL_RGB, GL_RGBA};
    drainGlErrors();
    GLint previousTexture = 0;
    GLint previousAlignment = 4;
    glGetIntegerv(GL_TEXTURE_BINDING_2D, &previousTexture);
    glGetIntegerv(GL_UNPACK_ALIGNMENT, &previousAlignment);
    glBindTexture(GL_TEXTURE_2D, m_id);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexSubImage2D(GL_TEXTURE_2D, level, x, levelHeight - (y + height), width, height,
                    kFormats[m_channels - 1], GL_FLOAT, flipped.data());
    glPixelStorei(GL_UNPACK_ALIGNMENT, previousAlignment);
    glBindTexture(GL_TEXTURE_2D, GLuint(previousTexture));
    if (const GLenum error = glGetError(); error != GL_NO_ERROR)
        return Error{"texture update: GL error " + std::to_string(unsigned(error))};
    return {};
}

void Texture2D::bind(int unit) const {
    glActiveTexture(GLenum(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_2D, m_id);
}

// ---------------------------------------------------------------------------------------------
// FullscreenTriangle

FullscreenTriangle::FullscreenTriangle() {
    glGenVertexArrays(1, &m_vao);
}

FullscreenTriangle::~FullscreenTriangle() {
    if (m_vao) glDeleteVertexArrays(1, &m_vao);
}

void FullscreenTriangle::draw() const {
    glBindVertexArray(m_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
}

} // namespace burnish::render
