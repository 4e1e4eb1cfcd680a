#include <burnish/render/cubemap.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace burnish::render {

namespace {

void drainGlErrors() {
    // Bounded: a lost context can report errors forever. 64 is far more than GL ever queues.
    for (int i = 0; i < 64 && glGetError() != GL_NO_ERROR; ++i) {
    }
}

} // namespace

CubeMapTexture::~CubeMapTexture() {
    release();
}

CubeMapTexture::CubeMapTexture(CubeMapTexture&& other) noexcept
    : m_id(std::exchange(other.m_id, 0))
    , m_faceSize(other.m_faceSize)
    , m_mips(other.m_mips)
    , m_clamped(other.m_clamped) {}

CubeMapTexture& CubeMapTexture::operator=(CubeMapTexture&& other) noexcept {
    if (this != &other) {
        release();
        m_id = std::exchange(other.m_id, 0);
        m_faceSize = other.m_faceSize;
        m_mips = other.m_mips;
        m_clamped = other.m_clamped;
    }
    return *this;
}

void CubeMapTexture::release() {
    if (m_id) glDeleteTextures(1, &m_id);
    m_id = 0;
}

Result<CubeMapTexture> CubeMapTexture::create(const CubeMap& cube) {
    if (cube.levels.empty()) return Error{"cube map: no levels"};
    const int size = cube.faceSize();
    if (!isPowerOfTwo(size))
        return Error{"cube map: face size " + std::to_string(size) + " is not a power of two"};
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_CUBE_MAP_TEXTURE_SIZE, &maxSize);
    if (size > maxSize)
        return Error{"cube map: face size " + std::to_string(size) + " exceeds the driver's " +
                     std::to_string(maxSize)};
    if (cube.mipCount() > fullMipCount(size))
        return Error{"cube map: " + std::to_string(cube.mipCount()) + " levels, a " + std::to_string(size) +
                     "² chain has " + std::to_string(fullMipCount(size))};
    for (int m = 0; m < cube.mipCount(); ++m) {
        const CubeLevel& level = cube.levels[size_t(m)];
        const int expected = std::max(size >> m, 1);
        if (level.size != expected)
            return Error{"cube map: level " + std::to_string(m) + " is " + std::to_string(level.size) +
                         "², expected " + std::to_string(expected) + "²"};
        for (const auto& face : level.faces)
            if (face.size() != size_t(expected) * size_t(expected) * 3)
                return Error{"cube map: level " + std::to_string(m) + " has a face of " +
                             std::to_string(face.size()) + " floats"};
    }

    drainGlErrors();
    GLint previousTexture = 0, previousAlignment = 4;
    glGetIntegerv(GL_TEXTURE_BINDING_CUBE_MAP, &previousTexture);
    glGetIntegerv(GL_UNPACK_ALIGNMENT, &previousAlignment);

    CubeMapTexture texture;
    texture.m_faceSize = size;
    texture.m_mips = cube.mipCount();
    glGenTextures(1, &texture.m_id);
    glBindTexture(GL_TEXTURE_CUBE_MAP, texture.m_id);
    // RGB rows of odd widths (the 1×1 level) are not 4-byte aligned.
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    std::vector<float> staged;
    for (int m = 0; m < cube.mipCount(); ++m) {
        const CubeLevel& level = cube.levels[size_t(m)];
        for (int f = 0; f < kCubeFaces; ++f) {
            staged = level.faces[size_t(f)];
            for (float& v : staged) {
                // RGB16F holds at most kHalfMax: a sun texel (1e5 and more) would become +Inf. NaN and
                // negative radiance have no meaning; core's import already maps them to 0.
                const float clamped = v > 0.0f ? std::min(v, kHalfMax) : 0.0f;
                if (clamped != v) ++texture.m_clamped;
                v = clamped;
            }
            glTexImage2D(GLenum(GL_TEXTURE_CUBE_MAP_POSITIVE_X + f), m, GL_RGB16F, level.size, level.size, 0,
                         GL_RGB, GL_FLOAT, staged.data());
        }
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, previousAlignment);
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_BASE_LEVEL, 0);
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAX_LEVEL, texture.m_mips - 1);
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
        glTexParameteri(GL_TEXTURE_CUBE_MAP, wrap, GL_CLAMP_TO_EDGE);
    glBindTexture(GL_TEXTURE_CUBE_MAP, GLuint(previousTexture));
    if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
        char code[16];
        std::snprintf(code, sizeof(code), "0x%04x", error);
        return Error{"cube map " + std::to_string(size) + "²: upload failed (GL error " + code + ")"};
    }
    return texture;
}

void CubeMapTexture::bind(int unit) const {
    // Filtering across face edges, as core's sampleCube does (a context-wide switch).
    glEnable(GL_TEXTURE_CUBE_MAP_SEAMLESS);
    glActiveTexture(GLenum(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_CUBE_MAP, m_id);
}

Result<CubeLevel> CubeMapTexture::readLevel(int level) const {
    if (!valid() || level < 0 || level >= m_mips)
        return Error{"cube map: level " + std::to_string(level) + " is outside 0.." +
                     std::to_string(m_mips - 1)};
    CubeLevel out;
    out.size = std::max(m_faceSize >> level, 1);
    GLint previousTexture = 0, previousAlignment = 4;
    glGetIntegerv(GL_TEXTURE_BINDING_CUBE_MAP, &previousTexture);
    glGetIntegerv(GL_PACK_ALIGNMENT, &previousAlignment);
    glBindTexture(GL_TEXTURE_CUBE_MAP, m_id);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    for (int f = 0; f < kCubeFaces; ++f) {
        out.faces[size_t(f)].assign(size_t(out.size) * size_t(out.size) * 3, 0.0f);
        glGetTexImage(GLenum(GL_TEXTURE_CUBE_MAP_POSITIVE_X + f), level, GL_RGB, GL_FLOAT,
                      out.faces[size_t(f)].data());
    }
    glPixelStorei(GL_PACK_ALIGNMENT, previousAlignment);
    glBindTexture(GL_TEXTURE_CUBE_MAP, GLuint(previousTexture));
    return out;
}

} // namespace burnish::render
