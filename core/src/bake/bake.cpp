#include <burnish/core/bake/bake.h>

#include <burnish/core/bake/base_variance.h>
#include <burnish/core/io/dds.h>
#include <burnish/core/prefilter/fitted_lobe.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/prefilter/mixture_refine.h>
#include <burnish/core/util/simd.h>

#if defined(__x86_64__) && defined(__GNUC__)
#include <cpuid.h>
#include <immintrin.h>
#endif
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>

namespace burnish {

// Imath's float-to-half (round to nearest even) for values clamped to [0, 1], eight lanes at a time:
// the normal halves from the float's bits by one rounding add, those below 2^-14 as denormals by a
// shift and the same tie rule, below 2^-25 zero. A block holding a NaN takes the scalar path.
BURNISH_AVX2_CLONES void portableHalfCodes(const float* values, size_t count, std::uint16_t* bits) {
    using simd::Float8;
    using simd::UInt8;
    size_t i = 0;
    for (; i + 8 <= count; i += 8) {
        Float8 v;
        std::memcpy(&v, values + i, sizeof v);
        bool nan = false;
        for (int k = 0; k < 8; ++k)
            nan |= v[k] != v[k];
        if (nan) {
            for (size_t k = i; k < i + 8; ++k)
                bits[k] = halfCode(values[k]).bits();
            continue;
        }
        v = v < 0.0f ? Float8{} : v; // std::clamp(v, 0, 1): −0 stays −0
        v = 1.0f < v ? Float8{} + 1.0f : v;
        UInt8 u;
        std::memcpy(&u, &v, sizeof u);
        const UInt8 sign = (u >> 16) & 0x8000u;
        const UInt8 ui = u & 0x7fffffffu;
        const UInt8 biased = ui - 0x38000000u;
        const UInt8 normal = (biased + 0x0fffu + ((biased >> 13) & 1u)) >> 13;
        // Denormal halves: the mantissa with its implicit bit, shifted right by 0x7e − e (14..24 in
        // that range; other lanes are clamped to a valid shift and not used).
        UInt8 shift = 0x7eu - (ui >> 23);
        shift = shift > 31u ? UInt8{} + 31u : shift;
        shift = shift < 1u ? UInt8{} + 1u : shift;
        const UInt8 m = 0x800000u | (ui & 0x7fffffu);
        const UInt8 rest = m << (32u - shift);
        UInt8 denormal = m >> shift;
        const auto up = (rest > 0x80000000u) | ((rest == 0x80000000u) & ((denormal & 1u) != 0u));
        denormal = up ? denormal + 1u : denormal;
        UInt8 half = ui >= 0x38800000u ? normal : ui < 0x33000001u ? UInt8{} : denormal;
        half |= sign;
        for (int k = 0; k < 8; ++k)
            bits[i + size_t(k)] = std::uint16_t(half[k]);
    }
    for (; i < count; ++i)
        bits[i] = halfCode(values[i]).bits();
}

namespace {

#if defined(__x86_64__) && defined(__GNUC__)
// Whether the CPU converts to half floats (F16C) and the OS keeps the 256-bit registers (AVX, enabled
// by XSAVE): CPUID leaf 1 and XCR0. Clang 14's __builtin_cpu_supports knows no "f16c".
bool hasAvxF16c() {
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    if (!__get_cpuid(1, &eax, &ebx, &ecx, &edx)) return false;
    constexpr unsigned kOsxsave = 1u << 27, kAvx = 1u << 28, kF16c = 1u << 29;
    if ((ecx & (kOsxsave | kAvx | kF16c)) != (kOsxsave | kAvx | kF16c)) return false;
    unsigned lo = 0, hi = 0;
    __asm__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    return (lo & 6u) == 6u; // the SSE and AVX register states
}

// The same codes by the F16C instruction, which rounds to nearest even as Imath does, denormal halves
// included: the values clamped as above (−0 stays −0), eight converted at once; a block holding a
// NaN takes the scalar path. About twelve times the portable lanes' speed on rows in cache: a 4096² mixture
// bake converts 320 million values.
__attribute__((target("avx,f16c"))) void f16cHalfCodes(const float* values, size_t count,
                                                       std::uint16_t* bits) {
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    size_t i = 0;
    for (; i + 8 <= count; i += 8) {
        __m256 v = _mm256_loadu_ps(values + i);
        if (_mm256_movemask_ps(_mm256_cmp_ps(v, v, _CMP_UNORD_Q)) != 0) {
            for (size_t k = i; k < i + 8; ++k)
                bits[k] = halfCode(values[k]).bits();
            continue;
        }
        // max and min return their second operand for two zeros: −0 stays −0, as std::clamp keeps it.
        v = _mm256_min_ps(one, _mm256_max_ps(zero, v));
        const __m128i h = _mm256_cvtps_ph(v, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(bits + i), h);
    }
    for (; i < count; ++i)
        bits[i] = halfCode(values[i]).bits();
}
#endif

} // namespace

void halfCodes(const float* values, size_t count, std::uint16_t* bits) {
#if defined(__x86_64__) && defined(__GNUC__)
    static const bool f16c = hasAvxF16c();
    if (f16c) {
        f16cHalfCodes(values, count, bits);
        return;
    }
#endif
    portableHalfCodes(values, count, bits);
}

namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point since) {
    return std::chrono::duration<double>(Clock::now() - since).count();
}

// Clamped to [0, 1] with selects (NaN gives 0), so row loops over it need no branches.
float unit(double v) {
    return float(saturate(v));
}

// The slope roles' row loops below get a 256-bit AVX2 copy with the same bits (BURNISH_AVX2_CLONES).

// The compact LEAN gloss of a row from the slope covariance (xx, yy, xy) and 1/s: the lobe's
// Σ = slope covariance + I/s, as leanSlopeCovariance builds it; then the logarithms, square roots
// and divisions without calls or branches, which the compiler vectorises.
BURNISH_AVX2_CLONES void leanGlossRow(const double* cxx, const double* cyy, const double* cxy,
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
BURNISH_AVX2_CLONES void leanMRow(const double* mxx, const double* myy, const double* mxy,
                                  const double* invBase, double invM, double invM2, int width, float* px) {
    for (int x = 0; x < width; ++x) {
        const double invS = invBase[x];
        px[3 * x] = unit((mxx[x] + invS) * invM);
        px[3 * x + 1] = unit((myy[x] + invS) * invM);
        px[3 * x + 2] = unit(mxy[x] * invM2 + 0.5);
    }
}

// The slope mean B (LEAN, CLEAN) scaled into [0, 1] (invB2 = 1/(2 sB)), `stride` floats a texel.
BURNISH_AVX2_CLONES void slopeMeanRow(const double* bx, const double* by, double invB2, int width, int stride,
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

// A description from the method table with its placeholders filled in.
std::string describe(std::string_view text, const BakeOptions& options) {
    std::string out(text);
    auto fill = [&out](std::string_view key, const std::string& value) {
        if (const auto at = out.find(key); at != std::string::npos) out.replace(at, key.size(), value);
    };
    fill("{encoding}", options.encoding.formula());
    fill("{toksvig-power}", std::to_string(options.params.toksvigMapPower));
    return out;
}

// Whether the bake writes the method's texture `role`: not a mixture's unused lobes, and only the
// roles asked for.
bool bakesRole(const BakeOptions& options, TextureRole role) {
    if (!bakesTexture(options.method, role, options.params)) return false;
    return !options.roles ||
           std::find(options.roles->begin(), options.roles->end(), role) != options.roles->end();
}

// The textures the method's table row names (those of options.roles when given), described, with
// their decodes under the bake's slope scales and no mips yet.
std::vector<BakedTexture> planTextures(const BakeOptions& options, const ChannelScales& scales) {
    std::vector<BakedTexture> textures;
    for (const MethodTexture& m : methodSpec(options.method).textures) {
        if (!bakesRole(options, m.role)) continue;
        const TextureSpec& spec = textureSpec(m.role);
        BakedTexture t;
        t.role = m.role;
        t.description = describe(m.description, options);
        t.decode = textureDecode(m.role, scales);
        t.channels = int(t.decode.size());
        t.needsHighPrecision = spec.needsHighPrecision;
        if (const auto it = options.storage.find(m.role); it != options.storage.end()) t.storage = it->second;
        textures.push_back(std::move(t));
    }
    return textures;
}

} // namespace

std::vector<ChannelDecode> textureDecode(TextureRole role, const ChannelScales& scales) {
    std::vector<ChannelDecode> decode;
    for (const ChannelSpec& c : textureSpec(role).channels) {
        const ChannelDecodeRule rule = channelDecode(c.range, scales);
        decode.push_back({std::string(c.name), rule.scale, rule.bias});
    }
    return decode;
}

const BakedTexture* BakeOutput::find(TextureRole role) const {
    for (const auto& t : textures)
        if (t.role == role) return &t;
    return nullptr;
}

double normalLikeFraction(const Image& image) {
    if (image.channels < 3 || image.texelCount() == 0) return 0.0;
    // A grey image stored as RGB (a gloss map saved in colour) is no normal map whatever its value.
    constexpr double kMinColour = 0.1;
    constexpr double kUnitTolerance = 0.1;
    double colour = 0.0;
    size_t unitUp = 0;
    const size_t n = image.texelCount();
    for (size_t i = 0; i < n; ++i) {
        const float* p = &image.pixels[i * size_t(image.channels)];
        colour += std::abs(double(p[0]) - double(p[2]));
        const double x = 2.0 * p[0] - 1.0, y = 2.0 * p[1] - 1.0, z = 2.0 * p[2] - 1.0;
        if (z > 0.0 && std::abs(std::sqrt(x * x + y * y + z * z) - 1.0) < kUnitTolerance) ++unitUp;
    }
    if (colour / double(n) < kMinColour) return 0.0;
    return double(unitUp) / double(n);
}

Result<std::vector<float>> glossFromImage(const Image& image, int width, int height) {
    if (image.width != width || image.height != height)
        return Error{"gloss map is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                     " but the normal map is " + std::to_string(width) + "x" + std::to_string(height)};
    // A normal map taken for a gloss map would bake its red channel as gloss, silently.
    if (const double f = normalLikeFraction(image); f >= kNormalLikeFraction)
        return Error{
            fmt::format("this image looks like a tangent-space normal map, not a gloss map ({:.1f} % of its "
                        "texels decode to unit vectors facing up): load it as the normal map",
                        100.0 * f)};
    std::vector<float> gloss(image.texelCount());
    for (size_t i = 0; i < gloss.size(); ++i) {
        const float v = image.pixels[i * size_t(image.channels)];
        if (!std::isfinite(v))
            return Error{"gloss map has a NaN or infinite texel at index " + std::to_string(i)};
        gloss[i] = std::clamp(v, 0.0f, 1.0f);
    }
    return gloss;
}

namespace {

// What bake() refuses in its options alone, whatever the map.
Status checkBakeOptions(const BakeOptions& options) {
    if (!(options.basePower > 0.0) || !(options.basePower <= kMaxPower))
        return Error{"base power must lie in (0, 1e9]"};
    return {};
}

Status checkBakeInput(const NormalMap& map, const BakeOptions& options) {
    if (map.texelCount() == 0) return Error{"the normal map is empty"};
    if (const Status s = checkBakeOptions(options); !s) return s;
    if (options.authoredGloss) {
        if (options.authoredGloss->size() != map.texelCount())
            return Error{"authored gloss has " + std::to_string(options.authoredGloss->size()) +
                         " texels, the normal map " + std::to_string(map.texelCount())};
        for (float g : *options.authoredGloss)
            if (!std::isfinite(g)) return Error{"authored gloss has a NaN or infinite texel"};
    }
    return {};
}

// The slope textures' scales of a map whose largest slope max(|b.x|, |b.y|) is maxSlope and whose
// smallest power (base or authored) is minPower.
ChannelScales slopeScalesFor(float maxSlope, double minPower) {
    const double maxB = double(maxSlope);
    const double maxM = double(maxSlope * maxSlope);
    return {binaryScale(maxB), binaryScale(maxM + 1.0 / std::max(minPower, 1e-6)), 1.0};
}

// Binary scales for the slope textures, so their [0, 1] storage covers every mip. Every box moment
// is a mean of finest-level values (and filtered moments means of box moments), so the finest
// level's largest |b| and b² bound every level; a value a rounding above them is clamped by unit().
// Level 0's moments are NormalMoments::ofNormal's: b = n.xy / max(n.z, kMinSlopeZ) in float, M = b²
// (its slope covariance is zero).
ChannelScales slopeScales(const NormalMap& map, const BakeOptions& options) {
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
    double minPower = options.basePower;
    if (options.authoredGloss)
        for (float g : *options.authoredGloss)
            minPower = std::min(minPower, options.encoding.power(g));
    return slopeScalesFor(maxSlope, minPower);
}

// What every row of one bake shares: the method's row in the table as flags, the textures' roles,
// the slope scales and the authored base powers.
struct RowPlan {
    const BakeOptions& options;
    const BaseVariancePyramid* base; // the authored gloss as variances, or none (options.basePower)
    // The mixture's lobes for K >= 2 (K = 1 stores LEAN's moments from the rows).
    const MixturePyramid* mixture = nullptr;
    // The fitted lobe's powers of levels 1 and up (Method::Fitted).
    const FittedPyramid* fitted = nullptr;
    const NormalMap* finestMap = nullptr;
    std::vector<TextureRole> roles; // of the textures produced, in order
    ChannelScales scales;
    bool slopeMethod = false;
    bool unnormalized = false;
    bool adjustedGloss = false;
    // Without a gloss map the stored gloss of the non-adjusting methods is the base power's at
    // every texel: encoded once, with its clamp counts added per level.
    bool constantGloss = false;
    bool producesGloss = false;
    bool needDirections = false;
    double glossMinPower = 0.0, glossMaxPower = 0.0;
    float baseGloss = 0.0f;

    RowPlan(const BakeOptions& o, const BaseVariancePyramid* b, const MixturePyramid* mix,
            const std::vector<BakedTexture>& textures, const ChannelScales& s)
        : options(o)
        , base(b)
        , mixture(mix)
        , scales(s) {
        const MethodSpec& spec = methodSpec(o.method);
        for (const auto& tex : textures)
            roles.push_back(tex.role);
        auto produces = [&](TextureRole r) {
            return std::find(roles.begin(), roles.end(), r) != roles.end();
        };
        slopeMethod = storesSlopes(o.method);
        unnormalized = spec.unnormalizedNormal;
        adjustedGloss = spec.adjustsGloss;
        constantGloss = !adjustedGloss && !base;
        producesGloss = produces(TextureRole::Gloss);
        needDirections = (produces(TextureRole::Normal) && !unnormalized) ||
                         (producesGloss && o.method == Method::VarianceToGloss);
        glossMinPower = o.encoding.minPower();
        glossMaxPower = o.encoding.maxPower();
        baseGloss = unit(o.encoding.value(o.basePower));
    }
};

// One row's values that several roles read, computed once per row (structure of arrays).
struct RowValues {
    std::vector<double> basePowers;    // the base power per texel (authored, filtered as variance)
    std::vector<double> lobePowers;    // the adjusted gloss's power (variance-to-gloss, vMF)
    std::vector<glm::vec3> directions; // mean directions: the normal texture, variance-to-gloss
    // The slope moments as rows of doubles, read from the moments once for all the slope roles, so
    // each role's loop is a flat one the compiler vectorises: B, the second moments M (in float, as
    // slopeSecondMoments gives them), the slope covariance, and 1/s per texel as the lobe adds it
    // (slopeInverseBasePower).
    std::vector<double> bx, by, mxx, myy, mxy, cxx, cyy, cxy, invBase;

    void fill(const RowPlan& plan, int k, int y, const NormalMoments* row, int width) {
        const BakeOptions& o = plan.options;
        basePowers.resize(size_t(width));
        for (int x = 0; x < width; ++x)
            basePowers[size_t(x)] = plan.base ? plan.base->power(k, x, y) : o.basePower;
        if (plan.needDirections) {
            directions.resize(size_t(width));
            for (int x = 0; x < width; ++x)
                directions[size_t(x)] = row[x].meanDirection();
        }
        // Only the adjusted gloss reads the lobe; the other roles store moments or the base power.
        if (plan.adjustedGloss && plan.producesGloss) {
            lobePowers.resize(size_t(width));
            if (o.method == Method::VarianceToGloss) {
                // methodPower's formula in two loops: the variances (projectedVariance), then the
                // powers in a loop without calls or branches, which the compiler vectorises.
                for (int x = 0; x < width; ++x)
                    lobePowers[size_t(x)] = row[x].projectedVarianceAbout(directions[size_t(x)]);
                for (int x = 0; x < width; ++x)
                    lobePowers[size_t(x)] =
                        varianceToGlossPower(lobePowers[size_t(x)], basePowers[size_t(x)]);
            } else if (o.method == Method::Fitted) {
                // Level 0's footprint is one normal, whose lobe is the base power's.
                for (int x = 0; x < width; ++x)
                    lobePowers[size_t(x)] = k > 0 ? plan.fitted->power(k, x, y) : basePowers[size_t(x)];
            } else {
                for (int x = 0; x < width; ++x)
                    lobePowers[size_t(x)] = methodPower(o.method, row[x], basePowers[size_t(x)], o.params);
            }
        }
        if (!plan.slopeMethod) return;
        invBase.resize(size_t(width));
        const double invConstant = slopeInverseBasePower(o.basePower);
        for (int x = 0; x < width; ++x)
            invBase[size_t(x)] = plan.base ? slopeInverseBasePower(basePowers[size_t(x)]) : invConstant;
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
};

struct ClampCounts {
    size_t low = 0, high = 0;
};

// The mixture roles' texels of row y of level k, every texture of them in one pass (px[r] for role
// MixtureWeights + r, null when not produced): each texel's lobes as premultiplied moments over its
// total weight (weights summing to 1), scaled into [0, 1]. Level 0 is one lobe per finest normal, at
// the index of the parent's lobe it belongs to (MixturePyramid::finestLobe).
constexpr int kMixtureRoles = int(TextureRole::MixtureCross) - int(TextureRole::MixtureWeights) + 1;

// The role's index among the mixture's roles (mixtureRows' px), or -1 for another role.
int mixtureSlot(TextureRole role) {
    const int i = int(role) - int(TextureRole::MixtureWeights);
    return i >= 0 && i < kMixtureRoles ? i : -1;
}

void mixtureRows(const RowPlan& plan, int k, int y, int width, const std::array<float*, kMixtureRoles>& px) {
    const MixturePyramid& mix = *plan.mixture;
    const BakeOptions& o = plan.options;
    const double sB = plan.scales.slope, sM = plan.scales.moment;
    const double invB2 = 1.0 / (2 * sB), invM = 1.0 / sM, invM2 = 1.0 / (2 * sM);
    float* weights = px[0];
    float* cross = px[kMixtureRoles - 1];
    if (k == 0) {
        // One lobe per texel, weight 1, in its slot; the other slots' values are the loop's below
        // for zero moments (0·scale + 0.5 is 0.5). Each texel's six values are computed once and
        // each slot takes them or the empty slot's.
        const float zero = unit(0.0), half = unit(0.5);
        const int lobeCount = mix.lobeCount();
        const double baseVariance = mixtureBaseVariance(o.basePower, lobeCount);
        const float* gloss = o.authoredGloss ? &(*o.authoredGloss)[size_t(y) * size_t(width)] : nullptr;
        const glm::vec3* normals = &plan.finestMap->normals[size_t(y) * size_t(width)];
        for (int x = 0; x < width; ++x) {
            const double v =
                gloss ? mixtureBaseVariance(o.encoding.power(gloss[x]), lobeCount) : baseVariance;
            const LobeMoments l = LobeMoments::ofNormal(normals[x], v);
            const int own = mix.finestLobe(x, y);
            const float w = unit(l.w), xy = unit(l.mxy * invM2 + 0.5);
            const std::array<float, 4> lobe{unit(l.bx * invB2 + 0.5), unit(l.by * invB2 + 0.5),
                                            unit(l.mxx * invM), unit(l.myy * invM)};
            const std::array<float, 4> empty{half, half, zero, zero};
            for (int i = 0; i < kMaxMixtureLobes; ++i) {
                const bool mine = i == own;
                if (weights) weights[4 * x + i] = mine ? w : zero;
                if (cross) cross[4 * x + i] = mine ? xy : half;
                if (float* p = px[size_t(1 + i)])
                    std::memcpy(p + 4 * x, mine ? lobe.data() : empty.data(), sizeof lobe);
            }
        }
        return;
    }
    for (int x = 0; x < width; ++x) {
        const std::array<LobeMoments, kMaxMixtureLobes> lobes =
            mix.storedTexel(*plan.finestMap, k, x, y, o.basePower); // k >= 1: the power is level 0's
        for (int i = 0; i < kMaxMixtureLobes; ++i) {
            const LobeMoments& l = lobes[size_t(i)];
            if (weights) weights[4 * x + i] = unit(l.w);
            if (cross) cross[4 * x + i] = unit(l.mxy * invM2 + 0.5);
            if (float* p = px[size_t(1 + i)]) {
                // An empty lobe stores zeros as its moments: w·b = 0 is 0.5.
                p[4 * x] = unit(l.bx * invB2 + 0.5);
                p[4 * x + 1] = unit(l.by * invB2 + 0.5);
                p[4 * x + 2] = unit(l.mxx * invM);
                p[4 * x + 3] = unit(l.myy * invM);
            }
        }
    }
}

// One role's texels of a row into `px` (`channels` floats a texel); the gloss role counts the powers
// it clamps to the encoding's range. sB and sM are powers of two, so multiplying by their
// reciprocals is exact.
ClampCounts writeRoleRow(const RowPlan& plan, TextureRole role, const NormalMoments* row, const RowValues& v,
                         int width, float* px) {
    const BakeOptions& o = plan.options;
    const double sB = plan.scales.slope, sM = plan.scales.moment;
    const double invB2 = 1.0 / (2 * sB), invM = 1.0 / sM, invM2 = 1.0 / (2 * sM);
    ClampCounts counts;
    switch (role) {
    case TextureRole::Normal:
        for (int x = 0; x < width; ++x, px += 3) {
            const glm::vec3 n = plan.unnormalized ? row[x].mean : v.directions[size_t(x)];
            for (int c = 0; c < 3; ++c)
                px[c] = unit(0.5 * double(n[c]) + 0.5);
        }
        break;
    case TextureRole::Gloss: {
        if (plan.constantGloss) {
            std::fill(px, px + width, plan.baseGloss); // the base power's gloss, encoded once
            break;
        }
        const double* powers = plan.adjustedGloss ? v.lobePowers.data() : v.basePowers.data();
        for (int x = 0; x < width; ++x) {
            counts.low += powers[x] < plan.glossMinPower ? 1 : 0;
            counts.high += powers[x] > plan.glossMaxPower ? 1 : 0;
        }
        o.encoding.values(powers, px, size_t(width));
        break;
    }
    case TextureRole::Toksvig:
        for (int x = 0; x < width; ++x)
            px[x] = unit(toksvigFactor(row[x].lengthNa(), o.params.toksvigMapPower));
        break;
    case TextureRole::LeanB:
        slopeMeanRow(v.bx.data(), v.by.data(), invB2, width, 2, px);
        break;
    case TextureRole::Clean:
        slopeMeanRow(v.bx.data(), v.by.data(), invB2, width, 3, px);
        for (int x = 0; x < width; ++x)
            px[3 * x + 2] = unit((0.5 * (v.mxx[size_t(x)] + v.myy[size_t(x)]) + v.invBase[size_t(x)]) * invM);
        break;
    case TextureRole::LeanM:
        leanMRow(v.mxx.data(), v.myy.data(), v.mxy.data(), v.invBase.data(), invM, invM2, width, px);
        break;
    case TextureRole::LeanGloss:
        leanGlossRow(v.cxx.data(), v.cyy.data(), v.cxy.data(), v.invBase.data(), width, px);
        break;
    case TextureRole::Detail: // no method's row names it: detail.cpp bakes it
        break;
    case TextureRole::MixtureWeights:
    case TextureRole::MixtureLobe0:
    case TextureRole::MixtureLobe1:
    case TextureRole::MixtureLobe2:
    case TextureRole::MixtureLobe3:
    case TextureRole::MixtureCross:
        if (plan.mixture) break; // bakeLevel writes them all at once (mixtureRows)
        // K = 1: one lobe of weight 1 with LEAN's moments B and M + I/s (leanMRow's values).
        for (int x = 0; x < width; ++x, px += 4) {
            const double invS = v.invBase[size_t(x)];
            if (role == TextureRole::MixtureWeights) {
                px[0] = 1.0f, px[1] = px[2] = px[3] = 0.0f;
            } else if (role == TextureRole::MixtureCross) {
                px[0] = unit(v.mxy[size_t(x)] * invM2 + 0.5), px[1] = px[2] = px[3] = 0.5f;
            } else {
                px[0] = unit(v.bx[size_t(x)] * invB2 + 0.5);
                px[1] = unit(v.by[size_t(x)] * invB2 + 0.5);
                px[2] = unit((v.mxx[size_t(x)] + invS) * invM);
                px[3] = unit((v.myy[size_t(x)] + invS) * invM);
            }
        }
        break;
    }
    return counts;
}

// Whether a bake reads the pyramid's filtered moments: every method but a mixture of K >= 2 lobes,
// whose lobes come from its own pyramid, baking only its own roles.
bool readsMomentRows(const BakeOptions& options) {
    if (options.method != Method::Mixture || std::clamp(options.params.mixtureLobes, 1, kMaxMixtureLobes) < 2)
        return true;
    for (const MethodTexture& m : methodSpec(options.method).textures)
        if (bakesRole(options, m.role) && !isMixtureRole(m.role)) return true;
    return false;
}

// Level k of every texture, each row from its filtered moments as they stream out of the pyramid,
// one role at a time, so each inner loop does one texture's arithmetic.
void bakeLevel(const RowPlan& plan, const NormalPyramid& pyramid, int k, BakeOutput& out) {
    const PyramidLevel& level = pyramid.level(k);
    const BakeOptions& o = plan.options;
    if (plan.constantGloss && plan.producesGloss) {
        const size_t texels = size_t(level.width) * size_t(level.height);
        if (o.basePower < plan.glossMinPower) out.stats.glossClampedLow += texels;
        if (o.basePower > plan.glossMaxPower) out.stats.glossClampedHigh += texels;
    }
    for (auto& tex : out.textures) {
        auto& mip = tex.mips[size_t(k)];
        mip.width = level.width;
        mip.height = level.height;
        const size_t values = size_t(level.width) * size_t(level.height) * size_t(tex.channels);
        if (tex.storage == TexelStorage::Unorm8)
            mip.unorm8.resize(values);
        else if (tex.storage == TexelStorage::Unorm16)
            mip.unorm16.resize(values);
        else if (tex.storage == TexelStorage::Half)
            mip.halfBits.resize(values);
        else
            mip.texels.resize(values);
    }
    std::vector<ClampCounts> rowCounts(size_t(level.height));
    // Codes: a row's floats go to a scratch row first and are then quantized as the export would.
    auto storeCodes = [k](BakedTexture& tex, size_t at, size_t count, const float* px) {
        TextureMip& mip = tex.mips[size_t(k)];
        if (tex.storage == TexelStorage::Unorm8)
            for (size_t i = 0; i < count; ++i)
                mip.unorm8[at + i] = unorm8(px[i]);
        else if (tex.storage == TexelStorage::Unorm16)
            for (size_t i = 0; i < count; ++i)
                mip.unorm16[at + i] = unorm16(px[i]);
        else if (tex.storage == TexelStorage::Half)
            halfCodes(px, count, &mip.halfBits[at]);
    };
    // Row y of every role; `row` is the filtered moments of the row, null when no role reads them.
    auto bakeRow = [&](int y, const NormalMoments* row) {
        const int width = level.width;
        const size_t first = size_t(y) * size_t(width);
        thread_local RowValues values;
        if (row) values.fill(plan, k, y, row, width);
        if (plan.mixture) {
            // Every mixture role in one pass (four channels each), then each stored.
            thread_local std::array<std::vector<float>, kMixtureRoles> scratch;
            std::array<float*, kMixtureRoles> px{};
            for (size_t r = 0; r < plan.roles.size(); ++r) {
                const int i = mixtureSlot(plan.roles[r]);
                BakedTexture& tex = out.textures[r];
                if (i < 0) continue;
                if (tex.storage == TexelStorage::Float) {
                    px[size_t(i)] = &tex.mips[size_t(k)].texels[first * 4];
                } else {
                    scratch[size_t(i)].resize(size_t(width) * 4);
                    px[size_t(i)] = scratch[size_t(i)].data();
                }
            }
            mixtureRows(plan, k, y, width, px);
            for (size_t r = 0; r < plan.roles.size(); ++r) {
                const int i = mixtureSlot(plan.roles[r]);
                if (i >= 0 && out.textures[r].storage != TexelStorage::Float)
                    storeCodes(out.textures[r], first * 4, size_t(width) * 4, px[size_t(i)]);
            }
        }
        for (size_t r = 0; r < plan.roles.size(); ++r) {
            BakedTexture& tex = out.textures[r];
            if (plan.mixture && mixtureSlot(plan.roles[r]) >= 0) continue; // written above
            TextureMip& mip = tex.mips[size_t(k)];
            const size_t at = first * size_t(tex.channels), count = size_t(width) * size_t(tex.channels);
            thread_local std::vector<float> scratch;
            if (tex.storage != TexelStorage::Float) scratch.resize(count);
            float* px = tex.storage == TexelStorage::Float ? &mip.texels[at] : scratch.data();
            const ClampCounts c = writeRoleRow(plan, plan.roles[r], row, values, width, px);
            storeCodes(tex, at, count, px);
            rowCounts[size_t(y)].low += c.low;
            rowCounts[size_t(y)].high += c.high;
        }
    };
    // The mixture's lobes (K >= 2) come from its own pyramid: a level of mixture roles only needs no
    // filtered moments.
    if (readsMomentRows(o))
        pyramid.forEachMomentRow(k, bakeRow);
    else
        tbb::parallel_for(0, level.height, [&](int y) { bakeRow(y, nullptr); });
    for (const ClampCounts& c : rowCounts) {
        out.stats.glossClampedLow += c.low;
        out.stats.glossClampedHigh += c.high;
    }
}

} // namespace

namespace {

// The authored power of every finest texel (the mixture's and the fitted lobe's truth), or none.
std::optional<std::vector<double>> authoredTexelPowers(const BakeOptions& options) {
    if (!options.authoredGloss) return std::nullopt;
    std::vector<double> powers(options.authoredGloss->size());
    for (size_t i = 0; i < powers.size(); ++i)
        powers[i] = options.encoding.power((*options.authoredGloss)[i]);
    return powers;
}

// Whether a bake with `largestLevel` skips level k of its `levels` (BakeOptions::largestLevel: wider
// or taller than the limit, and never the last level).
bool skipsLevel(const PyramidLevel& level, int k, int levels, int largestLevel) {
    return largestLevel > 0 && k + 1 < levels && std::max(level.width, level.height) > largestLevel;
}

} // namespace

Result<BakeOutput> bakeShape(const BakeOptions& options, int width, int height) {
    if (width < 1 || height < 1) return Error{"a bake needs a map of at least 1x1 texels"};
    if (const Status s = checkBakeOptions(options); !s) return Error{s.error()};
    BakeOutput shape;
    shape.method = options.method;
    // The method table's textures with a flat map's decodes: no slope, the base power (an authored
    // gloss map is not read).
    shape.textures = planTextures(
        options, storesSlopes(options.method) ? slopeScalesFor(0.0f, options.basePower) : ChannelScales{});
    const auto sizes = mipChainSizes(width, height, options.mipCount);
    for (auto& t : shape.textures) {
        t.mips.assign(sizes.size(), TextureMip{});
        for (size_t k = 0; k < sizes.size(); ++k) {
            t.mips[k].width = sizes[k].first;
            t.mips[k].height = sizes[k].second;
        }
    }
    shape.stats.mipCount = int(sizes.size());
    return shape;
}

Result<BakeOutput> bake(const NormalMap& map, const BakeOptions& options) {
    if (const Status s = checkBakeInput(map, options); !s) return Error{s.error()};

    BakeOutput out;
    out.method = options.method;
    auto start = Clock::now();
    // The caller's pyramid, or one of its own with only the moments the method reads (the rest are
    // most of the pyramid's work), whose levels are freed as they are baked.
    std::optional<NormalPyramid> own;
    if (const NormalPyramid* given = options.cachedPyramid.get()) {
        const PyramidOptions& p = given->options();
        const unsigned needed = momentsNeeded(options.method);
        if (&given->finest() != &map) return Error{"the pyramid given is of another normal map"};
        if (p.border != options.pyramid.border || p.kernel != options.pyramid.kernel)
            return Error{"the pyramid given has another border or kernel than the bake's"};
        if ((p.moments & needed) != needed || (!p.boxMoments && readsMomentRows(options)))
            return Error{"the pyramid given lacks moments the method reads"};
    } else {
        const std::shared_ptr<const NormalMap> borrowed(&map, [](const NormalMap*) {});
        PyramidOptions pyramidOptions = options.pyramid;
        pyramidOptions.moments = momentsNeeded(options.method);
        pyramidOptions.boxMoments = readsMomentRows(options);
        own.emplace(NormalPyramid::build(borrowed, pyramidOptions));
    }
    const NormalPyramid& pyramid = own ? *own : *options.cachedPyramid;
    std::optional<BaseVariancePyramid> base;
    if (options.authoredGloss) {
        base.emplace(pyramid);
        base->build(*options.authoredGloss, options.encoding);
    }
    out.stats.pyramidSeconds = seconds(start);
    start = Clock::now();

    const int levels =
        options.mipCount > 0 ? std::min(options.mipCount, pyramid.levelCount()) : pyramid.levelCount();
    out.stats.mipCount = levels;
    const ChannelScales scales = storesSlopes(options.method) ? slopeScales(map, options) : ChannelScales{};
    out.textures = planTextures(options, scales);
    for (auto& tex : out.textures)
        tex.mips.resize(size_t(levels));
    // The mixture's lobes (K >= 2) from the finest normals, each with its authored power.
    std::optional<MixturePyramid> mixture;
    const int lobes = std::clamp(options.params.mixtureLobes, 1, kMaxMixtureLobes);
    if (options.method == Method::Mixture && lobes > 1) {
        const std::optional<std::vector<double>> powers = authoredTexelPowers(options);
        const std::vector<double>* texelPowers = powers ? &*powers : nullptr;
        mixture.emplace(
            options.params.mixtureShadedFit
                ? buildShadedMixture(pyramid, options.basePower, lobes, levels - 1, texelPowers)
                : MixturePyramid::build(pyramid, options.basePower, lobes, levels - 1, texelPowers));
    }
    // The fitted lobe's powers, fitted under the BRDF the preset's engine shades with.
    std::optional<FittedPyramid> fitted;
    if (options.method == Method::Fitted && bakesRole(options, TextureRole::Gloss)) {
        const std::optional<std::vector<double>> powers = authoredTexelPowers(options);
        FittedLobeOptions fit;
        fit.brdf = glossBrdf(options.encoding);
        // The levels the bake skips (largestLevel) are not fitted: a cached pyramid has released them.
        while (fit.firstLevel < levels - 1 &&
               skipsLevel(pyramid.level(fit.firstLevel), fit.firstLevel, levels, options.largestLevel))
            ++fit.firstLevel;
        const BaseVariancePyramid* b = base ? &*base : nullptr;
        fitted.emplace(FittedPyramid::build(
            pyramid, [&](int k, int x, int y) { return b ? b->power(k, x, y) : options.basePower; },
            powers ? &*powers : nullptr, options.basePower, levels - 1, fit));
    }
    RowPlan plan(options, base ? &*base : nullptr, mixture ? &*mixture : nullptr, out.textures, scales);
    plan.fitted = fitted ? &*fitted : nullptr;
    plan.finestMap = &map;
    // Progress by texels: the pyramids as the finest level's, then each level baked.
    auto baked = [&](int k) {
        const PyramidLevel& level = pyramid.level(k);
        return skipsLevel(level, k, levels, options.largestLevel)
                   ? 0.0
                   : double(level.width) * double(level.height);
    };
    // A given pyramid cost this bake nothing: only the levels count then.
    double total = own ? double(map.texelCount()) : 0.0, done = total;
    for (int k = 0; k < levels; ++k)
        total += baked(k);
    auto carryOn = [&]() {
        return !options.progress || options.progress(total > 0.0 ? std::min(done / total, 1.0) : 1.0);
    };
    const Error cancelled{"cancelled"};
    if (!carryOn()) return cancelled;
    // A given pyramid must hold every level this bake computes (bakePyramid releases the larger ones).
    for (int k = 1; !own && readsMomentRows(options) && k < levels; ++k)
        if (baked(k) > 0.0 && pyramid.level(k).box.empty())
            return Error{"the pyramid given has released level " + std::to_string(k) +
                         ", which this bake computes"};
    auto bakeAndRelease = [&](int k) {
        const PyramidLevel& level = pyramid.level(k);
        if (skipsLevel(level, k, levels, options.largestLevel)) {
            for (auto& tex : out.textures)
                tex.mips[size_t(k)].width = level.width, tex.mips[size_t(k)].height = level.height;
        } else {
            bakeLevel(plan, pyramid, k, out);
        }
        // Level k's moments and lobes are read by nothing after its textures (a given pyramid is
        // the caller's, kept).
        if (own) own->releaseBox(k);
        if (mixture && k > 0) mixture->releaseLevel(k);
        if (fitted && k > 0) fitted->releaseLevel(k);
    };
    // Level 0 last: each level's textures depend on its own moments alone, and level 0's come from
    // the normals, so by then every coarser level's moments (and the mixture's lobes) are freed and
    // the peak holds the finest textures beside the normals, not beside the whole pyramid.
    for (int k = 1; k < levels; ++k) {
        bakeAndRelease(k);
        done += baked(k);
        if (!carryOn()) return cancelled;
    }
    bakeAndRelease(0);
    done += baked(0);
    if (!carryOn()) return cancelled;
    out.stats.methodSeconds = seconds(start);
    return out;
}

std::shared_ptr<const NormalPyramid> bakePyramid(std::shared_ptr<const NormalMap> map,
                                                 const BakeOptions& options, unsigned moments) {
    PyramidOptions pyramidOptions = options.pyramid;
    pyramidOptions.moments = moments;
    auto pyramid = std::make_shared<NormalPyramid>(NormalPyramid::build(std::move(map), pyramidOptions));
    // The levels a bake with this largestLevel skips.
    for (int k = 0; k < pyramid->levelCount(); ++k)
        if (skipsLevel(pyramid->level(k), k, pyramid->levelCount(), options.largestLevel))
            pyramid->releaseBox(k);
    return pyramid;
}

} // namespace burnish
