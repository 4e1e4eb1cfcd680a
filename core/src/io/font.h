// Anti-aliased text for plots, drawn with FreeType from a TrueType/OpenType font file found by name
// (private to core). Each glyph is rendered at the pixel size asked, laid out on a baseline by its
// advance, and blended over the image with its coverage as alpha.
#pragma once

#include <burnish/core/util/result.h>

#include <functional>
#include <memory>
#include <string>
#include <string_view>

namespace burnish {

/// The pixels a text covers relative to its origin on the baseline: x in [x0, x1), y in [y0, y1),
/// y growing downwards (y0 < 0 above the baseline). Empty text: all 0.
struct TextBox {
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    int width() const { return x1 - x0; }
    int height() const { return y1 - y0; }
};

/// Blends one pixel: the callback gets (x, y, coverage in (0, 1]).
using CoverageSink = std::function<void(int x, int y, float coverage)>;

class Font {
public:
    /// The font named `name` (a file's base name such as "DejaVuSans", looked up as .ttf, .otf and
    /// .ttc under $BURNISH_FONTS, ~/.fonts, ~/.local/share/fonts, /usr/local/share/fonts and
    /// /usr/share/fonts), or a path to a font file. Fonts stay open for the process (shared, thread
    /// safe). Error: no such font, or FreeType cannot read it.
    static Result<std::shared_ptr<const Font>> find(const std::string& name);

    /// The extent of `text` (UTF-8) at `pixelSize`.
    TextBox measure(std::string_view text, int pixelSize) const;
    /// Calls `sink` for every pixel `text` covers with its origin (the baseline's start) at (x, y).
    void draw(std::string_view text, int pixelSize, int x, int y, const CoverageSink& sink) const;

    struct Face;
    explicit Font(std::unique_ptr<Face> face);
    ~Font();

private:
    std::unique_ptr<Face> m_face;
};

} // namespace burnish
