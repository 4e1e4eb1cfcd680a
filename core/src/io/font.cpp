#include "io/font.h"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <system_error>
#include <vector>

namespace burnish {

namespace fs = std::filesystem;

struct Font::Face {
    FT_Library library = nullptr;
    FT_Face face = nullptr;
    // A FreeType face holds one size and one glyph slot: one caller at a time.
    mutable std::mutex mutex;

    ~Face() {
        if (face) FT_Done_Face(face);
        if (library) FT_Done_FreeType(library);
    }
};

Font::Font(std::unique_ptr<Face> face)
    : m_face(std::move(face)) {}
Font::~Font() = default;

namespace {

// Code points of UTF-8 text; a malformed byte reads as U+FFFD.
std::vector<char32_t> codePoints(std::string_view text) {
    std::vector<char32_t> out;
    out.reserve(text.size());
    size_t i = 0;
    while (i < text.size()) {
        const auto b = static_cast<unsigned char>(text[i]);
        int extra = 0;
        char32_t c = b;
        if (b >= 0x80) {
            if ((b & 0xE0) == 0xC0)
                extra = 1, c = b & 0x1F;
            else if ((b & 0xF0) == 0xE0)
                extra = 2, c = b & 0x0F;
            else if ((b & 0xF8) == 0xF0)
                extra = 3, c = b & 0x07;
            else
                extra = -1;
        }
        bool ok = extra >= 0 && i + size_t(extra) < text.size();
        for (int k = 1; ok && k <= extra; ++k) {
            const auto n = static_cast<unsigned char>(text[i + size_t(k)]);
            ok = (n & 0xC0) == 0x80;
            c = (c << 6) | (n & 0x3F);
        }
        out.push_back(ok ? c : 0xFFFD);
        i += ok ? size_t(extra) + 1 : 1;
    }
    return out;
}

std::vector<fs::path> fontFolders() {
    std::vector<fs::path> dirs;
    if (const char* env = std::getenv("BURNISH_FONTS"); env && *env) {
        std::string list = env;
        size_t start = 0;
        while (start <= list.size()) {
            const size_t end = std::min(list.find(':', start), list.size());
            if (end > start) dirs.emplace_back(list.substr(start, end - start));
            start = end + 1;
        }
    }
    if (const char* home = std::getenv("HOME"); home && *home) {
        dirs.emplace_back(fs::path(home) / ".fonts");
        dirs.emplace_back(fs::path(home) / ".local/share/fonts");
    }
    dirs.emplace_back("/usr/local/share/fonts");
    dirs.emplace_back("/usr/share/fonts");
    return dirs;
}

std::optional<fs::path> locate(const std::string& name) {
    std::error_code ec;
    if (name.find('/') != std::string::npos) {
        if (fs::is_regular_file(name, ec)) return fs::path(name);
        return std::nullopt;
    }
    for (const fs::path& dir : fontFolders()) {
        for (const char* ext : {".ttf", ".otf", ".ttc"}) {
            const fs::path direct = dir / (name + ext);
            if (fs::is_regular_file(direct, ec)) return direct;
        }
        fs::recursive_directory_iterator it(dir, fs::directory_options::skip_permission_denied, ec), end;
        for (; !ec && it != end; it.increment(ec)) {
            const fs::path& p = it->path();
            if (p.stem() != name) continue;
            const std::string ext = p.extension().string();
            if ((ext == ".ttf" || ext == ".otf" || ext == ".ttc") && it->is_regular_file(ec)) return p;
        }
        ec.clear();
    }
    return std::nullopt;
}

// Loads and renders `c` at the face's current size; false when the font cannot (the glyph is skipped).
bool renderGlyph(FT_Face face, char32_t c) {
    return FT_Load_Char(face, FT_ULong(c), FT_LOAD_RENDER) == 0 &&
           face->glyph->bitmap.pixel_mode == FT_PIXEL_MODE_GRAY;
}

} // namespace

Result<std::shared_ptr<const Font>> Font::find(const std::string& name) {
    static std::mutex mutex;
    static std::map<std::string, std::shared_ptr<const Font>> open;
    std::lock_guard lock(mutex);
    if (auto it = open.find(name); it != open.end()) return it->second;
    const auto path = locate(name);
    if (!path) return Error{"font \"" + name + "\" not found"};
    auto face = std::make_unique<Face>();
    if (FT_Init_FreeType(&face->library) != 0) return Error{"FreeType cannot start"};
    if (FT_New_Face(face->library, path->c_str(), 0, &face->face) != 0)
        return Error{"font \"" + name + "\": FreeType cannot read " + path->string()};
    auto font = std::make_shared<const Font>(std::move(face));
    open.emplace(name, font);
    return font;
}

namespace {

// Renders each glyph of `text` at `pixelSize` in turn and hands it to `glyph` with the pen's x (the
// origin at 0); glyphs the font cannot render are skipped. The face's lock must be held.
void layOut(FT_Face face, std::string_view text, int pixelSize,
            const std::function<void(const FT_GlyphSlotRec& g, int penX)>& glyph) {
    if (text.empty() || FT_Set_Pixel_Sizes(face, 0, FT_UInt(std::max(pixelSize, 1))) != 0) return;
    int x = 0;
    for (const char32_t c : codePoints(text)) {
        if (!renderGlyph(face, c)) continue;
        glyph(*face->glyph, x);
        x += int(face->glyph->advance.x >> 6);
    }
}

} // namespace

TextBox Font::measure(std::string_view text, int pixelSize) const {
    std::lock_guard lock(m_face->mutex);
    TextBox box;
    bool any = false;
    layOut(m_face->face, text, pixelSize, [&](const FT_GlyphSlotRec& g, int x) {
        const int gx0 = x + g.bitmap_left, gy0 = -g.bitmap_top;
        const int gx1 = gx0 + int(g.bitmap.width), gy1 = gy0 + int(g.bitmap.rows);
        if (!any) box = {gx0, gx1, gy0, gy1};
        box.x0 = std::min(box.x0, gx0), box.x1 = std::max(box.x1, gx1);
        box.y0 = std::min(box.y0, gy0), box.y1 = std::max(box.y1, gy1);
        any = true;
    });
    return box;
}

void Font::draw(std::string_view text, int pixelSize, int x, int y, const CoverageSink& sink) const {
    std::lock_guard lock(m_face->mutex);
    layOut(m_face->face, text, pixelSize, [&](const FT_GlyphSlotRec& g, int penX) {
        for (unsigned row = 0; row < g.bitmap.rows; ++row) {
            const unsigned char* line = g.bitmap.buffer + std::ptrdiff_t(row) * g.bitmap.pitch;
            for (unsigned col = 0; col < g.bitmap.width; ++col)
                if (line[col] != 0)
                    sink(x + penX + g.bitmap_left + int(col), y - g.bitmap_top + int(row),
                         float(line[col]) / 255.0f);
        }
    });
}

} // namespace burnish
