// Export: round trips through every format (read back with OpenImageIO), DDS block compression
// within its tolerance, full mip chains, the presets' documented conversions, precision and
// Toksvig refusals, all-or-nothing writes and byte-identical output.
#include <burnish/core/bake/export.h>

#include <burnish/core/bake/detail.h>
#include <burnish/core/util/files.h>

#include "temp_dir.h"

#include <Imath/half.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>

namespace burnish {
namespace {

namespace fs = std::filesystem;
using burnish::test::TempDir;

// Storage tolerances on a stored value in [0, 1]: half a code of round-to-nearest, plus float noise.
constexpr double kFloatNoise = 1e-6;
constexpr double kUint8Tolerance = 0.5 / 255.0 + kFloatNoise;
constexpr double kUint16Tolerance = 0.5 / 65535.0 + kFloatNoise;
// Half keeps 11 significant bits: relative rounding error 2^-11 on values <= 1.
constexpr double kHalfTolerance = 1.0 / 2048.0;
// Block compression on the smooth test map. BC4 (and BC5, two BC4 blocks; BC3's alpha) stores
// 8 levels between 8-bit endpoints per 4x4 block: the error is at most half a level of the
// block's range plus rounding, a few 8-bit codes on this map (measured: at most 2.7 codes).
constexpr double kBc4Tolerance = 4.0 / 255.0;
// BC3's colour is BC1: 4 colours on one segment per 4x4 block with 5:6:5 endpoints. A block whose
// normals span a plane (x and y both varying) keeps only the segment, so the bound is the block's
// own colour extent plus the endpoints' slack: least-squares endpoints rounded to 5 bits may sit
// up to two 5-bit steps outside the block's box (measured on this map: up to 49 codes in y at
// mip 2, where a block covers a quarter period of both sines; at most 0.0073 beyond one step).
constexpr double kBc1EndpointSlack = 2.0 / 31.0;

// A smooth bumpy normal map (low-frequency sines), not a power of two, so mips round down.
NormalMap smoothMap(int w = 40, int h = 24) {
    std::vector<glm::vec3> n(size_t(w) * size_t(h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float sx = 0.35f * std::sin(2.0f * 3.14159265f * float(x) / float(w));
            const float sy = 0.25f * std::cos(2.0f * 3.14159265f * float(y) / float(h));
            n[size_t(y) * size_t(w) + size_t(x)] = glm::vec3(sx, sy, 1.0f);
        }
    return makeNormalMap(w, h, std::move(n));
}

NormalMap flatMap(int w, int h) {
    return makeNormalMap(w, h, std::vector<glm::vec3>(size_t(w) * size_t(h), glm::vec3(0.0f, 0.0f, 1.0f)));
}

BakeOutput bakeWith(const NormalMap& map, Method method, const Preset& preset, double power = 256.0) {
    BakeOptions options;
    options.method = method;
    options.encoding = preset.encoding;
    options.basePower = power;
    auto out = bake(map, options);
    EXPECT_TRUE(out) << out.error();
    return std::move(out.value());
}

Preset preset(const char* name) {
    auto p = findPreset(name);
    EXPECT_TRUE(p) << p.error();
    return std::move(p.value());
}

struct ReadMip {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<float> values;
};

// Every MIP level of a file (subimage 0, levels 0..n) as OpenImageIO decodes it.
std::vector<ReadMip> readMips(const fs::path& path) {
    std::vector<ReadMip> mips;
    // Alpha is data here: read it unassociated, as an engine's importer does.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path.string(), &config);
    EXPECT_TRUE(in) << "cannot read back " << path << ": " << OIIO::geterror();
    if (!in) return mips;
    for (int k = 0; in->seek_subimage(0, k); ++k) {
        const OIIO::ImageSpec& s = in->spec();
        ReadMip m{s.width, s.height, s.nchannels,
                  std::vector<float>(size_t(s.width) * size_t(s.height) * size_t(s.nchannels))};
        EXPECT_TRUE(in->read_image(0, k, 0, s.nchannels, OIIO::TypeDesc::FLOAT, m.values.data()))
            << in->geterror();
        mips.push_back(std::move(m));
    }
    return mips;
}

// All levels of an exported file: one multi-level file, or one file per level.
std::vector<ReadMip> readExported(const fs::path& dir, const ExportedFile& file) {
    if (file.paths.size() == 1) return readMips(dir / file.paths[0]);
    std::vector<ReadMip> mips;
    for (const auto& p : file.paths) {
        auto one = readMips(dir / p);
        EXPECT_EQ(one.size(), 1u) << p;
        if (!one.empty()) mips.push_back(std::move(one[0]));
    }
    return mips;
}

// The value an exported channel should hold at texel t of level k.
double expectedStored(const BakeOutput& b, const Preset& p, const ExportedChannel& c, size_t k, size_t t) {
    if (c.value) return *c.value;
    const BakedTexture* tex = b.find(*roleFromName(c.role));
    int index = 0;
    while (tex->decode[size_t(index)].name != c.source)
        ++index;
    const double v = tex->mips[k].texels[t * size_t(tex->channels) + size_t(index)];
    const bool flip = p.green == GreenConvention::DirectX && (c.source == "normal.y" || c.source == "B.y" ||
                                                              c.source == "M.xy" || c.source == "rho");
    return flip ? 1.0 - v : v;
}

double storageTolerance(const ExportedFile& f) {
    if (f.storage == "uint8") return kUint8Tolerance;
    if (f.storage == "uint16") return kUint16Tolerance;
    if (f.storage == "half") return kHalfTolerance;
    if (f.storage == "float") return kFloatNoise;
    return kBc4Tolerance; // bc4, bc5, bc3's alpha; bc3's colour: see bc1Tolerance
}

// The largest extent of any colour channel (the first three) within texel t's 4x4 block.
double blockColourExtent(const std::vector<float>& expected, int w, int h, int channels, size_t t) {
    const int bx = int(t % size_t(w)) / 4 * 4, by = int(t / size_t(w)) / 4 * 4;
    double extent = 0.0;
    for (int c = 0; c < std::min(channels, 3); ++c) {
        double lo = 1.0, hi = 0.0;
        for (int y = by; y < std::min(by + 4, h); ++y)
            for (int x = bx; x < std::min(bx + 4, w); ++x) {
                const double v = expected[(size_t(y) * size_t(w) + size_t(x)) * size_t(channels) + size_t(c)];
                lo = std::min(lo, v);
                hi = std::max(hi, v);
            }
        extent = std::max(extent, hi - lo);
    }
    return extent;
}

// Compares every level and channel of every exported file with the bake; returns the largest error.
double checkRoundTrip(const fs::path& dir, const BakeOutput& b, const Preset& p, const ExportResult& r) {
    double worst = 0.0;
    for (const auto& f : r.files) {
        const auto mips = readExported(dir, f);
        EXPECT_EQ(mips.size(), b.textures[0].mips.size()) << f.name << ": not every mip level is present";
        for (size_t k = 0; k < mips.size() && k < b.textures[0].mips.size(); ++k) {
            EXPECT_EQ(mips[k].width, b.textures[0].mips[k].width) << f.name << " mip " << k;
            EXPECT_EQ(mips[k].height, b.textures[0].mips[k].height) << f.name << " mip " << k;
            EXPECT_EQ(mips[k].channels, f.storedChannels) << f.name << " mip " << k;
            const size_t n = size_t(mips[k].width) * size_t(mips[k].height);
            const size_t nc = f.channels.size();
            std::vector<float> expected(n * nc);
            for (size_t t = 0; t < n; ++t)
                for (size_t c = 0; c < nc; ++c)
                    expected[t * nc + c] = float(expectedStored(b, p, f.channels[c], k, t));
            for (size_t c = 0; c < nc; ++c) {
                const bool bc1Colour = f.storage == "bc3" && c < 3;
                // Error beyond each texel's bound (its storage's, or for BC1 colour its block's).
                double channelWorst = 0.0, excess = 0.0;
                for (size_t t = 0; t < n; ++t) {
                    const double got = mips[k].values[t * size_t(mips[k].channels) + c];
                    const double err = std::abs(got - expected[t * nc + c]);
                    const double bound =
                        bc1Colour ? blockColourExtent(expected, mips[k].width, mips[k].height, int(nc), t) +
                                        kBc1EndpointSlack
                                  : storageTolerance(f);
                    channelWorst = std::max(channelWorst, err);
                    excess = std::max(excess, err - bound);
                }
                EXPECT_LE(excess, 0.0) << f.name << " (" << f.storage << ") mip " << k << " channel "
                                       << f.channels[c].source << ": worst error " << channelWorst;
                worst = std::max(worst, channelWorst);
            }
        }
    }
    return worst;
}

std::vector<std::string> listFolder(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

bool hasTemporaries(const fs::path& dir) {
    for (const auto& name : listFolder(dir))
        if (name.find(".tmp-") != std::string::npos || name.rfind(kStagingPrefix, 0) == 0) return true;
    return false;
}

TEST(Export, RoundTripThroughEveryFormat) {
    const NormalMap map = smoothMap();
    const std::vector<std::pair<ExportFormat, std::optional<DdsCompression>>> formats{
        {ExportFormat::Png8, {}},      {ExportFormat::Png16, {}},
        {ExportFormat::Tga, {}},       {ExportFormat::ExrHalf, {}},
        {ExportFormat::ExrFloat, {}},  {ExportFormat::Tiff16, {}},
        {ExportFormat::TiffFloat, {}}, {ExportFormat::Dds, DdsCompression::Rgba8},
    };
    // unity: 3- and 4-channel files with a parameter and constants; godot: a 1-channel file;
    // unreal: DirectX green; lean: 2- and 3-channel high-precision files.
    for (const char* name : {"unity", "godot", "unreal", "lean"}) {
        const Preset p = preset(name);
        const BakeOutput b = bakeWith(map, p.method, p);
        for (const auto& [format, compression] : formats) {
            SCOPED_TRACE(std::string(name) + " " + std::string(exportFormatName(format)));
            TempDir dir;
            ExportOptions o;
            o.format = format;
            o.compression = compression;
            o.stem = "map";
            o.allowEightBit = true;
            o.parameters["metallic"] = 0.75;
            if (!p.findParameter("metallic")) o.parameters.clear();
            const auto r = exportBake(b, p, o, dir.path());
            ASSERT_TRUE(r) << r.error();
            EXPECT_TRUE(fs::exists(dir / "bake.json"));
            checkRoundTrip(dir.path(), b, p, *r);
            EXPECT_FALSE(hasTemporaries(dir.path()));
        }
    }
}

TEST(Export, OneFilePerMipForPngAndTga) {
    const NormalMap map = smoothMap(40, 24); // 40x24, 20x12, 10x6, 5x3, 2x1, 1x1
    const Preset p = preset("godot");
    const BakeOutput b = bakeWith(map, p.method, p);
    ASSERT_EQ(b.stats.mipCount, 6);
    TempDir dir;
    ExportOptions o;
    o.stem = "m";
    const auto r = exportBake(b, p, o, dir.path());
    ASSERT_TRUE(r) << r.error();
    const std::vector<std::string> expected{"bake.json",
                                            "m_normal.png",
                                            "m_normal_mip1.png",
                                            "m_normal_mip2.png",
                                            "m_normal_mip3.png",
                                            "m_normal_mip4.png",
                                            "m_normal_mip5.png",
                                            "m_roughness.png",
                                            "m_roughness_mip1.png",
                                            "m_roughness_mip2.png",
                                            "m_roughness_mip3.png",
                                            "m_roughness_mip4.png",
                                            "m_roughness_mip5.png"};
    EXPECT_EQ(listFolder(dir.path()), expected);
}

TEST(Export, DdsBlockCompressionWithinTolerance) {
    const NormalMap map = smoothMap(64, 32);
    struct Case {
        const char* preset;
        const char* file;
        DdsCompression compression;
        int storedChannels;
    };
    for (const Case& c :
         {Case{"godot", "roughness", DdsCompression::Bc4, 1}, Case{"godot", "normal", DdsCompression::Bc5, 2},
          Case{"exp2", "normal", DdsCompression::Bc3, 4}}) {
        SCOPED_TRACE(std::string(c.preset) + " " + c.file);
        const Preset p = preset(c.preset);
        // Variance-to-gloss: a roughness as smooth as the map, which the per-texel bounds below assume
        // (the fitted lobe's, godot's default, changes from texel to texel and BC4 blocks spread it).
        const BakeOutput b = bakeWith(map, Method::VarianceToGloss, p);
        TempDir dir;
        ExportOptions o;
        o.format = ExportFormat::Dds;
        const auto r = exportBake(b, p, o, dir.path());
        ASSERT_TRUE(r) << r.error();
        for (const auto& f : r->files) {
            if (f.name != c.file) continue;
            EXPECT_EQ(f.compression, c.compression);
            EXPECT_EQ(f.storedChannels, c.storedChannels);
            ASSERT_EQ(f.paths.size(), 1u);
            const auto mips = readMips(dir / f.paths[0]);
            EXPECT_EQ(int(mips.size()), b.stats.mipCount) << "DDS mip count";
        }
        const double worst = checkRoundTrip(dir.path(), b, p, *r);
        // Block compression is lossy but not free: a zero error would mean the check read nothing.
        EXPECT_GT(worst, 0.0);
    }
}

TEST(Export, DdsMipCountFollowsAShortChain) {
    const Preset p = preset("godot");
    BakeOptions options;
    options.method = p.method;
    options.encoding = p.encoding;
    options.mipCount = 3;
    const auto b = bake(smoothMap(32, 32), options);
    ASSERT_TRUE(b);
    // Every compression that holds the one-channel gloss.
    for (DdsCompression c : {DdsCompression::Bc4, DdsCompression::Bc3, DdsCompression::Rgba8}) {
        const std::vector<TextureMip>& mips = b->find(TextureRole::Gloss)->mips;
        const auto bytes = encodeDds(mips, 1, c);
        ASSERT_TRUE(bytes) << bytes.error();
        TempDir dir;
        ASSERT_TRUE(writeFileAtomic(dir / "g.dds", *bytes));
        const auto read = readMips(dir / "g.dds");
        ASSERT_EQ(read.size(), 3u) << ddsCompressionName(c);
        EXPECT_EQ(read[2].width, 8);
    }
}

// An 8-bit DDS stores unorm8's code, as PNG and TGA do: the float product v·255 rounds the 127
// floats in [0, 1] just below (k + 1/2)/255, k >= 128, up to a tie, which lround took to k + 1.
TEST(Export, DdsCodesAreThePngCodes) {
    for (float v : {0.503921568f, 0.519607842f, 0.5f, 1.0f, 0.0f, 0.25f}) {
        SCOPED_TRACE(v);
        const TextureMip level{1, 1, TexelVector{v}};
        const auto bytes = encodeDds({level}, 1, DdsCompression::Rgba8);
        ASSERT_TRUE(bytes) << bytes.error();
        ASSERT_GT(bytes->size(), 128u);
        EXPECT_EQ(std::uint8_t((*bytes)[128]), unorm8(v)); // the texel's first byte after the header
    }
    EXPECT_EQ(unorm8(0.503921568f), 128);
}

// The streaming encoder reads each level a block of texels at a time: every texel of every level
// lands in the file where it belongs, read back from the uncompressed layouts (rgba8: a 128-byte
// header, then B, G, R, A bytes; rgba16f: a 148-byte DX10 header, then R, G, B, A halves). Level 0
// has more texels than one block. A chain longer than the map's is refused.
TEST(Export, StreamingDdsWritesEveryTexelOfEveryLevel) {
    const auto sizes = mipChainSizes(100, 70);
    auto value = [](size_t k, size_t texel, size_t c) {
        return float((texel * 37 + c * 53 + k * 11) % 101) / 100.0f;
    };
    size_t reads = 0;
    const DdsLevelReader read = [&](size_t k, size_t begin, size_t end, float* out) {
        ++reads;
        for (size_t t = begin; t < end; ++t)
            for (size_t c = 0; c < 2; ++c)
                out[(t - begin) * 2 + c] = value(k, t, c);
    };
    const auto rgba8 = encodeDds(100, 70, int(sizes.size()), 2, DdsCompression::Rgba8, read);
    ASSERT_TRUE(rgba8) << rgba8.error();
    EXPECT_GT(reads, sizes.size()) << "level 0 takes more than one block";
    const auto halves = encodeDds(100, 70, int(sizes.size()), 2, DdsCompression::Rgba16f, read);
    ASSERT_TRUE(halves) << halves.error();
    size_t at8 = 128, at16 = 148;
    for (size_t k = 0; k < sizes.size(); ++k) {
        const size_t n = size_t(sizes[k].first) * size_t(sizes[k].second);
        ASSERT_LE(at8 + n * 4, rgba8->size());
        ASSERT_LE(at16 + n * 8, halves->size());
        for (size_t t = 0; t < n; ++t) {
            const auto byte = [&](size_t i) { return std::uint8_t((*rgba8)[at8 + t * 4 + i]); };
            ASSERT_EQ(byte(0), 0) << "blue of a two-channel texture, level " << k << " texel " << t;
            ASSERT_EQ(byte(1), unorm8(value(k, t, 1))) << "level " << k << " texel " << t;
            ASSERT_EQ(byte(2), unorm8(value(k, t, 0))) << "level " << k << " texel " << t;
            ASSERT_EQ(byte(3), 255);
            const auto half = [&](size_t i) {
                const size_t b = at16 + t * 8 + i * 2;
                return std::uint16_t(std::uint8_t((*halves)[b]) | (std::uint8_t((*halves)[b + 1]) << 8));
            };
            ASSERT_EQ(half(0), halfCode(value(k, t, 0)).bits()) << "level " << k << " texel " << t;
            ASSERT_EQ(half(1), halfCode(value(k, t, 1)).bits()) << "level " << k << " texel " << t;
            ASSERT_EQ(half(2), halfCode(0.0f).bits());
            ASSERT_EQ(half(3), halfCode(1.0f).bits());
        }
        at8 += n * 4;
        at16 += n * 8;
    }
    EXPECT_EQ(at8, rgba8->size());
    EXPECT_EQ(at16, halves->size());
    const auto tooLong = encodeDds(100, 70, int(sizes.size()) + 1, 2, DdsCompression::Rgba8, read);
    ASSERT_FALSE(tooLong);
    EXPECT_NE(tooLong.error().find("chain of"), std::string::npos) << tooLong.error();
}

TEST(Export, EncodeDdsRejectsBadChains) {
    TextureMip top{8, 8, TexelVector(64, 0.5f)};
    TextureMip wrong{3, 4, TexelVector(12, 0.5f)};
    const auto r = encodeDds({top, wrong}, 1, DdsCompression::Bc4);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("not half"), std::string::npos) << r.error();
    EXPECT_FALSE(encodeDds({top}, 2, DdsCompression::Bc4));
}

// Each preset's gloss channel, read back from its default format, equals the documented
// conversion of the baked power within the storage's quantization. The formulas are written here
// independently of gloss.cpp.
TEST(Export, PresetsDecodeThroughTheirDocumentedFormula) {
    const NormalMap map = flatMap(8, 8);
    const auto alphaOf = [](double p) { return std::sqrt(2.0 / (p + 2.0)); }; // GGX α of Blinn-Phong p
    for (const auto& p : builtinPresets()) {
        for (double power : {16.0, 256.0, 2000.0}) {
            SCOPED_TRACE(p.name + " power " + std::to_string(power));
            const BakeOutput b = bakeWith(map, p.method, p, power);
            TempDir dir;
            ExportOptions o;
            o.stem = "flat";
            const auto r = exportBake(b, p, o, dir.path());
            ASSERT_TRUE(r) << r.error();
            // The channel that carries the power, and its documented stored value.
            const std::string source = p.method == Method::Lean      ? "gloss.x"
                                       : p.method == Method::Clean   ? "M.avg"
                                       : p.method == Method::Mixture ? "wM.xx"
                                                                     : "gloss";
            double expected = 0.0;
            const std::string enc = p.encoding.name();
            if (p.method == Method::Lean)
                expected = std::log2(power) / 13.0; // Σ = 1/p, g = log2(1/Σ)/13
            else if (enc == "blackops")
                expected = std::log2(power) / 13.0; // p = 8192^g
            else if (enc == "exp2")
                expected = (std::log2(power) - 1.0) / 10.0; // p = exp2(10g + 1)
            else if (enc == "ggx-roughness")
                expected = std::sqrt(alphaOf(power)); // r = sqrt(α)
            else if (enc == "smoothness")
                expected = 1.0 - std::sqrt(alphaOf(power)); // 1 − r
            bool found = false;
            for (const auto& f : r->files)
                for (size_t c = 0; c < f.channels.size(); ++c) {
                    if (f.channels[c].source != source) continue;
                    // A flat map's one lobe is the mixture's lobe 0 (the others have no weight).
                    if (p.method == Method::Mixture && f.name != "mixture-lobe0") continue;
                    found = true;
                    const auto mips = readExported(dir.path(), f);
                    ASSERT_FALSE(mips.empty());
                    const double stored = mips[0].values[c];
                    // A constant block compresses exactly in BC4/BC5 and BC3's alpha: 8-bit rounding is the
                    // bound.
                    const bool block = f.storage == "bc4" || f.storage == "bc5" || f.storage == "bc3";
                    const double tol = block ? kUint8Tolerance : storageTolerance(f);
                    if (p.method == Method::Clean || p.method == Method::Mixture) {
                        // M.avg = 1/p; the mixture's w·M.xx = 1/(p + 2) at weight 1 (its three lobes' base
                        // variance). Decoded with bake.json's rule: value = stored·scale + bias.
                        const double value = stored * f.channels[c].decode.scale + f.channels[c].decode.bias;
                        const double variance =
                            p.method == Method::Mixture ? 1.0 / (power + 2.0) : 1.0 / power;
                        EXPECT_NEAR(value, variance, tol * f.channels[c].decode.scale);
                    } else {
                        EXPECT_NEAR(stored, expected, tol) << f.name;
                    }
                }
            EXPECT_TRUE(found) << "no '" << source << "' channel in the preset's files";
        }
    }
}

TEST(Export, DirectXPresetFlipsGreenOnly) {
    const NormalMap map = smoothMap();
    const Preset unreal = preset("unreal");
    const BakeOutput b = bakeWith(map, unreal.method, unreal);
    TempDir dir;
    ExportOptions o;
    o.format = ExportFormat::Png16;
    const auto r = exportBake(b, unreal, o, dir.path());
    ASSERT_TRUE(r) << r.error();
    const auto mips = readExported(dir.path(), r->files[0]);
    ASSERT_FALSE(mips.empty());
    const auto& baked = b.find(TextureRole::Normal)->mips[0].texels;
    double worstX = 0.0, worstY = 0.0;
    for (size_t t = 0; t < size_t(mips[0].width * mips[0].height); ++t) {
        // Decoded with the file's own rule, y is the OpenGL y negated; x is unchanged.
        const double x = mips[0].values[t * 3 + 0] * 2.0 - 1.0;
        const double y = mips[0].values[t * 3 + 1] * 2.0 - 1.0;
        worstX = std::max(worstX, std::abs(x - (baked[t * 3 + 0] * 2.0 - 1.0)));
        worstY = std::max(worstY, std::abs(y + (baked[t * 3 + 1] * 2.0 - 1.0)));
    }
    // Two 16-bit codes in the decoded [-1, 1] range.
    constexpr double kDecodedTolerance = 2.0 * kUint16Tolerance;
    EXPECT_LE(worstX, kDecodedTolerance);
    EXPECT_LE(worstY, kDecodedTolerance);
}

TEST(Export, HighPrecisionRefusesEightBitFormats) {
    const Preset lean = preset("lean");
    const BakeOutput b = bakeWith(smoothMap(), Method::Lean, lean);
    for (ExportFormat f : {ExportFormat::Png8, ExportFormat::Tga, ExportFormat::Dds}) {
        ExportOptions o;
        o.format = f;
        const auto r = planExport(b, lean, o);
        ASSERT_FALSE(r) << exportFormatName(f);
        EXPECT_NE(r.error().find("16-bit or float"), std::string::npos) << r.error();
        o.allowEightBit = true;
        EXPECT_TRUE(planExport(b, lean, o)) << exportFormatName(f);
    }
    ExportOptions o16;
    o16.format = ExportFormat::Png16;
    EXPECT_TRUE(planExport(b, lean, o16));
}

TEST(Export, ToksvigNormalRefusesBlockCompression) {
    const Preset blackops = preset("blackops");
    const BakeOutput b = bakeWith(smoothMap(), Method::Toksvig, blackops);
    ExportOptions o; // blackops' default: dds, normal as bc5
    const auto r = planExport(b, blackops, o);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("length"), std::string::npos) << r.error();
    o.compression = DdsCompression::Bc3;
    EXPECT_FALSE(planExport(b, blackops, o));
    o.compression = DdsCompression::Rgba8;
    EXPECT_TRUE(planExport(b, blackops, o));
}

TEST(Export, RejectsWhatThePresetCannotHold) {
    const Preset godot = preset("godot");
    const BakeOutput b = bakeWith(smoothMap(), godot.method, godot);
    ExportOptions o;
    o.parameters["metallic"] = 0.5;
    auto r = planExport(b, godot, o);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("no parameter 'metallic'"), std::string::npos) << r.error();

    const Preset unity = preset("unity");
    ExportOptions range;
    range.parameters["metallic"] = 1.5;
    EXPECT_FALSE(planExport(bakeWith(smoothMap(), unity.method, unity), unity, range));

    ExportOptions bc4;
    bc4.format = ExportFormat::Dds;
    bc4.compression = DdsCompression::Bc4; // the normal has three channels
    r = planExport(b, godot, bc4);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("bc4 holds one"), std::string::npos) << r.error();

    const BakeOutput lean = bakeWith(smoothMap(), Method::Lean, godot);
    r = planExport(lean, godot, ExportOptions{});
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("methods that fit"), std::string::npos) << r.error();
}

TEST(Export, MissingFolderWritesNothing) {
    TempDir dir;
    const Preset p = preset("godot");
    const BakeOutput b = bakeWith(smoothMap(), p.method, p);
    const auto r = exportBake(b, p, ExportOptions{}, dir / "missing");
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("does not exist"), std::string::npos) << r.error();
    EXPECT_TRUE(listFolder(dir.path()).empty());
}

TEST(Export, ReadOnlyFolderWritesNothing) {
    if (::geteuid() == 0)
        GTEST_SKIP() << "root writes into read-only folders; see ExportFailureLeavesNoPartialSet";
    TempDir dir;
    const Preset p = preset("godot");
    const BakeOutput b = bakeWith(smoothMap(), p.method, p);
    ASSERT_EQ(::chmod(dir.path().c_str(), 0555), 0);
    const auto r = exportBake(b, p, ExportOptions{}, dir.path());
    ::chmod(dir.path().c_str(), 0755);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("cannot write"), std::string::npos) << r.error();
    EXPECT_TRUE(listFolder(dir.path()).empty());
}

// A directory where the second file's target should go makes its rename fail after the first
// file was renamed: the set is rolled back and no temporary remains (works as root too).
TEST(Export, ExportFailureLeavesNoPartialSet) {
    TempDir dir;
    const Preset p = preset("blackops");
    const BakeOutput b = bakeWith(smoothMap(), p.method, p);
    ExportOptions o;
    o.stem = "m";
    o.overwrite = Overwrite::Allow;
    fs::create_directories(dir / "m_gloss.dds" / "blocker");
    const auto r = exportBake(b, p, o, dir.path());
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().find("m_gloss.dds"), std::string::npos) << r.error();
    EXPECT_EQ(listFolder(dir.path()), std::vector<std::string>{"m_gloss.dds"});
    EXPECT_TRUE(fs::is_directory(dir / "m_gloss.dds" / "blocker"));
}

TEST(Export, ExistingFilesNeedOverwrite) {
    TempDir dir;
    const Preset p = preset("godot");
    const BakeOutput b = bakeWith(smoothMap(), p.method, p, 100.0);
    const BakeOutput other = bakeWith(smoothMap(), p.method, p, 1000.0);
    ExportOptions o;
    o.stem = "m";
    ASSERT_TRUE(exportBake(b, p, o, dir.path()));
    const auto before = readFile(dir / "m_roughness.png").value();

    // Refused as a whole, even though only some targets exist.
    fs::remove(dir / "m_normal.png");
    const auto refused = exportBake(other, p, o, dir.path());
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.error().find("refusing to overwrite"), std::string::npos) << refused.error();
    EXPECT_FALSE(fs::exists(dir / "m_normal.png"));
    EXPECT_EQ(readFile(dir / "m_roughness.png").value(), before);
    EXPECT_FALSE(hasTemporaries(dir.path()));

    o.overwrite = Overwrite::Allow;
    ASSERT_TRUE(exportBake(other, p, o, dir.path()));
    EXPECT_TRUE(fs::exists(dir / "m_normal.png"));
    EXPECT_NE(readFile(dir / "m_roughness.png").value(), before);
    EXPECT_FALSE(hasTemporaries(dir.path()));
}

// Replacing a set with another format and fewer mips leaves exactly the new set: the files the old
// bake.json names that the new set does not write are removed, and nothing else is touched.
TEST(Export, ReplacingLeavesExactlyTheNewSet) {
    TempDir dir, fresh;
    const Preset p = preset("godot");
    const BakeOutput b = bakeWith(smoothMap(), p.method, p);
    ExportOptions o;
    o.stem = "m";
    o.format = ExportFormat::Png8; // one file per mip: 6 levels
    ASSERT_TRUE(exportBake(b, p, o, dir.path()));
    std::ofstream(dir / "notes.txt") << "the artist's own file";
    // A hostile or stale bake.json naming files outside the folder is not followed.
    std::ofstream(fresh / "victim.txt") << "precious";

    ExportOptions smaller = o;
    smaller.format = ExportFormat::ExrHalf;
    smaller.overwrite = Overwrite::Allow;
    const BakeOutput fewer = [&] {
        BakeOptions bo;
        bo.method = p.method;
        bo.encoding = p.encoding;
        bo.basePower = 256.0;
        bo.mipCount = 2;
        return bake(smoothMap(), bo).value();
    }();
    ASSERT_TRUE(exportBake(fewer, p, smaller, dir.path()));
    std::vector<std::string> expected;
    const auto planned = planExport(fewer, p, smaller);
    ASSERT_TRUE(planned) << planned.error();
    for (const auto& f : planned->files)
        for (const auto& path : f.paths)
            expected.push_back(path);
    expected.push_back("bake.json");
    expected.push_back("notes.txt");
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(listFolder(dir.path()), expected);

    auto json = nlohmann::json::parse(readFile(dir / "bake.json").value());
    json["files"][0]["paths"].push_back((fresh / "victim.txt").string());
    json["files"][0]["paths"].push_back("../" + fresh.path().filename().string() + "/victim.txt");
    ASSERT_TRUE(writeFileAtomic(dir / "bake.json", json.dump()));
    ASSERT_TRUE(exportBake(b, p, smaller, dir.path()));
    EXPECT_EQ(readFile(fresh / "victim.txt").value(), "precious");
    EXPECT_EQ(readFile(dir / "notes.txt").value(), "the artist's own file");
}

// Same bake, same bytes: every format and DDS compression, exported twice more than a second
// apart so a timestamp in any header would show.
TEST(Export, OutputIsByteIdenticalAcrossRuns) {
    const NormalMap map = smoothMap();
    const Preset godot = preset("godot");
    const Preset exp2 = preset("exp2");
    const BakeOutput b = bakeWith(map, godot.method, godot);
    const BakeOutput be = bakeWith(map, exp2.method, exp2);
    TempDir first, second;
    auto exportAll = [&](const fs::path& root) {
        for (ExportFormat f : allExportFormats()) {
            const fs::path dir = root / std::string(exportFormatName(f));
            fs::create_directories(dir);
            ExportOptions o;
            o.format = f;
            ASSERT_TRUE(exportBake(b, godot, o, dir)); // bc5 + bc4 for dds
            if (f == ExportFormat::Dds) {
                const fs::path dir3 = root / "dds-bc3";
                fs::create_directories(dir3);
                ASSERT_TRUE(exportBake(be, exp2, o, dir3));
            }
        }
    };
    exportAll(first.path());
    std::this_thread::sleep_for(std::chrono::milliseconds(1100));
    exportAll(second.path());
    int compared = 0;
    for (const auto& e : fs::recursive_directory_iterator(first.path())) {
        if (!e.is_regular_file()) continue;
        const fs::path rel = fs::relative(e.path(), first.path());
        const auto a = readFile(e.path());
        const auto c = readFile(second.path() / rel);
        ASSERT_TRUE(a && c) << rel;
        EXPECT_EQ(*a, *c) << rel << " differs between two runs";
        ++compared;
    }
    EXPECT_GT(compared, int(allExportFormats().size()));
}

TEST(Export, BakeJsonDescribesEveryFile) {
    TempDir dir;
    const Preset p = preset("gltf");
    const NormalMap map = smoothMap();
    const BakeOutput b = bakeWith(map, p.method, p);
    BakeRecord record;
    record.inputs = {{"normalMap", "in.png"}};
    record.options = {{"power", 256}};
    NormalMapDiagnostics diagnostics;
    diagnostics.warnings.push_back("a warning");
    record.diagnostics = diagnostics;
    ExportOptions o;
    o.parameters["metallic"] = 1.0;
    const auto r = exportBake(b, p, o, dir.path(), record);
    ASSERT_TRUE(r) << r.error();
    const auto text = readFile(dir / "bake.json");
    ASSERT_TRUE(text);
    const auto j = nlohmann::json::parse(*text);
    EXPECT_EQ(j["preset"]["name"], "gltf");
    EXPECT_EQ(j["method"], "fitted"); // the gltf preset's default
    EXPECT_EQ(j["inputs"]["normalMap"], "in.png");
    EXPECT_EQ(j["warnings"][0], "a warning");
    EXPECT_EQ(j["stats"]["mipCount"], b.stats.mipCount);
    ASSERT_EQ(j["files"].size(), 2u);
    const auto& mr = j["files"][1];
    EXPECT_EQ(mr["name"], "metallicRoughness");
    EXPECT_EQ(mr["channels"][0]["value"], 1.0);
    EXPECT_EQ(mr["channels"][1]["source"], "gloss");
    EXPECT_EQ(mr["channels"][2]["value"], 1.0);
    const auto& nx = j["files"][0]["channels"][0];
    EXPECT_EQ(nx["source"], "normal.x");
    EXPECT_EQ(nx["scale"], 2.0);
    EXPECT_EQ(nx["bias"], -1.0);
    EXPECT_EQ(j["files"][0]["mips"].size(), size_t(b.stats.mipCount));
    // The file on disk is the manifest the call returned.
    EXPECT_EQ(j, r->manifest);
}

// A detail map rides along with any preset: its own file and chain, its record in bake.json.
TEST(Export, DetailFileHasItsOwnChainAndRecord) {
    const Preset p = preset("godot");
    BakeOutput b = bakeWith(smoothMap(40, 24), p.method, p); // 6 levels
    auto detail = bakeDetail(smoothMap(16, 16));             // 5 levels: 16x16 .. 1x1
    ASSERT_TRUE(detail) << detail.error();
    const BakedTexture detailTexture = detail->texture;
    b.textures.push_back(detailTexture);
    BakeRecord record;
    record.detail = DetailRecord{"d.png", detail->constantVariance, 2, 4};
    ExportOptions o;
    o.stem = "m";
    o.format = ExportFormat::Png16;
    TempDir dir;
    const auto r = exportBake(b, p, o, dir.path(), record);
    ASSERT_TRUE(r) << r.error();
    const ExportedFile& f = r->files.back();
    EXPECT_EQ(f.name, "detail");
    ASSERT_EQ(f.paths.size(), 5u);
    EXPECT_EQ(f.paths[0], "m_detail.png");
    EXPECT_EQ(f.paths[4], "m_detail_mip4.png");
    EXPECT_EQ(f.mipSizes.front(), std::make_pair(16, 16));
    EXPECT_EQ(r->files.front().mipSizes.size(), 6u); // the preset's files keep the map's chain
    const auto& j = r->manifest["detail"];
    EXPECT_EQ(j["file"], "m_detail.png");
    EXPECT_EQ(j["input"], "d.png");
    EXPECT_EQ(j["constantVariance"], detail->constantVariance);
    EXPECT_EQ(j["fade"], nlohmann::json({2, 4}));
    // Every level reads back as baked (16-bit storage).
    const auto mips = readExported(dir.path(), f);
    ASSERT_EQ(mips.size(), 5u);
    for (size_t k = 0; k < mips.size(); ++k) {
        ASSERT_EQ(mips[k].values.size(), detailTexture.mips[k].texels.size()) << k;
        for (size_t i = 0; i < mips[k].values.size(); ++i)
            EXPECT_NEAR(mips[k].values[i], detailTexture.mips[k].texels[i], kUint16Tolerance)
                << k << " " << i;
    }

    // The record and the texture come together.
    EXPECT_FALSE(planExport(b, p, o, BakeRecord{}));
    BakeOutput without = bakeWith(smoothMap(40, 24), p.method, p);
    EXPECT_FALSE(planExport(without, p, o, record));
}

TEST(Export, DetailFlipsWithDirectXAndKeepsFourChannelsInDds) {
    const Preset p = preset("unreal"); // DirectX green
    BakeOutput b = bakeWith(smoothMap(32, 32), p.method, p);
    auto detail = bakeDetail(smoothMap(8, 8));
    ASSERT_TRUE(detail);
    b.textures.push_back(detail->texture);
    BakeRecord record;
    record.detail = DetailRecord{"d.png", detail->constantVariance, 3, 6};
    ExportOptions o;
    o.format = ExportFormat::Dds;
    o.compression = DdsCompression::Bc4; // the preset's one-channel files; the detail cannot take it
    o.stem = "m";
    auto r = planExport(b, p, o, record);
    // unreal's normal has three channels, which bc4 cannot hold: use the preset's own compressions.
    ASSERT_FALSE(r);
    o.compression.reset();
    TempDir dir;
    r = exportBake(b, p, o, dir.path(), record);
    ASSERT_TRUE(r) << r.error();
    const ExportedFile& f = r->files.back();
    EXPECT_EQ(f.compression, DdsCompression::Rgba8);
    const auto mips = readMips(dir / f.paths[0]);
    ASSERT_EQ(mips.size(), 4u); // 8x8 .. 1x1
    // y is stored flipped (1 - v), x as is, to 8 bits.
    const auto& baked = detail->texture.mips[0].texels;
    for (size_t t = 0; t < 64; ++t) {
        EXPECT_NEAR(mips[0].values[t * 4 + 0], baked[t * 4 + 0], kUint8Tolerance);
        EXPECT_NEAR(mips[0].values[t * 4 + 1], 1.0 - baked[t * 4 + 1], kUint8Tolerance);
    }
    // A compression that cannot hold four channels falls back to rgba8 for the detail file, with a
    // note: toksvig-map's files all fit bc5 (a normal whose z it drops, R/G gloss and factor).
    const Preset tm = preset("toksvig-map");
    BakeOutput t = bakeWith(smoothMap(32, 32), tm.method, tm);
    t.textures.push_back(detail->texture);
    o.compression = DdsCompression::Bc5;
    const auto bc5 = planExport(t, tm, o, record);
    ASSERT_TRUE(bc5) << bc5.error();
    EXPECT_EQ(bc5->files.front().compression, DdsCompression::Bc5);
    EXPECT_EQ(bc5->files.back().compression, DdsCompression::Rgba8);
    ASSERT_EQ(bc5->files.back().notes.size(), 1u);
    EXPECT_NE(bc5->files.back().notes[0].find("stored as rgba8"), std::string::npos);
}

// The shape comes from the method table, not from a bake: for every method and preset (their params,
// storage and roles), it is what a bake of a flat map of the same size holds, texture for texture —
// role, description, channels, every decode's name, scale and bias, precision, storage, mip sizes —
// with no texel.
TEST(Export, ShapeIsAFlatMapsBakeWithoutItsTexels) {
    const NormalMap flat = makeNormalMap(12, 5, std::vector<glm::vec3>(60, glm::vec3(0.0f, 0.0f, 1.0f)));
    std::vector<BakeOptions> cases;
    for (Method m : allMethods()) {
        BakeOptions o;
        o.method = m;
        o.mipCount = 3;
        cases.push_back(o);
        o.basePower = 2.0; // the moments' scale follows a low base power (1/s above 1/16)
        o.mipCount = 0;
        cases.push_back(o);
    }
    for (const char* name : {"godot", "lean", "unity", "mixture", "filament"}) {
        const Preset p = preset(name);
        BakeOptions o;
        o.method = p.method;
        o.encoding = p.encoding;
        o.params.mixtureLobes = 3;
        o.storage[TextureRole::Gloss] = TexelStorage::Unorm8;
        cases.push_back(o);
    }
    for (const BakeOptions& o : cases) {
        SCOPED_TRACE(std::string(methodName(o.method)) + " s=" + std::to_string(o.basePower));
        const auto real = bake(flat, o);
        const auto shape = bakeShape(o, flat.width, flat.height);
        ASSERT_TRUE(real && shape) << (real ? shape.error() : real.error());
        EXPECT_EQ(shape->method, real->method);
        EXPECT_EQ(shape->stats.mipCount, real->stats.mipCount);
        ASSERT_EQ(shape->textures.size(), real->textures.size());
        for (size_t i = 0; i < real->textures.size(); ++i) {
            const BakedTexture& a = real->textures[i];
            const BakedTexture& b = shape->textures[i];
            EXPECT_EQ(b.role, a.role);
            EXPECT_EQ(b.description, a.description);
            EXPECT_EQ(b.channels, a.channels);
            EXPECT_EQ(b.needsHighPrecision, a.needsHighPrecision);
            EXPECT_EQ(b.storage, a.storage);
            ASSERT_EQ(b.decode.size(), a.decode.size());
            for (size_t c = 0; c < a.decode.size(); ++c) {
                EXPECT_EQ(b.decode[c].name, a.decode[c].name);
                EXPECT_EQ(b.decode[c].scale, a.decode[c].scale) << b.decode[c].name;
                EXPECT_EQ(b.decode[c].bias, a.decode[c].bias) << b.decode[c].name;
            }
            ASSERT_EQ(b.mips.size(), a.mips.size());
            for (size_t k = 0; k < a.mips.size(); ++k) {
                EXPECT_EQ(b.mips[k].width, a.mips[k].width);
                EXPECT_EQ(b.mips[k].height, a.mips[k].height);
                EXPECT_TRUE(b.mips[k].texels.empty() && b.mips[k].unorm8.empty() &&
                            b.mips[k].unorm16.empty() && b.mips[k].halfBits.empty());
            }
        }
    }
    BakeOptions bad;
    bad.basePower = 0.0;
    EXPECT_FALSE(bakeShape(bad, 4, 4).ok());
    EXPECT_FALSE(bakeShape(BakeOptions{}, 0, 4).ok());
}

// planExport of a bake's shape names exactly the files a real export writes.
TEST(Export, ShapePlansTheFilesOfTheRealBake) {
    const NormalMap map = smoothMap(40, 24);
    for (const char* name : {"godot", "lean", "unity"})
        for (ExportFormat format : {ExportFormat::Png8, ExportFormat::ExrHalf, ExportFormat::Dds}) {
            SCOPED_TRACE(std::string(name) + " " + std::string(exportFormatName(format)));
            const Preset p = preset(name);
            BakeOptions options;
            options.method = p.method;
            options.encoding = p.encoding;
            options.mipCount = 4;
            auto real = bake(map, options);
            auto shape = bakeShape(options, map.width, map.height);
            ASSERT_TRUE(real && shape);
            ExportOptions o;
            o.format = format;
            o.allowEightBit = true;
            const auto a = planExport(*real, p, o);
            const auto b = planExport(*shape, p, o);
            ASSERT_EQ(bool(a), bool(b)) << (a ? b.error() : a.error());
            if (!a) continue; // e.g. lean's three-channel M in dds: refused for both
            ASSERT_EQ(a->files.size(), b->files.size());
            for (size_t i = 0; i < a->files.size(); ++i) {
                EXPECT_EQ(a->files[i].paths, b->files[i].paths);
                EXPECT_EQ(a->files[i].mipSizes, b->files[i].mipSizes);
            }
        }
    EXPECT_EQ(mipChainSizes(40, 24),
              (std::vector<std::pair<int, int>>{{40, 24}, {20, 12}, {10, 6}, {5, 3}, {2, 1}, {1, 1}}));
    EXPECT_EQ(mipChainSizes(40, 24, 2).size(), 2u);
    EXPECT_TRUE(mipChainSizes(0, 4).empty());
}

std::map<std::string, std::string> filesIn(const fs::path& folder) {
    std::map<std::string, std::string> files;
    for (const auto& e : fs::directory_iterator(folder))
        if (e.is_regular_file()) files[e.path().filename().string()] = readFile(e.path()).value();
    return files;
}

// A bake made only to be exported keeps the textures its files store as 8- or 16-bit codes as
// those codes (a quarter or half of the floats' memory): the codes are the export's own (unorm8 of
// the float bake, bit for bit) and the files are byte-identical. Flipped channels (DirectX green)
// and DDS files keep floats.
TEST(Export, CompactStorageKeepsTheExportsCodesAndWritesTheSameBytes) {
    const NormalMap map = smoothMap();
    struct Case {
        const char* preset;
        std::optional<ExportFormat> format;
        std::map<TextureRole, TexelStorage> expected;
        std::optional<DdsCompression> compression = {};
    };
    const std::vector<Case> cases{
        {"godot",
         {},
         {{TextureRole::Normal, TexelStorage::Unorm8}, {TextureRole::Gloss, TexelStorage::Unorm8}}},
        {"clean", {}, {{TextureRole::Clean, TexelStorage::Unorm16}}},
        {"gltf",
         ExportFormat::Tiff16,
         {{TextureRole::Normal, TexelStorage::Unorm16}, {TextureRole::Gloss, TexelStorage::Unorm16}}},
        {"unreal", {}, {{TextureRole::Gloss, TexelStorage::Unorm8}}}, // the normal's green is flipped
        // DDS: 8-bit codes before block compression.
        {"blackops",
         {},
         {{TextureRole::Normal, TexelStorage::Unorm8}, {TextureRole::Gloss, TexelStorage::Unorm8}}},
        {"exp2",
         {},
         {{TextureRole::Normal, TexelStorage::Unorm8}, {TextureRole::Gloss, TexelStorage::Unorm8}}},
        // DDS rgba16f: half floats.
        {"lean",
         ExportFormat::Dds,
         {{TextureRole::LeanB, TexelStorage::Half},
          {TextureRole::LeanM, TexelStorage::Half},
          {TextureRole::LeanGloss, TexelStorage::Half}},
         DdsCompression::Rgba16f},
        // The mixture's roles, written together, each kept as half.
        {"mixture",
         {},
         {{TextureRole::MixtureWeights, TexelStorage::Half},
          {TextureRole::MixtureLobe0, TexelStorage::Half},
          {TextureRole::MixtureLobe1, TexelStorage::Half},
          {TextureRole::MixtureLobe2, TexelStorage::Half},
          {TextureRole::MixtureCross, TexelStorage::Half}}},
        {"lean",
         {},
         {{TextureRole::LeanB, TexelStorage::Half},
          {TextureRole::LeanM, TexelStorage::Half},
          {TextureRole::LeanGloss, TexelStorage::Half}}},
        {"gltf", ExportFormat::ExrFloat, {}}, // float files keep floats
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.preset);
        const Preset p = preset(c.preset);
        ExportOptions o;
        o.format = c.format;
        o.compression = c.compression;
        o.stem = "map";
        if (p.findParameter("metallic")) o.parameters["metallic"] = 1.0;
        BakeOptions options;
        options.method = p.method;
        options.encoding = p.encoding;
        options.basePower = 256.0;
        options.params.mixtureLobes = 3;
        options.roles = presetRoles(p);
        const auto shape = bakeShape(options, map.width, map.height);
        ASSERT_TRUE(shape) << shape.error();
        const auto storage = compactStorage(*shape, p, o);
        EXPECT_EQ(storage, c.expected);

        const BakeOutput floats = bake(map, options).value();
        options.storage = storage;
        const BakeOutput compact = bake(map, options).value();
        for (const BakedTexture& t : compact.textures) {
            const BakedTexture* f = floats.find(t.role);
            ASSERT_TRUE(f);
            for (size_t k = 0; k < t.mips.size(); ++k) {
                const auto& fl = f->mips[k].texels;
                if (t.storage == TexelStorage::Unorm8) {
                    ASSERT_TRUE(t.mips[k].texels.empty()) << "no floats kept beside the codes";
                    for (size_t i = 0; i < fl.size(); ++i)
                        ASSERT_EQ(t.mips[k].unorm8[i], unorm8(fl[i])) << roleName(t.role) << " mip " << k;
                } else if (t.storage == TexelStorage::Unorm16) {
                    ASSERT_TRUE(t.mips[k].texels.empty());
                    for (size_t i = 0; i < fl.size(); ++i)
                        ASSERT_EQ(t.mips[k].unorm16[i], unorm16(fl[i])) << roleName(t.role) << " mip " << k;
                } else if (t.storage == TexelStorage::Half) {
                    ASSERT_TRUE(t.mips[k].texels.empty());
                    for (size_t i = 0; i < fl.size(); ++i)
                        ASSERT_EQ(t.mips[k].halfBits[i], halfCode(fl[i]).bits())
                            << roleName(t.role) << " mip " << k;
                } else {
                    EXPECT_EQ(t.mips[k].texels, fl);
                }
            }
        }
        TempDir a, b;
        ASSERT_TRUE(exportBake(floats, p, o, a.path()));
        ASSERT_TRUE(exportBake(compact, p, o, b.path()));
        EXPECT_EQ(filesIn(a.path()), filesIn(b.path())) << "the same bytes";
    }
}

} // namespace
} // namespace burnish
