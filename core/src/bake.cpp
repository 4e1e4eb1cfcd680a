#include <burnish/core/bake.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace burnish {

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point since) {
    return std::chrono::duration<double>(Clock::now() - since).count();
}

// Clamped to [0, 1] with selects (NaN gives 0), so row loops over it need no branches.
float unit(double v) {
    return float(saturate(v));
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
// The slope roles' row loops get a 256-bit AVX2 copy, picked when the program loads on CPUs that
// have it. FMA is not enabled (it is not part of "avx2"), so no multiply-add is fused: both copies
// do the same IEEE operations lane by lane and give the same bits.
#define BURNISH_ROW_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define BURNISH_ROW_CLONES
#endif

// The compact LEAN gloss of a row from the slope covariance (xx, yy, xy) and 1/s: the lobe's
// Σ = slope covariance + I/s, as leanSlopeCovariance builds it; then the logarithms, square roots
// and divisions without calls or branches, which the compiler vectorises.
BURNISH_ROW_CLONES void leanGlossRow(const double* cxx, const double* cyy, const double* cxy,
                                     const double* invBase, int width, float* px) {
    for (int x = 0; x < width; ++x) {
        const double sx = cxx[x] + invBase[x];
        const double sy = cyy[x] + invBase[x];
        px[3 * x] = float(encodeLogVariance(sx)); // in [0, 1]
        px[3 * x + 1] = float(encodeLogVariance(sy));
        const double product = sx * sy;
        double rho = cxy[x] / std::sqrt(product > 1e-300 ? product : 1e-300);
        rho = rho > -1.0 ? rho : -1.0;
        rho = rho < 1.0 ? rho : 1.0;
        px[3 * x + 2] = unit(0.5 * rho + 0.5);
    }
}

// LEAN's second moments M with 1/s on the diagonal, scaled into [0, 1] (invM = 1/sM, invM2 =
// 1/(2 sM)).
BURNISH_ROW_CLONES void leanMRow(const double* mxx, const double* myy, const double* mxy,
                                 const double* invBase, double invM, double invM2, int width, float* px) {
    for (int x = 0; x < width; ++x) {
        const double invS = invBase[x];
        px[3 * x] = unit((mxx[x] + invS) * invM);
        px[3 * x + 1] = unit((myy[x] + invS) * invM);
        px[3 * x + 2] = unit(mxy[x] * invM2 + 0.5);
    }
}

// The slope mean B (LEAN, CLEAN) scaled into [0, 1] (invB2 = 1/(2 sB)), `stride` floats a texel.
BURNISH_ROW_CLONES void slopeMeanRow(const double* bx, const double* by, double invB2, int width, int stride,
                                     float* px) {
    for (int x = 0; x < width; ++x) {
        px[stride * x] = unit(bx[x] * invB2 + 0.5);
        px[stride * x + 1] = unit(by[x] * invB2 + 0.5);
    }
}

// Smallest power of two >= x (and >= 2^-4), so stored ranges are exact binary scales.
double binaryScale(double x) {
    return std::exp2(std::ceil(std::log2(std::max(x, 1.0 / 16.0))));
}

// Per level, the authored base variance 1/s averaged over each texel's footprint and then
// filtered with the pyramid's kernel: variances (not powers or gloss values) are what average
// correctly under minification (Baker & Hill 2012: "storing power as 1/s will cause MIP filter to
// operate correctly").
class BaseVariancePyramid {
public:
    BaseVariancePyramid(const NormalPyramid& pyramid, const std::vector<float>& gloss,
                        const GlossEncoding& encoding)
        : m_pyramid(pyramid)
        , m_taps(kernelTaps(pyramid.options().kernel)) {
        const int levels = pyramid.levelCount();
        m_levels.resize(size_t(levels));
        const PyramidLevel& l0 = pyramid.level(0);
        m_levels[0].resize(size_t(l0.width) * size_t(l0.height));
        for (size_t i = 0; i < gloss.size(); ++i)
            m_levels[0][i] = varianceFromPower(encoding.power(gloss[i]), VarianceConvention::InversePower);
        for (int k = 1; k < levels; ++k) {
            const PyramidLevel& level = pyramid.level(k);
            const PyramidLevel& child = pyramid.level(k - 1);
            auto& out = m_levels[size_t(k)];
            out.resize(size_t(level.width) * size_t(level.height));
            for (int y = 0; y < level.height; ++y)
                for (int x = 0; x < level.width; ++x) {
                    double sum = 0.0, weight = 0.0;
                    for (int j = level.yChild[size_t(y)]; j < level.yChild[size_t(y) + 1]; ++j)
                        for (int i = level.xChild[size_t(x)]; i < level.xChild[size_t(x) + 1]; ++i) {
                            const double w = pyramid.footprintCount(k - 1, i, j);
                            sum += w * m_levels[size_t(k - 1)][size_t(j) * size_t(child.width) + size_t(i)];
                            weight += w;
                        }
                    out[size_t(y) * size_t(level.width) + size_t(x)] = sum / weight;
                }
        }
    }

    /// Base power at a texel of level k, with the pyramid's kernel applied.
    double power(int k, int x, int y) const {
        const KernelTaps& taps = m_taps;
        const PyramidLevel& level = m_pyramid.level(k);
        double sum = 0.0, weight = 0.0;
        for (int j = -taps.radius; j <= taps.radius; ++j)
            for (int i = -taps.radius; i <= taps.radius; ++i) {
                const int xi = borderIndex(x + i, level.width, m_pyramid.options().border);
                const int yj = borderIndex(y + j, level.height, m_pyramid.options().border);
                const double w =
                    taps.w[i + taps.radius] * taps.w[j + taps.radius] * m_pyramid.footprintCount(k, xi, yj);
                sum += w * m_levels[size_t(k)][size_t(yj) * size_t(level.width) + size_t(xi)];
                weight += w;
            }
        return powerFromVariance(sum / weight, VarianceConvention::InversePower);
    }

private:
    const NormalPyramid& m_pyramid;
    KernelTaps m_taps; // looked up once: the Gaussian's weights cost two exp() each
    std::vector<std::vector<double>> m_levels;
};

BakedTexture makeTexture(std::string role, std::string description, std::vector<ChannelDecode> decode,
                         bool highPrecision = false) {
    BakedTexture t;
    t.role = std::move(role);
    t.description = std::move(description);
    t.channels = int(decode.size());
    t.decode = std::move(decode);
    t.needsHighPrecision = highPrecision;
    return t;
}

std::vector<ChannelDecode> normalDecode() {
    return {{"normal.x", 2.0, -1.0}, {"normal.y", 2.0, -1.0}, {"normal.z", 2.0, -1.0}};
}

} // namespace

const BakedTexture* BakeOutput::find(const std::string& role) const {
    for (const auto& t : textures)
        if (t.role == role) return &t;
    return nullptr;
}

Result<std::vector<float>> glossFromImage(const Image& image, int width, int height) {
    if (image.width != width || image.height != height)
        return Error{"gloss map is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                     " but the normal map is " + std::to_string(width) + "x" + std::to_string(height)};
    std::vector<float> gloss(image.texelCount());
    for (size_t i = 0; i < gloss.size(); ++i) {
        const float v = image.pixels[i * size_t(image.channels)];
        if (!std::isfinite(v))
            return Error{"gloss map has a NaN or infinite texel at index " + std::to_string(i)};
        gloss[i] = std::clamp(v, 0.0f, 1.0f);
    }
    return gloss;
}

Result<BakeOutput> bake(const NormalMap& map, const BakeOptions& options) {
    if (map.texelCount() == 0) return Error{"the normal map is empty"};
    if (!(options.basePower > 0.0) || !(options.basePower <= kMaxPower))
        return Error{"base power must lie in (0, 1e9]"};
    if (options.authoredGloss) {
        if (options.authoredGloss->size() != map.texelCount())
            return Error{"authored gloss has " + std::to_string(options.authoredGloss->size()) +
                         " texels, the normal map " + std::to_string(map.texelCount())};
        for (float g : *options.authoredGloss)
            if (!std::isfinite(g)) return Error{"authored gloss has a NaN or infinite texel"};
    }

    BakeOutput out;
    out.method = options.method;
    auto start = Clock::now();
    const std::shared_ptr<const NormalMap> borrowed(&map, [](const NormalMap*) {});
    // Only the moments the method reads: the rest are most of the pyramid's work.
    PyramidOptions pyramidOptions = options.pyramid;
    pyramidOptions.moments = momentsNeeded(options.method);
    const NormalPyramid pyramid = NormalPyramid::build(borrowed, pyramidOptions);
    std::optional<BaseVariancePyramid> base;
    if (options.authoredGloss) base.emplace(pyramid, *options.authoredGloss, options.encoding);
    out.stats.pyramidSeconds = seconds(start);
    start = Clock::now();

    const int levels =
        options.mipCount > 0 ? std::min(options.mipCount, pyramid.levelCount()) : pyramid.levelCount();
    out.stats.mipCount = levels;
    const Method method = options.method;
    const bool slopeMethod = method == Method::Lean || method == Method::Clean;
    const bool unnormalized = method == Method::Toksvig;
    const bool adjustedGloss = method == Method::VarianceToGloss || method == Method::Vmf;

    // Binary scales for the slope textures, so their [0, 1] storage covers every mip. Every box
    // moment is a mean of finest-level values (and filtered moments means of box moments), so the
    // finest level's largest |b| and b² bound every level; a value a rounding above them is
    // clamped by unit(). Level 0's moments are NormalMoments::ofNormal's: b = n.xy / max(n.z,
    // kMinSlopeZ) in float, M = b² (its slope covariance is zero).
    double sB = 1.0, sM = 1.0;
    if (slopeMethod) {
        const NormalVector& normals = map.normals;
        const float maxSlope = tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, normals.size(), size_t(1) << 15), 0.0f,
            [&](const tbb::blocked_range<size_t>& r, float b) {
                for (size_t i = r.begin(); i != r.end(); ++i) {
                    // max(|x|/z, |y|/z) = max(|x|, |y|)/z exactly: rounding is monotonic.
                    const glm::vec3& n = normals[i];
                    const float z = std::max(n.z, kMinSlopeZ);
                    const float ax = std::abs(n.x), ay = std::abs(n.y);
                    const float slope = (ax > ay ? ax : ay) / z;
                    b = slope > b ? slope : b;
                }
                return b;
            },
            [](float a, float b) { return std::max(a, b); }); // max is exact: any order gives the same
        const double maxB = double(maxSlope);
        const double maxM = double(maxSlope * maxSlope);
        double minPower = options.basePower;
        if (options.authoredGloss)
            for (float g : *options.authoredGloss)
                minPower = std::min(minPower, options.encoding.power(g));
        sB = binaryScale(maxB);
        sM = binaryScale(maxM + 1.0 / std::max(minPower, 1e-6));
    }

    // The textures each method stores.
    out.textures.push_back(makeTexture("normal",
                                       unnormalized
                                           ? "unnormalized mean normal Na (its length carries the variance)"
                                           : "renormalized mean normal",
                                       normalDecode()));
    if (!slopeMethod)
        out.textures.push_back(makeTexture(
            "gloss",
            std::string(adjustedGloss ? "adjusted gloss, " : "authored gloss, ") + options.encoding.formula(),
            {{"gloss", 1.0, 0.0}}));
    if (method == Method::ToksvigMap)
        out.textures.push_back(makeTexture("toksvig",
                                           "Toksvig factor f_t for power " +
                                               std::to_string(options.params.toksvigMapPower) +
                                               "; convert with ft /= lerp(s/fixed_s, 1, ft)",
                                           {{"toksvig", 1.0, 0.0}}));
    if (method == Method::Lean) {
        out.textures.push_back(
            makeTexture("lean-b", "LEAN slope mean B", {{"B.x", 2 * sB, -sB}, {"B.y", 2 * sB, -sB}}, true));
        out.textures.push_back(makeTexture("lean-m", "LEAN second moments M with 1/s on the diagonal",
                                           {{"M.xx", sM, 0.0}, {"M.yy", sM, 0.0}, {"M.xy", 2 * sM, -sM}},
                                           true));
        out.textures.push_back(makeTexture(
            "lean-gloss", "compact LEAN: log2(1/Sigma_x)/13, log2(1/Sigma_y)/13, correlation (rho+1)/2",
            {{"gloss.x", 1.0, 0.0}, {"gloss.y", 1.0, 0.0}, {"rho", 2.0, -1.0}}));
    }
    if (method == Method::Clean)
        out.textures.push_back(makeTexture("clean", "CLEAN: B and (M.xx + M.yy)/2 with 1/s added",
                                           {{"B.x", 2 * sB, -sB}, {"B.y", 2 * sB, -sB}, {"M.avg", sM, 0.0}},
                                           true));
    if (options.roles) {
        const auto& wanted = *options.roles;
        std::erase_if(out.textures, [&](const BakedTexture& t) {
            return std::find(wanted.begin(), wanted.end(), t.role) == wanted.end();
        });
    }
    for (auto& tex : out.textures)
        tex.mips.resize(size_t(levels));

    enum class Role { Normal, Gloss, Toksvig, LeanB, LeanM, LeanGloss, Clean };
    std::vector<Role> roles;
    for (const auto& tex : out.textures)
        roles.push_back(tex.role == "normal"    ? Role::Normal
                        : tex.role == "gloss"   ? Role::Gloss
                        : tex.role == "toksvig" ? Role::Toksvig
                        : tex.role == "lean-b"  ? Role::LeanB
                        : tex.role == "lean-m"  ? Role::LeanM
                        : tex.role == "clean"   ? Role::Clean
                                                : Role::LeanGloss);

    // Without a gloss map the stored gloss of the non-adjusting methods is the base power's at
    // every texel: encoded once, with its clamp counts added per texel below.
    const bool constantGloss = !adjustedGloss && !base;
    const bool producesGloss = std::find(roles.begin(), roles.end(), Role::Gloss) != roles.end();
    const bool producesNormal = std::find(roles.begin(), roles.end(), Role::Normal) != roles.end();
    const bool needDirections =
        (producesNormal && !unnormalized) || (producesGloss && method == Method::VarianceToGloss);
    const double glossMinPower = options.encoding.minPower(), glossMaxPower = options.encoding.maxPower();
    const float baseGloss = unit(options.encoding.value(options.basePower));
    for (int k = 0; k < levels; ++k) {
        const PyramidLevel& level = pyramid.level(k);
        if (constantGloss && producesGloss) {
            const size_t texels = size_t(level.width) * size_t(level.height);
            if (options.basePower < glossMinPower) out.stats.glossClampedLow += texels;
            if (options.basePower > glossMaxPower) out.stats.glossClampedHigh += texels;
        }
        for (auto& tex : out.textures) {
            auto& mip = tex.mips[size_t(k)];
            mip.width = level.width;
            mip.height = level.height;
            mip.texels.resize(size_t(level.width) * size_t(level.height) * size_t(tex.channels));
        }
        std::vector<size_t> lowRow(static_cast<size_t>(level.height), 0),
            highRow(static_cast<size_t>(level.height), 0);
        // Each row is produced from its filtered moments as they stream out of the pyramid, one
        // role at a time, so each inner loop does one texture's arithmetic.
        pyramid.forEachMomentRow(k, [&](int y, const NormalMoments* row) {
            const int width = level.width;
            const size_t first = size_t(y) * size_t(width);
            // The base power per texel (authored gloss, filtered as variance), or the constant.
            thread_local std::vector<double> basePowers;
            basePowers.resize(size_t(width));
            for (int x = 0; x < width; ++x)
                basePowers[size_t(x)] = base ? base->power(k, x, y) : options.basePower;
            // Only the adjusted gloss reads the lobe; the other roles store moments or the base
            // power directly.
            thread_local std::vector<double> lobePowers;
            // The mean directions, once for the normal texture and variance-to-gloss's variances.
            thread_local std::vector<glm::vec3> directions;
            if (needDirections) {
                directions.resize(size_t(width));
                for (int x = 0; x < width; ++x)
                    directions[size_t(x)] = row[x].meanDirection();
            }
            if (adjustedGloss && producesGloss) {
                lobePowers.resize(size_t(width));
                if (method == Method::VarianceToGloss) {
                    // methodPower's formula in two loops: the variances (projectedVariance), then the
                    // powers in a loop without calls or branches, which the compiler vectorises.
                    for (int x = 0; x < width; ++x)
                        lobePowers[size_t(x)] = row[x].projectedVarianceAbout(directions[size_t(x)]);
                    for (int x = 0; x < width; ++x)
                        lobePowers[size_t(x)] =
                            varianceToGlossPower(lobePowers[size_t(x)], basePowers[size_t(x)]);
                } else {
                    for (int x = 0; x < width; ++x)
                        lobePowers[size_t(x)] =
                            methodPower(method, row[x], basePowers[size_t(x)], options.params);
                }
            }
            // The slope moments as rows of doubles (structure of arrays), read from the moments once
            // for all the slope roles, so each role's loop is a flat one the compiler vectorises: B,
            // the second moments M (in float, as slopeSecondMoments gives them), the slope covariance,
            // and 1/s per texel as the lobe adds it (slopeInverseBasePower). sB and sM are powers of
            // two, so multiplying by their reciprocals is exact.
            thread_local std::vector<double> bx, by, mxx, myy, mxy, cxx, cyy, cxy, invBase;
            if (slopeMethod) {
                invBase.resize(size_t(width));
                const double invConstant = slopeInverseBasePower(options.basePower);
                for (int x = 0; x < width; ++x)
                    invBase[size_t(x)] = base ? slopeInverseBasePower(basePowers[size_t(x)]) : invConstant;
                for (auto* v : {&bx, &by, &mxx, &myy, &mxy, &cxx, &cyy, &cxy})
                    v->resize(size_t(width));
                for (int x = 0; x < width; ++x) {
                    const NormalMoments& m = row[x];
                    const auto M = m.slopeSecondMoments();
                    bx[size_t(x)] = m.slope.x;
                    by[size_t(x)] = m.slope.y;
                    mxx[size_t(x)] = M[0];
                    myy[size_t(x)] = M[1];
                    mxy[size_t(x)] = M[2];
                    cxx[size_t(x)] = m.slopeCov[0];
                    cyy[size_t(x)] = m.slopeCov[1];
                    cxy[size_t(x)] = m.slopeCov[2];
                }
            }
            const double invB2 = 1.0 / (2 * sB), invM = 1.0 / sM, invM2 = 1.0 / (2 * sM);
            for (size_t r = 0; r < roles.size(); ++r) {
                BakedTexture& tex = out.textures[r];
                float* px = &tex.mips[size_t(k)].texels[first * size_t(tex.channels)];
                switch (roles[r]) {
                case Role::Normal:
                    for (int x = 0; x < width; ++x, px += 3) {
                        const glm::vec3 n = unnormalized ? row[x].mean : directions[size_t(x)];
                        for (int c = 0; c < 3; ++c)
                            px[c] = unit(0.5 * double(n[c]) + 0.5);
                    }
                    break;
                case Role::Gloss:
                    if (constantGloss) {
                        std::fill(px, px + width, baseGloss); // the base power's gloss, encoded once above
                        break;
                    }
                    {
                        const double* powers = adjustedGloss ? lobePowers.data() : basePowers.data();
                        size_t low = 0, high = 0;
                        for (int x = 0; x < width; ++x) {
                            low += powers[x] < glossMinPower ? 1 : 0;
                            high += powers[x] > glossMaxPower ? 1 : 0;
                        }
                        lowRow[size_t(y)] += low;
                        highRow[size_t(y)] += high;
                        options.encoding.values(powers, px, size_t(width));
                        break;
                    }
                case Role::Toksvig:
                    for (int x = 0; x < width; ++x)
                        px[x] = unit(toksvigFactor(row[x].lengthNa(), options.params.toksvigMapPower));
                    break;
                case Role::LeanB:
                    slopeMeanRow(bx.data(), by.data(), invB2, width, 2, px);
                    break;
                case Role::Clean:
                    slopeMeanRow(bx.data(), by.data(), invB2, width, 3, px);
                    for (int x = 0; x < width; ++x)
                        px[3 * x + 2] =
                            unit((0.5 * (mxx[size_t(x)] + myy[size_t(x)]) + invBase[size_t(x)]) * invM);
                    break;
                case Role::LeanM:
                    leanMRow(mxx.data(), myy.data(), mxy.data(), invBase.data(), invM, invM2, width, px);
                    break;
                case Role::LeanGloss:
                    leanGlossRow(cxx.data(), cyy.data(), cxy.data(), invBase.data(), width, px);
                    break;
                }
            }
        });
        for (int y = 0; y < level.height; ++y) {
            out.stats.glossClampedLow += lowRow[size_t(y)];
            out.stats.glossClampedHigh += highRow[size_t(y)];
        }
    }
    out.stats.methodSeconds = seconds(start);
    return out;
}

} // namespace burnish
