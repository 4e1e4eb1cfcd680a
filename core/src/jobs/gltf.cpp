// glTF 2.0 in, glTF 2.0 out, with Burnish's bake in every normal-mapped material (gltf.h).
// The asset's JSON is edited in place (nlohmann::json keeps every member it does not touch), so
// whatever Burnish does not know — extensions, extras, animations — passes through as it was.
#include <burnish/core/bake/bake.h>
#include <burnish/core/bake/export.h>
#include <burnish/core/io/image.h>
#include <burnish/core/io/ktx2.h>
#include <burnish/core/jobs/bake_job.h>
#include <burnish/core/jobs/gltf.h>
#include <burnish/core/prefilter/fitted_lobe.h>
#include <burnish/core/prefilter/lobe_mixture.h>
#include <burnish/core/shading/specular_terms.h>

#include "io/png_encode.h"

#include <Imath/half.h>
#include <fmt/format.h>
#include <glm/glm.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <set>

namespace burnish {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::uint32_t kGlbMagic = 0x46546C67; // "glTF"
constexpr std::uint32_t kGlbJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kGlbBin = 0x004E4942;   // "BIN\0"
constexpr int kRepeat = 10497, kMirroredRepeat = 33648;

std::uint32_t le32(std::string_view s, size_t at) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i)
        v = (v << 8) | static_cast<unsigned char>(s[at + size_t(i)]);
    return v;
}
void put32(std::string& out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
        out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

Result<std::string> decodeBase64(std::string_view in) {
    auto value = [](char c) -> int {
        if (c >= 'A' && c <= 'Z') return c - 'A';
        if (c >= 'a' && c <= 'z') return c - 'a' + 26;
        if (c >= '0' && c <= '9') return c - '0' + 52;
        if (c == '+' || c == '-') return 62;
        if (c == '/' || c == '_') return 63;
        return -1;
    };
    std::string out;
    out.reserve(in.size() / 4 * 3);
    std::uint32_t bits = 0;
    int count = 0;
    size_t i = 0;
    for (; i < in.size() && in[i] != '='; ++i) {
        const int v = value(in[i]);
        if (v < 0) return Error{"not base64"};
        bits = (bits << 6) | std::uint32_t(v);
        if (++count == 4) {
            out.push_back(static_cast<char>((bits >> 16) & 0xFF));
            out.push_back(static_cast<char>((bits >> 8) & 0xFF));
            out.push_back(static_cast<char>(bits & 0xFF));
            bits = 0;
            count = 0;
        }
    }
    for (; i < in.size(); ++i)
        if (in[i] != '=') return Error{"not base64"};
    if (count == 1) return Error{"not base64"};
    if (count == 2) out.push_back(static_cast<char>((bits >> 4) & 0xFF));
    if (count == 3) {
        out.push_back(static_cast<char>((bits >> 10) & 0xFF));
        out.push_back(static_cast<char>((bits >> 2) & 0xFF));
    }
    return out;
}

Result<std::string> percentDecode(std::string_view in) {
    std::string out;
    for (size_t i = 0; i < in.size(); ++i) {
        if (in[i] != '%') {
            out.push_back(in[i]);
            continue;
        }
        if (i + 2 >= in.size() || !std::isxdigit(static_cast<unsigned char>(in[i + 1])) ||
            !std::isxdigit(static_cast<unsigned char>(in[i + 2])))
            return Error{"a malformed %-escape"};
        out.push_back(static_cast<char>(std::stoi(std::string(in.substr(i + 1, 2)), nullptr, 16)));
        i += 2;
    }
    return out;
}

// One external or embedded resource of the asset.
struct Resource {
    std::string bytes;
    std::string mime;     // data URIs and bufferView images: their mimeType
    fs::path file;        // external files: where it lies (empty otherwise)
    std::string relative; // external files: the URI's decoded path
};

class Asset {
public:
    fs::path path;
    fs::path folder;
    bool glb = false;
    json doc;
    std::string bin; // the GLB's binary chunk
    std::vector<std::string> buffers;

    static Result<Asset> read(const fs::path& input);
    /// The bytes a URI names: a data: URI's payload or a file inside the asset's folder.
    Result<Resource> uri(const std::string& uri, const std::string& what) const;
    /// An image's bytes, by URI or bufferView.
    Result<Resource> image(int index) const;
    Result<std::string_view> bufferView(int index, const std::string& what) const;
};

Result<Asset> Asset::read(const fs::path& input) {
    Asset a;
    a.path = input;
    a.folder = input.parent_path().empty() ? fs::path(".") : input.parent_path();
    auto bytes = readFile(input);
    if (!bytes) return Error{bytes.error()};
    const std::string name = input.string();
    const std::string_view text = *bytes;
    if (text.size() >= 4 && le32(text, 0) == kGlbMagic) {
        a.glb = true;
        if (text.size() < 20) return Error{name + ": a GLB file shorter than its header"};
        if (le32(text, 4) != 2)
            return Error{fmt::format("{}: GLB container version {} (Burnish reads 2)", name, le32(text, 4))};
        if (le32(text, 8) != text.size())
            return Error{fmt::format("{}: the GLB header says {} bytes, the file has {}", name, le32(text, 8),
                                     text.size())};
        bool first = true;
        for (size_t at = 12; at < text.size();) {
            if (text.size() - at < 8) return Error{name + ": a truncated GLB chunk header"};
            const std::uint32_t length = le32(text, at), type = le32(text, at + 4);
            if (length > text.size() - at - 8)
                return Error{name + ": a GLB chunk runs past the end of the file"};
            const std::string_view chunk = text.substr(at + 8, length);
            if (first) {
                if (type != kGlbJson) return Error{name + ": the GLB's first chunk is not JSON"};
                a.doc = json::parse(chunk.begin(), chunk.end(), nullptr, false);
                if (a.doc.is_discarded()) return Error{name + ": the GLB's JSON chunk is not valid JSON"};
            } else if (type == kGlbBin && a.bin.empty()) {
                a.bin = std::string(chunk);
            }
            first = false;
            at += 8 + size_t(length);
        }
        if (first) return Error{name + ": a GLB without a JSON chunk"};
    } else {
        a.doc = json::parse(text.begin(), text.end(), nullptr, false);
        if (a.doc.is_discarded()) return Error{name + ": not valid JSON (nor a GLB file)"};
    }
    if (!a.doc.is_object()) return Error{name + ": the glTF JSON is not an object"};
    const json* asset = a.doc.contains("asset") ? &a.doc["asset"] : nullptr;
    if (!asset || !asset->is_object() || !asset->contains("version") || !(*asset)["version"].is_string())
        return Error{name + ": not a glTF asset (no asset.version)"};
    const std::string version = (*asset)["version"];
    if (version.rfind("2.", 0) != 0)
        return Error{fmt::format("{}: glTF version {} (Burnish reads 2.0)", name, version)};
    for (const char* key :
         {"buffers", "bufferViews", "images", "textures", "samplers", "materials", "meshes"})
        if (a.doc.contains(key) && !a.doc[key].is_array())
            return Error{fmt::format("{}: '{}' is not an array", name, key)};

    const json& buffers = a.doc.value("buffers", json::array());
    for (size_t i = 0; i < buffers.size(); ++i) {
        const json& b = buffers[i];
        const std::string what = fmt::format("buffer {}", i);
        if (!b.is_object() || !b.contains("byteLength") || !b["byteLength"].is_number_unsigned())
            return Error{fmt::format("{}: {} has no byteLength", name, what)};
        const std::uint64_t length = b["byteLength"];
        std::string data;
        if (b.contains("uri")) {
            if (!b["uri"].is_string()) return Error{fmt::format("{}: {}'s uri is not a string", name, what)};
            auto r = a.uri(b["uri"], what);
            if (!r) return Error{r.error()};
            data = std::move(r->bytes);
        } else if (a.glb && i == 0) {
            data = a.bin;
        } else {
            return Error{fmt::format("{}: {} has no uri", name, what)};
        }
        if (data.size() < length)
            return Error{fmt::format("{}: {} holds {} bytes, less than its byteLength {}", name, what,
                                     data.size(), length)};
        a.buffers.push_back(std::move(data));
    }
    return a;
}

Result<Resource> Asset::uri(const std::string& uri, const std::string& what) const {
    const std::string name = path.string();
    Resource r;
    if (uri.rfind("data:", 0) == 0) {
        const size_t comma = uri.find(',');
        if (comma == std::string::npos)
            return Error{fmt::format("{}: {}: a data URI without ','", name, what)};
        const std::string header = uri.substr(5, comma - 5);
        if (header.size() < 7 || header.substr(header.size() - 7) != ";base64")
            return Error{fmt::format("{}: {}: a data URI that is not base64", name, what)};
        r.mime = header.substr(0, header.size() - 7);
        auto bytes = decodeBase64(std::string_view(uri).substr(comma + 1));
        if (!bytes) return Error{fmt::format("{}: {}: the data URI's payload is not base64", name, what)};
        r.bytes = std::move(*bytes);
        return r;
    }
    const size_t colon = uri.find(':'), slash = uri.find('/');
    if (colon != std::string::npos && (slash == std::string::npos || colon < slash))
        return Error{fmt::format(
            "{}: {}: URI '{}' has a scheme; Burnish reads files beside the asset and data: URIs only", name,
            what, uri)};
    auto decoded = percentDecode(uri);
    if (!decoded) return Error{fmt::format("{}: {}: URI '{}': {}", name, what, uri, decoded.error())};
    const fs::path relative = fs::path(*decoded).lexically_normal();
    if (decoded->empty() || relative.is_absolute() || relative.empty() || *relative.begin() == "..")
        return Error{fmt::format("{}: {}: URI '{}' points outside the asset's folder", name, what, uri)};
    const fs::path file = folder / relative;
    std::error_code ec;
    const fs::path real = fs::weakly_canonical(file, ec), base = fs::weakly_canonical(folder, ec);
    if (!ec) {
        const fs::path within = real.lexically_relative(base);
        if (within.empty() || *within.begin() == "..")
            return Error{fmt::format("{}: {}: URI '{}' leads outside the asset's folder", name, what, uri)};
    }
    auto bytes = readFile(file);
    if (!bytes) return Error{fmt::format("{}: {}: {}", name, what, bytes.error())};
    r.bytes = std::move(*bytes);
    r.file = file;
    r.relative = relative.generic_string();
    return r;
}

Result<std::string_view> Asset::bufferView(int index, const std::string& what) const {
    const std::string name = path.string();
    const json& views = doc.value("bufferViews", json::array());
    if (index < 0 || size_t(index) >= views.size() || !views[size_t(index)].is_object())
        return Error{fmt::format("{}: {}: bufferView {} does not exist", name, what, index)};
    const json& v = views[size_t(index)];
    const int buffer = v.value("buffer", -1);
    if (buffer < 0 || size_t(buffer) >= buffers.size())
        return Error{fmt::format("{}: {}: bufferView {} names buffer {}, which does not exist", name, what,
                                 index, buffer)};
    if (!v.contains("byteLength") || !v["byteLength"].is_number_unsigned())
        return Error{fmt::format("{}: {}: bufferView {} has no byteLength", name, what, index)};
    const std::uint64_t offset = v.value("byteOffset", std::uint64_t(0)), length = v["byteLength"];
    const std::string& data = buffers[size_t(buffer)];
    if (offset > data.size() || length > data.size() - offset)
        return Error{
            fmt::format("{}: {}: bufferView {} runs past the end of buffer {}", name, what, index, buffer)};
    return std::string_view(data).substr(offset, length);
}

Result<Resource> Asset::image(int index) const {
    const std::string name = path.string();
    const json& images = doc.value("images", json::array());
    const std::string what = fmt::format("image {}", index);
    if (index < 0 || size_t(index) >= images.size() || !images[size_t(index)].is_object())
        return Error{fmt::format("{}: {} does not exist", name, what)};
    const json& im = images[size_t(index)];
    if (im.contains("uri") && im["uri"].is_string()) return uri(im["uri"], what);
    if (im.contains("bufferView") && im["bufferView"].is_number_integer()) {
        auto view = bufferView(im["bufferView"], what);
        if (!view) return Error{view.error()};
        Resource r;
        r.bytes = std::string(*view);
        r.mime = im.value("mimeType", std::string());
        return r;
    }
    return Error{fmt::format("{}: {} has neither a uri nor a bufferView", name, what)};
}

// Checks an image's header before it is decoded (the memory its use will need).
using HeaderCheck = std::function<Status(const ImageHeader&)>;

// Reads image bytes through the importer (which reads files): a private temporary file. `check` (if
// set) sees the header first; its error stops the read.
Result<Image> decodeImage(const Resource& r, const std::string& what, const HeaderCheck& check = {}) {
    auto checked = [&](const fs::path& file) -> Status {
        if (!check) return {};
        const auto header = readImageHeader(file);
        if (!header) return Error{what + ": " + header.error()};
        if (const Status s = check(*header); !s) return Error{what + ": " + s.error()};
        return {};
    };
    if (!r.file.empty()) {
        if (const Status s = checked(r.file); !s) return Error{s.error()};
        auto image = readImage(r.file);
        if (!image) return Error{what + ": " + image.error()};
        return image;
    }
    const bool png = r.bytes.size() >= 8 && std::memcmp(r.bytes.data(), "\x89PNG", 4) == 0;
    const bool jpeg = r.bytes.size() >= 3 && static_cast<unsigned char>(r.bytes[0]) == 0xFF &&
                      static_cast<unsigned char>(r.bytes[1]) == 0xD8;
    if (!png && !jpeg) return Error{what + ": neither a PNG nor a JPEG image"};
    auto staging = StagingFolder::create(fs::temp_directory_path());
    if (!staging) return Error{what + ": " + staging.error()};
    const fs::path file = staging.value().fileFor(png ? "image.png" : "image.jpg");
    if (Status s = writeNewFile(file, r.bytes); !s) return Error{what + ": " + s.error()};
    if (const Status s = checked(file); !s) return Error{s.error()};
    auto image = readImage(file);
    if (!image) return Error{what + ": " + image.error()};
    return image;
}

// The texture a textureInfo names and its image index, checked.
struct TextureRef {
    int texture = -1;
    int image = -1;
    int texCoord = 0;
    json transform; // KHR_texture_transform, null without
    int wrapS = kRepeat, wrapT = kRepeat;
};

Result<TextureRef> textureRef(const Asset& a, const json& info, const std::string& what) {
    const std::string name = a.path.string();
    TextureRef t;
    if (!info.is_object() || !info.contains("index") || !info["index"].is_number_integer())
        return Error{fmt::format("{}: {} has no texture index", name, what)};
    t.texture = info["index"];
    t.texCoord = info.value("texCoord", 0);
    if (info.contains("extensions") && info["extensions"].is_object() &&
        info["extensions"].contains("KHR_texture_transform"))
        t.transform = info["extensions"]["KHR_texture_transform"];
    const json& textures = a.doc.value("textures", json::array());
    if (t.texture < 0 || size_t(t.texture) >= textures.size() || !textures[size_t(t.texture)].is_object())
        return Error{fmt::format("{}: {}: texture {} does not exist", name, what, t.texture)};
    const json& tex = textures[size_t(t.texture)];
    if (!tex.contains("source") || !tex["source"].is_number_integer())
        return Error{fmt::format("{}: {}: texture {} has no PNG or JPEG source Burnish can read", name, what,
                                 t.texture)};
    t.image = tex["source"];
    if (tex.contains("sampler") && tex["sampler"].is_number_integer()) {
        const json& samplers = a.doc.value("samplers", json::array());
        const int s = tex["sampler"];
        if (s < 0 || size_t(s) >= samplers.size() || !samplers[size_t(s)].is_object())
            return Error{fmt::format("{}: {}: sampler {} does not exist", name, what, s)};
        t.wrapS = samplers[size_t(s)].value("wrapS", kRepeat);
        t.wrapT = samplers[size_t(s)].value("wrapT", kRepeat);
    }
    return t;
}

// Bilinear sample of channel c of `image` at texel-centre coordinates scaled to a w×h grid.
std::vector<float> resampleChannel(const Image& image, int channel, int w, int h, bool wrap) {
    std::vector<float> out(size_t(w) * size_t(h));
    auto texel = [&](int x, int y) {
        if (wrap) {
            x = ((x % image.width) + image.width) % image.width;
            y = ((y % image.height) + image.height) % image.height;
        } else {
            x = std::clamp(x, 0, image.width - 1);
            y = std::clamp(y, 0, image.height - 1);
        }
        const float v = image.at(x, y, channel);
        return std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (image.width == w && image.height == h) {
                out[size_t(y) * size_t(w) + size_t(x)] = texel(x, y);
                continue;
            }
            const double u = (x + 0.5) * image.width / w - 0.5, v = (y + 0.5) * image.height / h - 0.5;
            const int x0 = int(std::floor(u)), y0 = int(std::floor(v));
            const float fx = float(u - x0), fy = float(v - y0);
            out[size_t(y) * size_t(w) + size_t(x)] =
                (texel(x0, y0) * (1 - fx) + texel(x0 + 1, y0) * fx) * (1 - fy) +
                (texel(x0, y0 + 1) * (1 - fx) + texel(x0 + 1, y0 + 1) * fx) * fy;
        }
    return out;
}

// The mip chain of one channel by box filtering each level's footprint in the level above.
std::vector<std::vector<float>> boxChain(std::vector<float> top,
                                         const std::vector<std::pair<int, int>>& sizes) {
    std::vector<std::vector<float>> chain;
    chain.push_back(std::move(top));
    for (size_t k = 1; k < sizes.size(); ++k) {
        const auto [pw, ph] = sizes[k - 1];
        const auto [w, h] = sizes[k];
        const std::vector<float>& up = chain.back();
        std::vector<float> level(size_t(w) * size_t(h));
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const int x0 = x * pw / w, x1 = std::max(x0 + 1, (x + 1) * pw / w);
                const int y0 = y * ph / h, y1 = std::max(y0 + 1, (y + 1) * ph / h);
                double sum = 0;
                for (int yy = y0; yy < y1; ++yy)
                    for (int xx = x0; xx < x1; ++xx)
                        sum += up[size_t(yy) * size_t(pw) + size_t(xx)];
                level[size_t(y) * size_t(w) + size_t(x)] = float(sum / double((x1 - x0) * (y1 - y0)));
            }
        chain.push_back(std::move(level));
    }
    return chain;
}

// Planar per-channel chains → interleaved 8-bit levels (KTX2's uncompressed payload) or float mips
// (the BC encoder's input).
struct Chains {
    std::vector<std::pair<int, int>> sizes;
    std::vector<std::vector<std::vector<float>>> channels; // [channel][level][texel]
};

std::string unormLevel(const Chains& c, size_t k) {
    const size_t n = c.channels[0][k].size(), channels = c.channels.size();
    std::string out(n * channels, '\0');
    for (size_t i = 0; i < n; ++i)
        for (size_t ch = 0; ch < channels; ++ch)
            out[i * channels + ch] = static_cast<char>(unorm8(c.channels[ch][k][i]));
    return out;
}

Result<std::string> encodeKtx2Chains(const Chains& c, Ktx2Format format, const std::string& role) {
    Ktx2Texture t;
    t.format = format;
    t.width = c.sizes[0].first;
    t.height = c.sizes[0].second;
    t.keyValues = {{"burnish:role", role}};
    if (!ktx2IsBlockCompressed(format)) {
        for (size_t k = 0; k < c.sizes.size(); ++k)
            t.levels.push_back(unormLevel(c, k));
    } else {
        std::vector<TextureMip> mips;
        const size_t channels = c.channels.size();
        for (size_t k = 0; k < c.sizes.size(); ++k) {
            TextureMip m;
            m.width = c.sizes[k].first;
            m.height = c.sizes[k].second;
            const size_t n = c.channels[0][k].size();
            m.texels.resize(n * channels);
            for (size_t i = 0; i < n; ++i)
                for (size_t ch = 0; ch < channels; ++ch)
                    m.texels[i * channels + ch] = c.channels[ch][k][i];
            mips.push_back(std::move(m));
        }
        const DdsCompression compression = format == Ktx2Format::Bc5   ? DdsCompression::Bc5
                                           : format == Ktx2Format::Bc4 ? DdsCompression::Bc4
                                                                       : DdsCompression::Bc3;
        auto dds = encodeDds(mips, int(channels), compression);
        if (!dds) return Error{dds.error()};
        std::uint64_t total = 0;
        for (const auto& [w, h] : c.sizes)
            total += ktx2LevelBytes(format, w, h);
        if (dds->size() < total) return Error{"the DDS encoder wrote fewer blocks than the chain holds"};
        size_t at = dds->size() - total; // the blocks follow the DDS header, level 0 first
        for (const auto& [w, h] : c.sizes) {
            const size_t bytes = ktx2LevelBytes(format, w, h);
            t.levels.push_back(dds->substr(at, bytes));
            at += bytes;
        }
    }
    return encodeKtx2(t);
}

// Interleaved half floats (KTX2's RGBA16F payload) of four-channel chains, little-endian; values past
// the half range clamped to it, NaN to 0.
std::string halfLevel(const Chains& c, size_t k) {
    const size_t n = c.channels[0][k].size(), channels = c.channels.size();
    std::string out(n * channels * 2, '\0');
    for (size_t i = 0; i < n; ++i)
        for (size_t ch = 0; ch < channels; ++ch) {
            const float v = c.channels[ch][k][i];
            const float clamped = std::isnan(v) ? 0.0f : std::clamp(v, -65504.0f, 65504.0f);
            const std::uint16_t bits = Imath::half(clamped).bits();
            out[(i * channels + ch) * 2] = static_cast<char>(bits & 0xFF);
            out[(i * channels + ch) * 2 + 1] = static_cast<char>(bits >> 8);
        }
    return out;
}

Result<std::string> encodeKtx2Half(const Chains& c, const std::string& role) {
    Ktx2Texture t;
    t.format = Ktx2Format::Rgba16f;
    t.width = c.sizes[0].first;
    t.height = c.sizes[0].second;
    t.keyValues = {{"burnish:role", role}};
    for (size_t k = 0; k < c.sizes.size(); ++k)
        t.levels.push_back(halfLevel(c, k));
    return encodeKtx2(t);
}

Result<std::string> encodePngLevel(const Chains& c) {
    const std::string level = unormLevel(c, 0);
    PngPixels p;
    p.width = c.sizes[0].first;
    p.height = c.sizes[0].second;
    p.channels = int(c.channels.size());
    p.data = level.data();
    return encodePng(p);
}

// A file name that no other output of the set has taken: "<stem>.<ext>", else "<stem>-2.<ext>", ...
std::string uniqueName(std::set<std::string>& taken, const std::string& stem, const std::string& ext) {
    std::string name = stem + ext;
    for (int i = 2; taken.count(name); ++i)
        name = fmt::format("{}-{}{}", stem, i, ext);
    taken.insert(name);
    return name;
}

std::string safeStem(std::string s) {
    for (char& ch : s)
        if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_') ch = '_';
    return s.empty() ? std::string("asset") : s;
}

// Every textureInfo of the document (an object under a key ending in "Texture", or in an array under a key
// ending in "Textures" as BURNISH_lobe_mixture's lobeTextures, with an integer "index"), visited with its
// index.
void forEachTextureInfo(json& node, const std::function<void(json& info)>& visit) {
    auto endsWith = [](const std::string& key, std::string_view end) {
        return key.size() > end.size() && key.compare(key.size() - end.size(), end.size(), end) == 0;
    };
    auto isInfo = [](const json& v) {
        return v.is_object() && v.contains("index") && v["index"].is_number_integer();
    };
    if (node.is_object()) {
        for (auto& [key, value] : node.items()) {
            if (endsWith(key, "Texture") && isInfo(value)) visit(value);
            if (endsWith(key, "Textures") && value.is_array())
                for (json& item : value)
                    if (isInfo(item)) visit(item);
            forEachTextureInfo(value, visit);
        }
    } else if (node.is_array()) {
        for (json& value : node)
            forEachTextureInfo(value, visit);
    }
}

// The images a texture reads: its source and every extension's source.
void forEachTextureSource(json& texture, const std::function<void(json& holder)>& visit) {
    if (texture.contains("source") && texture["source"].is_number_integer()) visit(texture);
    if (texture.contains("extensions") && texture["extensions"].is_object())
        for (auto& [name, ext] : texture["extensions"].items())
            if (ext.is_object() && ext.contains("source") && ext["source"].is_number_integer()) visit(ext);
}

// Removes the textures of `candidates` that no textureInfo names any more, then the images no texture
// reads, renumbering what stays (GltfOptions::pruneReplaced).
void pruneTextures(json& doc, const std::set<int>& candidates) {
    json& textures = doc["textures"];
    std::set<int> used;
    forEachTextureInfo(doc, [&](json& info) { used.insert(info["index"].get<int>()); });
    std::vector<int> textureMap(textures.size());
    int next = 0;
    json keptTextures = json::array();
    for (size_t i = 0; i < textures.size(); ++i) {
        if (candidates.count(int(i)) && !used.count(int(i))) {
            textureMap[i] = -1;
            continue;
        }
        textureMap[i] = next++;
        keptTextures.push_back(textures[i]);
    }
    forEachTextureInfo(doc, [&](json& info) {
        const int i = info["index"];
        if (i >= 0 && size_t(i) < textureMap.size()) info["index"] = textureMap[size_t(i)];
    });
    textures = std::move(keptTextures);
    json& images = doc["images"];
    std::set<int> read;
    for (json& t : textures)
        forEachTextureSource(t, [&](json& h) { read.insert(h["source"].get<int>()); });
    std::vector<int> imageMap(images.size());
    next = 0;
    json keptImages = json::array();
    for (size_t i = 0; i < images.size(); ++i) {
        imageMap[i] = read.count(int(i)) ? next++ : -1;
        if (imageMap[i] >= 0) keptImages.push_back(images[i]);
    }
    for (json& t : textures)
        forEachTextureSource(t, [&](json& h) {
            const int i = h["source"];
            if (i >= 0 && size_t(i) < imageMap.size()) h["source"] = imageMap[size_t(i)];
        });
    images = std::move(keptImages);
}

// The plain file names (no folder) an asset written earlier names in its images and buffers; none when
// it is missing or unreadable (then nothing is removed).
std::vector<std::string> previousFiles(const fs::path& asset) {
    auto bytes = readFile(asset);
    if (!bytes) return {};
    std::string_view text = *bytes;
    if (text.size() >= 20 && le32(text, 0) == kGlbMagic) {
        const std::uint32_t length = le32(text, 12);
        if (le32(text, 16) != kGlbJson || length > text.size() - 20) return {};
        text = text.substr(20, length);
    }
    const json doc = json::parse(text.begin(), text.end(), nullptr, false);
    std::vector<std::string> names;
    if (!doc.is_object()) return names;
    for (const char* key : {"images", "buffers"}) {
        const json list = doc.value(key, json::array());
        if (!list.is_array()) continue;
        for (const json& item : list) {
            if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
            const std::string uri = item["uri"];
            if (!uri.empty() && uri.find_first_of("/\\:%") == std::string::npos && uri != "." && uri != "..")
                names.push_back(uri);
        }
    }
    return names;
}

} // namespace

Result<GltfResult> processGltf(const fs::path& input, const fs::path& outDir, const GltfOptions& options) {
    auto progress = [&](double f, std::string_view stage) {
        return !options.progress || options.progress(f, stage);
    };
    if (!progress(0.0, "reading")) return Error{"cancelled"};
    auto read = Asset::read(input);
    if (!read) return Error{read.error()};
    Asset& a = read.value();
    const std::string name = input.string();

    BakeJobSpec spec;
    spec.input = name;
    spec.out = outDir.string();
    spec.preset = "gltf";
    // The mixture rides beside the fitted lobe: clients without its module read the fitted roughness.
    const bool mixture = options.method && *options.method == "mixture";
    const int mixtureLobes = std::clamp(options.mixtureLobes, 1, kMaxMixtureLobes);
    spec.method = mixture ? std::optional<std::string>("fitted") : options.method;
    spec.allowImplausible = options.allowImplausible;
    auto resolved = resolveBakeJob(spec);
    if (!resolved) return Error{resolved.error()};
    const BakeJob job = std::move(*resolved);

    // The arrays this edits, made where the asset has none (and left out again if still empty).
    std::vector<std::string> absent;
    for (const char* key : {"materials", "textures", "images", "bufferViews", "buffers"})
        if (!a.doc.contains(key)) {
            absent.push_back(key);
            a.doc[key] = json::array();
        }
    json& materials = a.doc["materials"];
    json& textures = a.doc["textures"];
    json& images = a.doc["images"];
    const size_t originalBuffers = a.doc["buffers"].size();
    // The asset's own images, told from the new ones after pruning renumbers them (the tag is removed
    // when they are carried over).
    constexpr const char* kOriginalTag = "__burnish_original";
    for (json& image : images)
        if (image.is_object()) image[kOriginalTag] = true;

    // Which materials use a UV set that a primitive drawing them lacks.
    std::map<int, std::vector<std::pair<std::string, std::set<std::string>>>> users;
    const json& meshes = a.doc.value("meshes", json::array());
    for (size_t m = 0; m < meshes.size(); ++m) {
        if (!meshes[m].is_object() || !meshes[m].contains("primitives") ||
            !meshes[m]["primitives"].is_array())
            continue;
        const json& prims = meshes[m]["primitives"];
        for (size_t p = 0; p < prims.size(); ++p) {
            if (!prims[p].is_object() || !prims[p].contains("material") ||
                !prims[p]["material"].is_number_integer())
                continue;
            std::set<std::string> attributes;
            if (prims[p].contains("attributes") && prims[p]["attributes"].is_object())
                for (const auto& [key, value] : prims[p]["attributes"].items())
                    attributes.insert(key);
            const std::string label =
                fmt::format("mesh {} ('{}') primitive {}", m, meshes[m].value("name", std::string()), p);
            users[prims[p]["material"].get<int>()].emplace_back(label, std::move(attributes));
        }
    }

    struct Work {
        int material;
        TextureRef normal;
        std::optional<TextureRef> roughness;
    };
    std::vector<Work> work;
    for (size_t i = 0; i < materials.size(); ++i) {
        json& m = materials[i];
        if (!m.is_object() || !m.contains("normalTexture")) continue;
        const std::string what = fmt::format("material {} ('{}')", i, m.value("name", std::string()));
        auto normal = textureRef(a, m["normalTexture"], what + " normalTexture");
        if (!normal) return Error{normal.error()};
        for (const auto& [label, attributes] : users[int(i)])
            if (!attributes.count(fmt::format("TEXCOORD_{}", normal->texCoord)))
                return Error{fmt::format("{}: {}'s normalTexture uses TEXCOORD_{}, which {} lacks", name,
                                         what, normal->texCoord, label)};
        Work w{int(i), *normal, std::nullopt};
        const json pbr = m.value("pbrMetallicRoughness", json::object());
        if (pbr.is_object() && pbr.contains("metallicRoughnessTexture")) {
            auto mr = textureRef(a, pbr["metallicRoughnessTexture"], what + " metallicRoughnessTexture");
            if (!mr) return Error{mr.error()};
            if (mr->texCoord != normal->texCoord || mr->transform != normal->transform)
                return Error{fmt::format(
                    "{}: {}'s metallicRoughnessTexture uses another UV set or transform than its "
                    "normalTexture; Burnish folds a roughness texture into the normal map's texels only "
                    "when both share them",
                    name, what)};
            w.roughness = *mr;
        }
        work.push_back(std::move(w));
    }

    GltfResult result;
    std::set<std::string> taken;
    const std::string stem = safeStem(input.stem().string());
    const std::string assetName = uniqueName(taken, stem, a.glb ? ".glb" : ".gltf");
    struct NewFile {
        std::string name;
        std::string bytes;
    };
    std::vector<NewFile> files;
    std::string newBin = a.bin;
    bool binBuffer =
        a.glb && !a.doc.value("buffers", json::array()).empty() && !a.doc["buffers"][0].contains("uri");
    auto embed = [&](const std::string& bytes, const std::string& mime) {
        if (!binBuffer) { // a GLB whose buffers are all external: a new first buffer for the binary chunk
            json& buffers = a.doc["buffers"];
            buffers.insert(buffers.begin(), json{{"byteLength", 0}});
            for (json& v : a.doc["bufferViews"])
                if (v.is_object() && v.contains("buffer") && v["buffer"].is_number_integer())
                    v["buffer"] = v["buffer"].get<int>() + 1;
            newBin.clear();
            binBuffer = true;
        }
        while (newBin.size() % 4)
            newBin.push_back('\0');
        json view = {{"buffer", 0}, {"byteOffset", newBin.size()}, {"byteLength", bytes.size()}};
        newBin += bytes;
        json& views = a.doc["bufferViews"];
        views.push_back(view);
        a.doc["buffers"][0]["byteLength"] = newBin.size();
        return json{{"bufferView", views.size() - 1}, {"mimeType", mime}};
    };
    auto addImage = [&](const std::string& fileName, const std::string& bytes, const std::string& mime,
                        GltfMaterialReport& report) {
        json image;
        if (a.glb) {
            image = embed(bytes, mime);
        } else {
            image = json{{"uri", fileName}, {"mimeType", mime}};
            files.push_back({fileName, bytes});
            report.files.push_back(fileName);
        }
        image["name"] = fileName;
        images.push_back(image);
        return int(images.size() - 1);
    };

    bool anisotropyUsed = false, mixtureUsed = false;
    for (size_t wi = 0; wi < work.size(); ++wi) {
        const Work& w = work[wi];
        json& m = materials[size_t(w.material)];
        GltfMaterialReport report;
        report.index = w.material;
        report.name = m.value("name", std::string());
        const std::string what = fmt::format("material {} ('{}')", w.material, report.name);
        if (!progress(0.05 + 0.85 * double(wi) / double(work.size()), "baking " + what))
            return Error{"cancelled"};

        auto normalBytes = a.image(w.normal.image);
        if (!normalBytes) return Error{normalBytes.error()};
        // The bake's memory, checked from the image's header before it is decoded (as `burnish bake`'s).
        auto bakeMemory = [&job](const ImageHeader& h) -> Status {
            const auto perTexel = bakeJobBytesPerTexel(
                job, h.width, h.height, decodedByCore(h.source.formatName, h.source.channelType));
            if (!perTexel) return Error{perTexel.error()};
            // OpenImageIO counted: the asset's other images (JPEG among them) are read through it.
            return checkBakeMemory(estimatedBakeBytes(*perTexel, h.width, h.height, /*openImageIo=*/true),
                                   h.width, h.height);
        };
        auto normalImage =
            decodeImage(*normalBytes, fmt::format("{}: {} normal map (image {})", name, what, w.normal.image),
                        bakeMemory);
        if (!normalImage) return Error{normalImage.error()};
        auto map = decodeNormalMap(*normalImage, job.normalMap);
        if (!map)
            return Error{
                fmt::format("{}: {} normal map (image {}): {}", name, what, w.normal.image, map.error())};
        report.normalScale = m["normalTexture"].value("scale", 1.0);
        if (!std::isfinite(report.normalScale))
            return Error{fmt::format("{}: {}: a normalTexture scale that is not finite", name, what)};
        if (report.normalScale != 1.0)
            for (glm::vec3& n : map.value().normals) {
                const glm::vec3 s(n.x * float(report.normalScale), n.y * float(report.normalScale), n.z);
                const float len = glm::length(s);
                n = len > 1e-12f ? s / len : glm::vec3(0, 0, 1);
            }
        const bool wrap = w.normal.wrapS == kRepeat && w.normal.wrapT == kRepeat;
        report.border = wrap ? "wrap" : "clamp";
        if (w.normal.wrapS == kMirroredRepeat || w.normal.wrapT == kMirroredRepeat)
            report.notes.push_back(
                "mirrored repeat baked as clamp (the same neighbours for the tent filter)");
        if (!wrap && (w.normal.wrapS == kRepeat || w.normal.wrapT == kRepeat))
            report.notes.push_back("repeat on one axis only: baked as clamp on both");

        BakeOptions bo = job.bake;
        bo.pyramid.border = wrap ? BorderMode::Wrap : BorderMode::Clamp;
        const json pbr = m.value("pbrMetallicRoughness", json::object());
        report.roughnessFactor = pbr.is_object() ? pbr.value("roughnessFactor", 1.0) : 1.0;
        if (!std::isfinite(report.roughnessFactor))
            return Error{fmt::format("{}: {}: a roughnessFactor that is not finite", name, what)};
        const double factor = std::clamp(report.roughnessFactor, 0.0, 1.0);
        const int W = map->width, H = map->height;
        std::optional<Image> mrImage;
        if (w.roughness) {
            auto bytes = a.image(w.roughness->image);
            if (!bytes) return Error{bytes.error()};
            auto image = decodeImage(*bytes, fmt::format("{}: {} metallicRoughness texture (image {})", name,
                                                         what, w.roughness->image));
            if (!image) return Error{image.error()};
            mrImage = std::move(*image);
            const int g = mrImage->channels >= 3 ? 1 : 0;
            std::vector<float> gloss = resampleChannel(*mrImage, g, W, H, wrap);
            for (float& v : gloss)
                v = float(factor) * v;
            bo.authoredGloss = std::move(gloss);
            report.roughnessTexture = true;
            if (mrImage->width != W || mrImage->height != H)
                report.notes.push_back(
                    fmt::format("metallicRoughness texture {}x{} resampled to the normal map's {}x{}",
                                mrImage->width, mrImage->height, W, H));
        } else {
            bo.basePower = job.preset.encoding.power(factor);
        }
        const double done = 0.05 + 0.85 * double(wi) / double(work.size()), span = 0.85 / double(work.size());
        bo.progress = [&](double fraction) {
            return progress(done + 0.8 * span * fraction, "baking " + what);
        };
        // One normal pyramid for the bake and, with anisotropy, the anisotropic fit: built once, from the
        // one copy of the map.
        const bool fitAnisotropy =
            options.anisotropy != GltfAnisotropy::Off && job.method == Method::Fitted && !w.roughness;
        const bool fitMixture = mixture && !w.roughness;
        const auto shared = std::make_shared<const NormalMap>(std::move(map.value()));
        if (fitAnisotropy || fitMixture) bo.cachedPyramid = bakePyramid(shared, bo);
        auto baked = bake(*shared, bo);
        if (!baked && baked.error() == "cancelled") return Error{"cancelled"};
        if (!baked) return Error{fmt::format("{}: {}: {}", name, what, baked.error())};
        const BakedTexture* normalTex = baked->find(TextureRole::Normal);
        const BakedTexture* glossTex = baked->find(TextureRole::Gloss);
        if (!normalTex || !glossTex || normalTex->channels < 2 || glossTex->channels != 1 ||
            normalTex->decode[0].scale != 2.0 || normalTex->decode[0].bias != -1.0)
            return Error{
                fmt::format("{}: method {} bakes no unsigned normal and one roughness texture for glTF", name,
                            methodName(job.method))};
        Chains normal, mr;
        for (const TextureMip& mip : normalTex->mips) {
            normal.sizes.emplace_back(mip.width, mip.height);
            mr.sizes.emplace_back(mip.width, mip.height);
        }
        report.width = W;
        report.height = H;
        report.mipCount = int(normal.sizes.size());
        const int normalChannels = 2; // x and y: RG8 and BC5 both leave z to the client
        normal.channels.assign(size_t(normalChannels), {});
        std::vector<std::vector<float>> rough;
        for (const TextureMip& mip : normalTex->mips)
            for (int ch = 0; ch < normalChannels; ++ch) {
                std::vector<float> v(size_t(mip.width) * size_t(mip.height));
                for (size_t i = 0; i < v.size(); ++i)
                    v[i] = mip.texels[i * size_t(normalTex->channels) + size_t(ch)];
                normal.channels[size_t(ch)].push_back(std::move(v));
            }
        for (const TextureMip& mip : glossTex->mips)
            rough.emplace_back(mip.texels.begin(), mip.texels.end());
        auto mean = [](const std::vector<float>& v) {
            double s = 0;
            for (float x : v)
                s += x;
            return v.empty() ? 0.0 : s / double(v.size());
        };
        report.meanRoughnessMip0 = mean(rough.front());
        report.meanRoughnessLast = mean(rough.back());
        auto channelChain = [&](int channel) {
            if (!mrImage) return std::vector<std::vector<float>>(mr.sizes.size(), std::vector<float>());
            const int c = mrImage->channels >= 3 ? channel : 0;
            return boxChain(resampleChannel(*mrImage, c, W, H, wrap), mr.sizes);
        };
        auto constantOr = [&](std::vector<std::vector<float>> chain) {
            for (size_t k = 0; k < chain.size(); ++k)
                if (chain[k].empty())
                    chain[k].assign(size_t(mr.sizes[k].first) * size_t(mr.sizes[k].second), 1.0f);
            return chain;
        };
        // KHR_materials_anisotropy from the anisotropic fit (fitted_lobe.h), where it pays for this map: the
        // fit's relative L1 over levels 1-6 as the engines shade every texel with the extension on,
        // against the isotropic fit's. Then G holds α_b's roughness and the anisotropy texture the
        // direction (RG) and strength (B); level 0 keeps the base, round.
        Chains aniso;
        if (options.anisotropy != GltfAnisotropy::Off && job.method == Method::Fitted) {
            if (w.roughness) {
                report.anisotropy =
                    "off: fitted for a constant base roughness only (this material has a texture)";
            } else {
                const NormalPyramid& pyramid = *bo.cachedPyramid;
                FittedLobeOptions fo;
                fo.brdf = Brdf::Ggx;
                fo.anisotropic = true;
                const double base = bo.basePower;
                std::atomic<bool> stop{false};
                const FittedPyramid fp = FittedPyramid::build(
                    pyramid, [&](int, int, int) { return base; }, nullptr, base, -1, fo,
                    [&] {
                        if (!progress(done + 0.85 * span, "fitting anisotropy, " + what)) stop = true;
                        return stop.load();
                    });
                if (stop) return Error{"cancelled"};
                int levels = 0;
                for (int k = 1; k < std::min(fp.levelCount(), 7); ++k) {
                    const FittedPyramid::FitErrors e = fp.fitErrors(k);
                    if (!(e.truth > 0.0)) continue;
                    report.isotropicError += e.isotropic / e.truth;
                    report.anisotropicError += e.anisotropic / e.truth;
                    ++levels;
                }
                if (levels > 0) report.isotropicError /= levels, report.anisotropicError /= levels;
                const bool on = levels > 0 && (options.anisotropy == GltfAnisotropy::On ||
                                               report.anisotropicError < report.isotropicError);
                report.anisotropy = on ? "on" : "off: the isotropic fit is closer on this map";
                if (on) {
                    aniso.sizes = mr.sizes;
                    aniso.channels.assign(4, {});
                    for (size_t k = 0; k < aniso.sizes.size(); ++k) {
                        const auto [lw, lh] = aniso.sizes[k];
                        const size_t n = size_t(lw) * size_t(lh);
                        std::vector<float> r(n, 1.0f), g(n, 0.5f), b(n, 0.0f), alphaChannel(n, 1.0f);
                        if (k > 0)
                            for (int y = 0; y < lh; ++y)
                                for (int x = 0; x < lw; ++x) {
                                    const AnisotropicLobe lobe = fp.anisotropic(int(k), x, y);
                                    const size_t i = size_t(y) * size_t(lw) + size_t(x);
                                    r[i] = float(0.5 + 0.5 * std::cos(lobe.angle));
                                    g[i] = float(0.5 + 0.5 * std::sin(lobe.angle));
                                    b[i] = float(lobe.strength());
                                    rough[k][i] = float(std::sqrt(lobe.alphaB)); // perceptual roughness
                                }
                        aniso.channels[0].push_back(std::move(r));
                        aniso.channels[1].push_back(std::move(g));
                        aniso.channels[2].push_back(std::move(b));
                        aniso.channels[3].push_back(std::move(alphaChannel));
                    }
                }
            }
        }
        // BURNISH_lobe_mixture: the mixture's lobes fitted at the base roughness, each slot one RGBA16F chain
        // of mixtureGgxTexel's (w, w·b.x, w·b.y, w·(tr M − 2v)), every level down to 1×1.
        std::vector<Chains> lobeChains;
        if (mixture && w.roughness) {
            report.mixture = "off: fitted for a constant base roughness only (this material has a texture)";
        } else if (mixture) {
            if (!progress(done + 0.82 * span, "fitting the lobe mixture, " + what)) return Error{"cancelled"};
            const double s = bo.basePower;
            const MixturePyramid mix = MixturePyramid::build(*bo.cachedPyramid, s, mixtureLobes);
            const double v = mixtureBaseVariance(s, mixtureLobes);
            lobeChains.assign(size_t(mixtureLobes), Chains{});
            for (Chains& c : lobeChains) {
                c.sizes = mr.sizes;
                c.channels.assign(4, std::vector<std::vector<float>>(mr.sizes.size()));
            }
            for (size_t k = 0; k < mr.sizes.size(); ++k) {
                const auto [lw, lh] = mr.sizes[k];
                for (Chains& c : lobeChains)
                    for (auto& channel : c.channels)
                        channel[k].assign(size_t(lw) * size_t(lh), 0.0f);
                for (int y = 0; y < lh; ++y)
                    for (int x = 0; x < lw; ++x) {
                        const auto lobes = mix.storedTexel(*shared, int(k), x, y, s);
                        const size_t i = size_t(y) * size_t(lw) + size_t(x);
                        for (int l = 0; l < mixtureLobes; ++l) {
                            const std::array<double, 4> t = mixtureGgxTexel(lobes[size_t(l)], v);
                            for (size_t ch = 0; ch < 4; ++ch)
                                lobeChains[size_t(l)].channels[ch][k][i] = float(t[ch]);
                        }
                    }
            }
            report.mixture = fmt::format("on, {} lobes", mixtureLobes);
        }
        mr.channels = {constantOr(channelChain(0)), rough, constantOr(channelChain(2)),
                       std::vector<std::vector<float>>(mr.sizes.size())};
        mr.channels[3] = constantOr(std::move(mr.channels[3]));

        // PNG fallback of mip 0: the normal as RGB (z from the baked texture), metallicRoughness as RGB.
        Chains normalPng;
        normalPng.sizes = {normal.sizes[0]};
        for (int ch = 0; ch < 3; ++ch) {
            std::vector<float> v(size_t(W) * size_t(H));
            const TextureMip& mip = normalTex->mips[0];
            for (size_t i = 0; i < v.size(); ++i)
                v[i] = ch < normalTex->channels ? mip.texels[i * size_t(normalTex->channels) + size_t(ch)]
                                                : 1.0f;
            normalPng.channels.push_back({std::move(v)});
        }
        Chains mrPng;
        mrPng.sizes = {mr.sizes[0]};
        for (int ch = 0; ch < 3; ++ch)
            mrPng.channels.push_back({mr.channels[size_t(ch)][0]});

        const Ktx2Format normalFormat =
            options.coding == GltfTextureCoding::Bc ? Ktx2Format::Bc5 : Ktx2Format::Rg8;
        const Ktx2Format mrFormat =
            options.coding == GltfTextureCoding::Bc ? Ktx2Format::Bc3 : Ktx2Format::Rgba8;
        auto normalKtx = encodeKtx2Chains(normal, normalFormat, "normal");
        if (!normalKtx)
            return Error{fmt::format("{}: {}: the normal texture's KTX2: {}", name, what, normalKtx.error())};
        auto mrKtx = encodeKtx2Chains(mr, mrFormat, "metallicRoughness");
        if (!mrKtx)
            return Error{
                fmt::format("{}: {}: the metallicRoughness texture's KTX2: {}", name, what, mrKtx.error())};
        auto normalPngBytes = encodePngLevel(normalPng);
        if (!normalPngBytes) return Error{normalPngBytes.error()};
        auto mrPngBytes = encodePngLevel(mrPng);
        if (!mrPngBytes) return Error{mrPngBytes.error()};

        const std::string base = fmt::format("{}_material{}", stem, w.material);
        auto texture = [&](const std::string& role, const std::string& ktx, const std::string& png) {
            const int ktxImage =
                addImage(uniqueName(taken, base + "_" + role, ".ktx2"), ktx, "image/ktx2", report);
            const int pngImage =
                addImage(uniqueName(taken, base + "_" + role, ".png"), png, "image/png", report);
            json t = textures[size_t(w.normal.texture)];
            t.erase("extensions");
            t.erase("name");
            t["source"] = pngImage;
            t["extensions"] = json{{std::string(kKhrTextureKtx), json{{"source", ktxImage}}}};
            t["name"] = fmt::format("{} {} (Burnish)", report.name, role);
            textures.push_back(t);
            return int(textures.size() - 1);
        };
        const int normalTexIndex = texture("normal", *normalKtx, *normalPngBytes);
        const int mrTexIndex = texture("metallicRoughness", *mrKtx, *mrPngBytes);
        json& nt = m["normalTexture"];
        nt["index"] = normalTexIndex;
        nt.erase("scale");
        json& p = m["pbrMetallicRoughness"];
        if (!p.is_object()) p = json::object();
        json mrInfo = {{"index", mrTexIndex}};
        if (w.normal.texCoord != 0) mrInfo["texCoord"] = w.normal.texCoord;
        if (!w.normal.transform.is_null())
            mrInfo["extensions"] = json{{"KHR_texture_transform", w.normal.transform}};
        p["metallicRoughnessTexture"] = mrInfo;
        p.erase("roughnessFactor"); // 1: folded into the texture
        if (!aniso.sizes.empty()) {
            Chains anisoPng;
            anisoPng.sizes = {aniso.sizes[0]};
            for (int ch = 0; ch < 3; ++ch)
                anisoPng.channels.push_back({aniso.channels[size_t(ch)][0]});
            auto anisoKtx = encodeKtx2Chains(aniso, Ktx2Format::Rgba8, "anisotropy");
            if (!anisoKtx)
                return Error{
                    fmt::format("{}: {}: the anisotropy texture's KTX2: {}", name, what, anisoKtx.error())};
            auto anisoPngBytes = encodePngLevel(anisoPng);
            if (!anisoPngBytes) return Error{anisoPngBytes.error()};
            json info = {{"index", texture("anisotropy", *anisoKtx, *anisoPngBytes)}};
            if (w.normal.texCoord != 0) info["texCoord"] = w.normal.texCoord;
            if (!w.normal.transform.is_null())
                info["extensions"] = json{{"KHR_texture_transform", w.normal.transform}};
            json& ext = m["extensions"];
            if (!ext.is_object()) ext = json::object();
            ext["KHR_materials_anisotropy"] = {
                {"anisotropyStrength", 1.0}, {"anisotropyRotation", 0.0}, {"anisotropyTexture", info}};
            anisotropyUsed = true;
        }
        if (!lobeChains.empty()) {
            json infos = json::array();
            for (size_t l = 0; l < lobeChains.size(); ++l) {
                const std::string role = fmt::format("mixtureLobe{}", l);
                auto ktx = encodeKtx2Half(lobeChains[l], role);
                if (!ktx)
                    return Error{
                        fmt::format("{}: {}: the {} texture's KTX2: {}", name, what, role, ktx.error())};
                // KTX2 only: no PNG holds these values, and only a client that reads the extension reads
                // them.
                const int image =
                    addImage(uniqueName(taken, base + "_" + role, ".ktx2"), *ktx, "image/ktx2", report);
                json t = textures[size_t(w.normal.texture)];
                t.erase("extensions");
                t.erase("name");
                t.erase("source");
                t["extensions"] = json{{std::string(kKhrTextureKtx), json{{"source", image}}}};
                t["name"] = fmt::format("{} {} (Burnish)", report.name, role);
                textures.push_back(t);
                json info = {{"index", int(textures.size() - 1)}};
                if (w.normal.texCoord != 0) info["texCoord"] = w.normal.texCoord;
                if (!w.normal.transform.is_null())
                    info["extensions"] = json{{"KHR_texture_transform", w.normal.transform}};
                infos.push_back(info);
            }
            json& ext = m["extensions"];
            if (!ext.is_object()) ext = json::object();
            ext[std::string(kBurnishLobeMixture)] = {{"lobes", mixtureLobes},
                                                     {"roughnessFactor", factor},
                                                     {"spreadScale", kMixtureGgxSpreadScale},
                                                     {"lobeTextures", infos}};
            mixtureUsed = true;
        }
        m["extras"] = m.value("extras", json::object());
        if (m["extras"].is_object())
            m["extras"]["burnish"] = json{{"method", mixture ? "mixture" : methodName(job.method)},
                                          {"normalScale", report.normalScale},
                                          {"roughnessFactor", report.roughnessFactor}};
        result.materials.push_back(std::move(report));
    }
    if (options.pruneReplaced) {
        std::set<int> replaced;
        for (const Work& w : work) {
            replaced.insert(w.normal.texture);
            if (w.roughness) replaced.insert(w.roughness->texture);
        }
        pruneTextures(a.doc, replaced);
    }
    if (!work.empty()) {
        json& used = a.doc["extensionsUsed"];
        if (!used.is_array()) used = json::array();
        for (const std::string& ext : {std::string(kKhrTextureKtx), std::string("KHR_materials_anisotropy"),
                                       std::string(kBurnishLobeMixture)})
            if ((ext != "KHR_materials_anisotropy" || anisotropyUsed) &&
                (ext != kBurnishLobeMixture || mixtureUsed) &&
                std::find(used.begin(), used.end(), json(ext)) == used.end())
                used.push_back(ext);
    }

    // External files carried over under plain names in the output folder, their URIs rewritten.
    std::map<std::string, std::string> copiedAs;
    auto carry = [&](json& holder, const std::string& what) -> Status {
        if (!holder.contains("uri") || !holder["uri"].is_string()) return {};
        const std::string uri = holder["uri"];
        if (uri.rfind("data:", 0) == 0) return {};
        auto r = a.uri(uri, what);
        if (!r) return Error{r.error()};
        auto found = copiedAs.find(r->relative);
        if (found == copiedAs.end()) {
            const fs::path rel(r->relative);
            const std::string plain =
                uniqueName(taken, safeStem(rel.stem().string()), rel.extension().string());
            found = copiedAs.emplace(r->relative, plain).first;
            files.push_back({plain, std::move(r->bytes)});
            result.copied.push_back(plain);
        }
        holder["uri"] = found->second;
        return {};
    };
    // (The originals only: a GLB's new first buffer shifts them by one.)
    const size_t firstBuffer = a.doc["buffers"].size() - originalBuffers;
    for (size_t i = firstBuffer; i < a.doc["buffers"].size(); ++i)
        if (Status s = carry(a.doc["buffers"][i], fmt::format("buffer {}", i - firstBuffer)); !s)
            return Error{s.error()};
    for (size_t i = 0; i < images.size(); ++i)
        if (images[i].is_object() && images[i].contains(kOriginalTag)) {
            images[i].erase(kOriginalTag);
            if (Status s = carry(images[i], fmt::format("image {}", i)); !s) return Error{s.error()};
        }

    for (const std::string& key : absent)
        if (a.doc[key].empty()) a.doc.erase(key);
    if (!progress(0.9, "writing")) return Error{"cancelled"};
    std::string assetBytes;
    if (a.glb) {
        while (newBin.size() % 4)
            newBin.push_back('\0');
        if (binBuffer && newBin.size() != a.bin.size()) a.doc["buffers"][0]["byteLength"] = newBin.size();
        std::string text = a.doc.dump();
        while (text.size() % 4)
            text.push_back(' ');
        const bool withBin = binBuffer;
        const size_t total = 12 + 8 + text.size() + (withBin ? 8 + newBin.size() : 0);
        if (total > 0xFFFFFFFFull) return Error{fmt::format("{}: the output GLB would exceed 4 GiB", name)};
        put32(assetBytes, kGlbMagic);
        put32(assetBytes, 2);
        put32(assetBytes, std::uint32_t(total));
        put32(assetBytes, std::uint32_t(text.size()));
        put32(assetBytes, kGlbJson);
        assetBytes += text;
        if (withBin) {
            put32(assetBytes, std::uint32_t(newBin.size()));
            put32(assetBytes, kGlbBin);
            assetBytes += newBin;
        }
    } else {
        assetBytes = a.doc.dump(2) + "\n";
    }

    std::error_code ec;
    fs::create_directories(outDir, ec);
    if (ec) return Error{fmt::format("--out {}: {}", outDir.string(), ec.message())};
    auto set = FileSet::begin(outDir);
    if (!set) return Error{set.error()};
    for (const NewFile& f : files)
        if (Status s = set.value().addBytes(f.name, f.bytes); !s) return Error{s.error()};
    if (Status s = set.value().addBytes(assetName, assetBytes); !s) return Error{s.error()};
    // Files the previous asset of this name named beside it that this set does not write (another
    // method's or option's textures) go with it, as a bake's previous set goes (export.h).
    std::vector<std::string> obsolete;
    for (const std::string& old : previousFiles(outDir / assetName))
        if (std::none_of(files.begin(), files.end(), [&](const NewFile& f) { return f.name == old; }))
            obsolete.push_back(old);
    if (Status s = set.value().commit(assetName, obsolete, options.overwrite); !s) return Error{s.error()};

    result.asset = outDir / assetName;
    for (const NewFile& f : files)
        result.written.push_back(f.name);
    result.written.push_back(assetName);
    json mats = json::array();
    for (const GltfMaterialReport& r : result.materials)
        mats.push_back({{"index", r.index},
                        {"name", r.name},
                        {"width", r.width},
                        {"height", r.height},
                        {"mipCount", r.mipCount},
                        {"border", r.border},
                        {"normalScale", r.normalScale},
                        {"roughnessFactor", r.roughnessFactor},
                        {"roughnessTexture", r.roughnessTexture},
                        {"meanRoughnessMip0", r.meanRoughnessMip0},
                        {"meanRoughnessLast", r.meanRoughnessLast},
                        {"anisotropy", r.anisotropy},
                        {"mixture", r.mixture},
                        {"files", r.files},
                        {"notes", r.notes}});
    result.summary = {{"input", name},
                      {"asset", result.asset.string()},
                      {"method", mixture ? "mixture" : methodName(job.method)},
                      {"coding", options.coding == GltfTextureCoding::Bc ? "bc" : "raw"},
                      {"materials", mats},
                      {"copied", result.copied},
                      {"written", result.written}};
    progress(1.0, "done");
    return result;
}

namespace {

std::string encodeBase64(std::string_view in) {
    static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < in.size(); i += 3) {
        std::uint32_t v = std::uint32_t(static_cast<unsigned char>(in[i])) << 16;
        if (i + 1 < in.size()) v |= std::uint32_t(static_cast<unsigned char>(in[i + 1])) << 8;
        if (i + 2 < in.size()) v |= std::uint32_t(static_cast<unsigned char>(in[i + 2]));
        out.push_back(kDigits[(v >> 18) & 63]);
        out.push_back(kDigits[(v >> 12) & 63]);
        out.push_back(i + 1 < in.size() ? kDigits[(v >> 6) & 63] : '=');
        out.push_back(i + 2 < in.size() ? kDigits[v & 63] : '=');
    }
    return out;
}

// A 2×2 quad in the xz plane facing +y: positions, normals, UVs (v down the image, as glTF's), tangents
// and indices in one buffer, as glTF JSON around it.
json quadAsset() {
    const float positions[] = {-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1};
    const float normals[] = {0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0};
    const float uvs[] = {0, 1, 1, 1, 1, 0, 0, 0};
    const float tangents[] = {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1};
    const std::uint16_t indices[] = {0, 1, 2, 0, 2, 3};
    std::string bytes;
    auto add = [&](const void* data, size_t n) {
        bytes.append(static_cast<const char*>(data), n);
        while (bytes.size() % 4)
            bytes.push_back('\0');
    };
    add(positions, sizeof positions);
    add(normals, sizeof normals);
    add(uvs, sizeof uvs);
    add(tangents, sizeof tangents);
    add(indices, sizeof indices);
    json views = json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 48}, {"target", 34962}},
                              {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 48}, {"target", 34962}},
                              {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 32}, {"target", 34962}},
                              {{"buffer", 0}, {"byteOffset", 128}, {"byteLength", 64}, {"target", 34962}},
                              {{"buffer", 0}, {"byteOffset", 192}, {"byteLength", 12}, {"target", 34963}}});
    json accessors =
        json::array({{{"bufferView", 0},
                      {"componentType", 5126},
                      {"count", 4},
                      {"type", "VEC3"},
                      {"min", {-1, 0, -1}},
                      {"max", {1, 0, 1}}},
                     {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
                     {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
                     {{"bufferView", 3}, {"componentType", 5126}, {"count", 4}, {"type", "VEC4"}},
                     {{"bufferView", 4}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}});
    return json{
        {"asset", {{"version", "2.0"}, {"generator", "Burnish"}}},
        {"scene", 0},
        {"scenes", json::array({{{"nodes", {0}}}})},
        {"nodes", json::array({{{"mesh", 0}, {"name", "plane"}}})},
        {"meshes",
         json::array({{{"name", "plane"},
                       {"primitives",
                        json::array({{{"attributes",
                                       {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}, {"TANGENT", 3}}},
                                      {"indices", 4},
                                      {"material", 0}}})}}})},
        {"buffers", json::array({{{"byteLength", bytes.size()},
                                  {"uri", "data:application/octet-stream;base64," + encodeBase64(bytes)}}})},
        {"bufferViews", views},
        {"accessors", accessors}};
}

// 16-bit RGB PNG bytes of width×height texels made by `texel(i, rgb)`.
Result<std::string> png16(int width, int height, const std::function<void(size_t i, float rgb[3])>& texel) {
    std::vector<std::uint16_t> data(size_t(width) * size_t(height) * 3);
    for (size_t i = 0; i < size_t(width) * size_t(height); ++i) {
        float rgb[3];
        texel(i, rgb);
        for (int c = 0; c < 3; ++c)
            data[i * 3 + size_t(c)] = unorm16(rgb[c]);
    }
    PngPixels p;
    p.width = width;
    p.height = height;
    p.channels = 3;
    p.bitDepth = 16;
    p.data = data.data();
    return encodePng(p);
}

} // namespace

Result<GltfResult> exportMaterialGltf(const GltfMaterialSource& m, const fs::path& outDir,
                                      const GltfOptions& options) {
    if (!m.normal || m.normal->width < 1 || m.normal->height < 1) return Error{"glTF export: no normal map"};
    const NormalMap& map = *m.normal;
    const size_t texels = map.texelCount();
    auto unit = [](double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; };
    if (m.roughnessTexels) {
        if (m.roughnessTexels->size() != texels)
            return Error{fmt::format("glTF export: {} roughness values for a {}x{} normal map",
                                     m.roughnessTexels->size(), map.width, map.height)};
        for (float v : *m.roughnessTexels)
            if (!unit(v)) return Error{"glTF export: a roughness value outside [0, 1]"};
    } else if (!unit(m.roughness)) {
        return Error{fmt::format("glTF export: roughness {} outside [0, 1]", m.roughness)};
    }
    for (double c : m.specular)
        if (!unit(c)) return Error{"glTF export: a specular colour channel outside [0, 1]"};
    for (double c : m.albedo)
        if (!unit(c)) return Error{"glTF export: an albedo channel outside [0, 1]"};

    json doc = quadAsset();
    json material = {{"name", m.name}};
    // The specular colour in glTF's terms (shading/specular_terms.h): a metal's F0 is its base colour, a
    // dielectric's KHR_materials_specular colour at ior 1.5.
    const SpecularTerms terms =
        specularTerms(SpecularConvention::Gltf, m.metal ? MaterialClass::Metal : MaterialClass::Dielectric,
                      LinearRgb{m.specular[0], m.specular[1], m.specular[2]});
    json pbr = {{"metallicFactor", terms.values["metallicFactor"]}};
    if (m.metal) {
        pbr["baseColorFactor"] = terms.values["baseColorFactor"];
    } else {
        pbr["baseColorFactor"] = {m.albedo[0], m.albedo[1], m.albedo[2], 1.0};
        material["extensions"] = {{"KHR_materials_specular", terms.values["KHR_materials_specular"]},
                                  {"KHR_materials_ior", terms.values["KHR_materials_ior"]}};
        doc["extensionsUsed"] = {"KHR_materials_specular", "KHR_materials_ior"};
    }
    const int sampler = m.border == BorderMode::Wrap ? kRepeat : 33071;
    doc["samplers"] =
        json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", sampler}, {"wrapT", sampler}}});
    doc["textures"] = json::array({{{"source", 0}, {"sampler", 0}}});
    doc["images"] = json::array({{{"uri", "normal.png"}}});
    material["normalTexture"] = {{"index", 0}};
    if (m.roughnessTexels) {
        doc["textures"].push_back({{"source", 1}, {"sampler", 0}});
        doc["images"].push_back({{"uri", "roughness.png"}});
        pbr["metallicRoughnessTexture"] = {{"index", 1}};
    } else {
        pbr["roughnessFactor"] = m.roughness;
    }
    material["pbrMetallicRoughness"] = pbr;
    doc["materials"] = json::array({material});

    auto staging = StagingFolder::create(fs::temp_directory_path());
    if (!staging) return Error{"glTF export: " + staging.error()};
    const fs::path folder = staging.value().path();
    auto normalPng = png16(map.width, map.height, [&](size_t i, float rgb[3]) {
        for (int c = 0; c < 3; ++c)
            rgb[c] = 0.5f * map.normals[i][c] + 0.5f;
    });
    if (!normalPng) return Error{normalPng.error()};
    if (Status st = writeNewFile(folder / "normal.png", *normalPng); !st) return Error{st.error()};
    if (m.roughnessTexels) {
        auto roughPng = png16(map.width, map.height, [&](size_t i, float rgb[3]) {
            rgb[0] = 1.0f, rgb[1] = (*m.roughnessTexels)[i], rgb[2] = 1.0f;
        });
        if (!roughPng) return Error{roughPng.error()};
        if (Status st = writeNewFile(folder / "roughness.png", *roughPng); !st) return Error{st.error()};
    }
    const fs::path asset = folder / (safeStem(m.name) + ".gltf");
    if (Status st = writeNewFile(asset, doc.dump(1) + "\n"); !st) return Error{st.error()};
    GltfOptions o = options;
    o.pruneReplaced = true;
    // The studio's normals are already decoded (any green convention): the 16-bit source holds them as +Y.
    o.allowImplausible = true;
    auto result = processGltf(asset, outDir, o);
    // What glTF cannot hold of the colour (a "metal" as dark as a dielectric, ...) is said, as bake.json says
    // it.
    if (result && !result->materials.empty())
        for (const std::string& w : terms.warnings) {
            result.value().materials[0].notes.push_back(w);
            result.value().summary["materials"][0]["notes"].push_back(w);
        }
    return result;
}

} // namespace burnish
