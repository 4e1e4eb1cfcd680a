// A cube map on the GPU: core's CubeMap (environment.h) uploaded with all its mips as RGB16F, read
// with seamless filtering across face edges (GL_TEXTURE_CUBE_MAP_SEAMLESS). Needs a current context.
#pragma once

#include <burnish/core/env/cube.h>
#include <burnish/core/env/storage.h>
#include <burnish/core/util/result.h>

#include <cstdint>

namespace burnish::render {

class CubeMapTexture {
public:
    CubeMapTexture() = default;
    ~CubeMapTexture();
    CubeMapTexture(CubeMapTexture&& other) noexcept;
    CubeMapTexture& operator=(CubeMapTexture&& other) noexcept;
    CubeMapTexture(const CubeMapTexture&) = delete;
    CubeMapTexture& operator=(const CubeMapTexture&) = delete;

    /// Uploads every level of `cube` (core's layout is GL's: face f is
    /// GL_TEXTURE_CUBE_MAP_POSITIVE_X + f, row j at t = (j + 0.5)/size) as RGB16F, trilinear over the
    /// uploaded chain (GL_TEXTURE_MAX_LEVEL = mips − 1, so a partial chain is complete). Texels above
    /// the half range are stored as kHalfMax and NaN or negative ones as 0 (counted in
    /// clampedTexels()), so no lookup returns Inf or NaN. Errors: an empty cube, a face size that is
    /// not a power of two or exceeds GL_MAX_CUBE_MAP_TEXTURE_SIZE, mis-sized levels.
    static Result<CubeMapTexture> create(const CubeMap& cube);

    unsigned id() const { return m_id; }
    bool valid() const { return m_id != 0; }
    int faceSize() const { return m_faceSize; }
    int mipCount() const { return m_mips; }
    /// Texel values changed on upload (above kHalfMax, negative or NaN), over all faces and mips.
    std::uint64_t clampedTexels() const { return m_clamped; }
    /// Binds to texture unit `unit` and turns GL_TEXTURE_CUBE_MAP_SEAMLESS on (a global switch the
    /// host may have left off).
    void bind(int unit) const;
    /// Reads level `level` back as stored (RGB floats, core's layout). Errors: level out of range.
    Result<CubeLevel> readLevel(int level) const;

private:
    void release();

    unsigned m_id = 0;
    int m_faceSize = 0;
    int m_mips = 0;
    std::uint64_t m_clamped = 0;
};

} // namespace burnish::render
