#include <burnish/core/bake/detail.h>

#include <burnish/core/io/dds.h>
#include <burnish/core/prefilter/gloss.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace burnish {

glm::vec3 reorientedBlend(const glm::vec3& base, const glm::vec3& detail) {
    const glm::dvec3 t(base.x, base.y, double(base.z) + 1.0);
    const glm::dvec3 u(-double(detail.x), -double(detail.y), detail.z);
    // t.z = base.z + 1 >= 1 for a base facing +z; a base at or below the horizon has no frame to
    // rotate into, so the detail is returned unchanged there.
    if (!(t.z > 1e-6)) return glm::normalize(detail);
    const glm::dvec3 r = t * (glm::dot(t, u) / t.z) - u;
    const double len = glm::length(r);
    return len > 0.0 && std::isfinite(len) ? glm::vec3(r / len) : base;
}

double addVarianceToPower(double s, double sigma2) {
    const double v = varianceFromPower(s, VarianceConvention::InversePower) + (sigma2 > 0.0 ? sigma2 : 0.0);
    return powerFromVariance(v, VarianceConvention::InversePower);
}

namespace {

// What bakeDetail refuses in its options alone.
Status checkDetailOptions(const DetailOptions& options) {
    if (options.fadeStartMip < 0 || options.fadeEndMip < options.fadeStartMip)
        return Error{"detail fade mips must satisfy 0 <= start <= end (got " +
                     std::to_string(options.fadeStartMip) + ".." + std::to_string(options.fadeEndMip) + ")"};
    if (options.mipCount < 0)
        return Error{"detail mip count must be 0 (all) or positive (got " + std::to_string(options.mipCount) +
                     ")"};
    return {};
}

// The variance channel's binary scale for the largest variance stored (at least 2^-10).
double varianceScale(double maxVariance) {
    return std::exp2(std::ceil(std::log2(std::max(maxVariance, 1.0 / 1024.0))));
}

// The detail texture's description and decodes, without mips.
BakedTexture detailTexture(double constantVariance, double scale) {
    BakedTexture tex;
    tex.role = TextureRole::Detail;
    tex.description = "detail normal [x, y, 0, variance]; blend with reoriented normal mapping and use "
                      "1/s' = 1/s + variance; constant variance beyond the fade: " +
                      std::to_string(constantVariance);
    tex.decode = textureDecode(TextureRole::Detail, {1.0, 1.0, scale});
    tex.channels = int(tex.decode.size());
    tex.needsHighPrecision = textureSpec(TextureRole::Detail).needsHighPrecision;
    return tex;
}

} // namespace

Result<DetailBake> bakeDetail(const NormalMap& detail, const DetailOptions& options) {
    if (detail.texelCount() == 0) return Error{"the detail normal map is empty"};
    if (const Status s = checkDetailOptions(options); !s) return Error{s.error()};
    const std::shared_ptr<const NormalMap> borrowed(&detail, [](const NormalMap*) {});
    const NormalPyramid pyramid = NormalPyramid::build(borrowed, options.pyramid);
    const int levels = pyramid.levelCount();

    DetailBake out;
    const NormalMoments total = pyramid.boxMoments(levels - 1, 0, 0);
    out.constantVariance = toksvigVariance(total.lengthNa());

    // The variance channel's binary scale: filtered variances never exceed the largest box one
    // by much, so bound it by the maximum over the levels actually stored.
    std::vector<std::vector<float>> variance(static_cast<size_t>(levels));
    std::vector<std::vector<glm::vec2>> xy(static_cast<size_t>(levels));
    double maxVariance = out.constantVariance;
    for (int k = 0; k < levels; ++k) {
        const PyramidLevel& level = pyramid.level(k);
        variance[size_t(k)].resize(size_t(level.width) * size_t(level.height));
        xy[size_t(k)].resize(variance[size_t(k)].size());
        // Fade weight: 0 keeps the map's own values, 1 is fully faded to flat + constant variance.
        const double fade = options.fadeEndMip == options.fadeStartMip
                                ? (k >= options.fadeEndMip ? 1.0 : 0.0)
                                : std::clamp(double(k - options.fadeStartMip) /
                                                 double(options.fadeEndMip - options.fadeStartMip),
                                             0.0, 1.0);
        pyramid.forEachMomentRow(k, [&](int y, const NormalMoments* row) {
            for (int x = 0; x < level.width; ++x) {
                const size_t t = size_t(y) * size_t(level.width) + size_t(x);
                const glm::vec3 n = row[x].meanDirection();
                const double v = toksvigVariance(row[x].lengthNa());
                xy[size_t(k)][t] = glm::vec2(float((1.0 - fade) * n.x), float((1.0 - fade) * n.y));
                variance[size_t(k)][t] = float((1.0 - fade) * v + fade * out.constantVariance);
            }
        });
        for (float v : variance[size_t(k)])
            maxVariance = std::max(maxVariance, double(v));
    }
    const double scale = varianceScale(maxVariance);

    out.texture = detailTexture(out.constantVariance, scale);
    BakedTexture& tex = out.texture;
    // Every level above shaped the variance scale, so a short chain is a prefix of the full one.
    const int stored = options.mipCount > 0 ? std::min(options.mipCount, levels) : levels;
    tex.mips.resize(size_t(stored));
    for (int k = 0; k < stored; ++k) {
        TextureMip& mip = tex.mips[size_t(k)];
        mip.width = pyramid.level(k).width;
        mip.height = pyramid.level(k).height;
        mip.texels.resize(variance[size_t(k)].size() * 4);
        for (size_t t = 0; t < variance[size_t(k)].size(); ++t) {
            mip.texels[4 * t + 0] = std::clamp(0.5f * xy[size_t(k)][t].x + 0.5f, 0.0f, 1.0f);
            mip.texels[4 * t + 1] = std::clamp(0.5f * xy[size_t(k)][t].y + 0.5f, 0.0f, 1.0f);
            mip.texels[4 * t + 2] = 0.0f;
            mip.texels[4 * t + 3] = std::clamp(float(variance[size_t(k)][t] / scale), 0.0f, 1.0f);
        }
    }
    return out;
}

Result<BakedTexture> detailShape(int width, int height, const DetailOptions& options) {
    if (width < 1 || height < 1) return Error{"a detail map needs at least 1x1 texels"};
    if (const Status s = checkDetailOptions(options); !s) return Error{s.error()};
    // A flat map's texture: no variance anywhere.
    BakedTexture tex = detailTexture(0.0, varianceScale(0.0));
    const auto sizes = mipChainSizes(width, height, options.mipCount);
    tex.mips.assign(sizes.size(), TextureMip{});
    for (size_t k = 0; k < sizes.size(); ++k) {
        tex.mips[k].width = sizes[k].first;
        tex.mips[k].height = sizes[k].second;
    }
    return tex;
}

} // namespace burnish
