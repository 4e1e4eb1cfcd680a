#include <burnish/core/io/plot.h>

#include <burnish/core/util/files.h>

#include "io/font.h"
#include "io/png_encode.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string_view>

namespace burnish {

namespace {

enum class AlignX { Left, Center, Right };
enum class AlignY { Baseline, Top, Center, Bottom };

/// Pixels [x0, x1) × [y0, y1) that drawing may touch.
struct Clip {
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    bool contains(int x, int y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
};

Clip whole(const PlotImage& img) {
    return {0, img.width, 0, img.height};
}

/// Paints one pixel `color` with opacity `alpha` over what is there.
void blend(PlotImage& img, int x, int y, const PlotColor& color, float alpha, const Clip& clip) {
    if (!clip.contains(x, y) || x < 0 || y < 0 || x >= img.width || y >= img.height) return;
    float* p = img.rgb.data() + 3 * (size_t(y) * size_t(img.width) + size_t(x));
    for (int c = 0; c < 3; ++c)
        p[c] = p[c] * (1.0f - alpha) + color[size_t(c)] * alpha;
}

/// A one-pixel line from (x0, y0) to (x1, y1), both ends included (Bresenham).
void drawLine(PlotImage& img, int x0, int y0, int x1, int y1, const PlotColor& color, const Clip& clip) {
    const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
    const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
    int err = dx + dy;
    for (;;) {
        blend(img, x0, y0, color, 1.0f, clip);
        if (x0 == x1 && y0 == y1) return;
        const int e2 = 2 * err;
        if (e2 >= dy) err += dy, x0 += sx;
        if (e2 <= dx) err += dx, y0 += sy;
    }
}

void drawLine(PlotImage& img, int x0, int y0, int x1, int y1, const PlotColor& color) {
    drawLine(img, x0, y0, x1, y1, color, whole(img));
}

/// The box with corners (x0, y0) and (x1, y1), both included: its outline, or filled.
void drawBox(PlotImage& img, int x0, int y0, int x1, int y1, const PlotColor& color, bool fill,
             const Clip& clip) {
    if (!fill) {
        drawLine(img, x0, y0, x1, y0, color, clip);
        drawLine(img, x1, y0, x1, y1, color, clip);
        drawLine(img, x1, y1, x0, y1, color, clip);
        drawLine(img, x0, y1, x0, y0, color, clip);
        return;
    }
    for (int y = std::min(y0, y1); y <= std::max(y0, y1); ++y)
        for (int x = std::min(x0, x1); x <= std::max(x0, x1); ++x)
            blend(img, x, y, color, 1.0f, clip);
}

constexpr PlotColor kBlack = {0.0f, 0.0f, 0.0f};
constexpr PlotColor kGrid = {0.88f, 0.88f, 0.88f};
constexpr PlotColor kMinorGrid = {0.95f, 0.95f, 0.95f};
// Tick labels stay readable up to about this many per axis on the default 1100 px width.
constexpr int kMaxMajorTicks = 10;

struct Tick {
    double value;
    std::string label; // empty for minor ticks
};

/// Maps data values to pixels along one axis.
struct AxisMap {
    AxisScale scale = AxisScale::Linear;
    double lo = 0.0, hi = 1.0; // data range
    double p0 = 0.0, p1 = 1.0; // pixels of lo and hi
    std::vector<Tick> ticks;

    double t(double v) const {
        if (scale == AxisScale::Log)
            return (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo));
        return (v - lo) / (hi - lo);
    }
    double toPixel(double v) const { return p0 + t(v) * (p1 - p0); }
    bool placeable(double v) const { return std::isfinite(v) && (scale == AxisScale::Linear || v > 0.0); }
};

double niceStep(double span, int targetTicks) {
    const double raw = span / std::max(targetTicks, 1);
    const double decade = std::pow(10.0, std::floor(std::log10(raw)));
    for (const double m : {1.0, 2.0, 5.0})
        if (m * decade >= raw) return m * decade;
    return 10.0 * decade;
}

std::string logTickLabel(int exponent) {
    // Decades close to 1 read better written out; the others in exponent form.
    if (exponent >= -3 && exponent <= 3) return fmt::format("{:g}", std::pow(10.0, exponent));
    return fmt::format("1e{}", exponent);
}

AxisMap makeAxis(const PlotAxis& axis, const std::vector<double>& values) {
    AxisMap map;
    map.scale = axis.scale;
    double dataMin = INFINITY, dataMax = -INFINITY;
    for (const double v : values)
        if (map.placeable(v)) {
            dataMin = std::min(dataMin, v);
            dataMax = std::max(dataMax, v);
        }
    if (axis.scale == AxisScale::Log) {
        if (!(dataMin <= dataMax)) dataMin = 1.0, dataMax = 10.0; // no placeable data: one decade
        double lo = std::pow(10.0, std::floor(std::log10(dataMin)));
        double hi = std::pow(10.0, std::ceil(std::log10(dataMax)));
        if (axis.min && *axis.min > 0.0 && std::isfinite(*axis.min)) lo = *axis.min;
        if (axis.max && *axis.max > 0.0 && std::isfinite(*axis.max)) hi = *axis.max;
        if (!(hi > lo)) hi = lo * 10.0;
        map.lo = lo, map.hi = hi;
        const int e0 = static_cast<int>(std::ceil(std::log10(lo) - 1e-9));
        const int e1 = static_cast<int>(std::floor(std::log10(hi) + 1e-9));
        const int decades = e1 - e0 + 1;
        const int stride = std::max(1, (decades + kMaxMajorTicks - 1) / kMaxMajorTicks);
        for (int e = e0; e <= e1; ++e) {
            if ((e - e0) % stride == 0) map.ticks.push_back({std::pow(10.0, e), logTickLabel(e)});
            // Minor ticks at 2..9 × 10^e only while decades are wide enough to show them.
            if (decades <= 6)
                for (int m = 2; m <= 9; ++m) {
                    const double v = m * std::pow(10.0, e);
                    if (v > lo && v < hi) map.ticks.push_back({v, ""});
                }
        }
        return map;
    }
    if (!(dataMin <= dataMax)) dataMin = 0.0, dataMax = 1.0;
    if (dataMax - dataMin <= 0.0) {
        // A single value: centre it in a unit-wide (or 10 %-wide) range.
        const double half = dataMin == 0.0 ? 1.0 : 0.1 * std::abs(dataMin);
        dataMin -= half, dataMax += half;
    }
    double lo = axis.min.value_or(dataMin), hi = axis.max.value_or(dataMax);
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo)) lo = dataMin, hi = dataMax;
    const double step = niceStep(hi - lo, 6);
    if (!axis.min) lo = std::floor(lo / step) * step;
    if (!axis.max) hi = std::ceil(hi / step) * step;
    map.lo = lo, map.hi = hi;
    const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step))));
    for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) {
        const double snapped = std::round(v / step) * step;
        map.ticks.push_back({snapped, fmt::format("{:.{}f}", snapped == 0.0 ? 0.0 : snapped, decimals)});
    }
    return map;
}

/// Draws text (UTF-8) at (x, y), aligned on that point as asked, anti-aliased over the image.
void drawText(PlotImage& dst, const Font& font, int x, int y, std::string_view text, int size,
              const PlotColor& color, AlignX ax, AlignY ay) {
    if (text.empty()) return;
    const TextBox box = font.measure(text, size);
    if (ax == AlignX::Right) x -= box.width();
    if (ax == AlignX::Center) x -= box.width() / 2 + box.x0;
    if (ay == AlignY::Top) y -= box.y0;
    if (ay == AlignY::Bottom) y -= box.y1;
    if (ay == AlignY::Center) y -= box.height() / 2 + box.y0;
    font.draw(text, size, x, y,
              [&](int px, int py, float coverage) { blend(dst, px, py, color, coverage, whole(dst)); });
}

int textWidth(const Font& font, std::string_view text, int size) {
    return text.empty() ? 0 : font.measure(text, size).width();
}

void drawMarker(PlotImage& dst, double px, double py, MarkerShape shape, int size, const PlotColor& color,
                const Clip& clip) {
    const int h = std::max(1, size / 2);
    const int x = static_cast<int>(std::lround(px)), y = static_cast<int>(std::lround(py));
    switch (shape) {
    case MarkerShape::None:
        return;
    case MarkerShape::Square:
        drawBox(dst, x - h, y - h, x + h, y + h, color, true, clip);
        return;
    case MarkerShape::HollowSquare:
        // Two nested outlines so a hollow marker is as visible as a filled one.
        drawBox(dst, x - h, y - h, x + h, y + h, color, false, clip);
        drawBox(dst, x - h + 1, y - h + 1, x + h - 1, y + h - 1, color, false, clip);
        return;
    case MarkerShape::OutlinedSquare:
        drawBox(dst, x - h, y - h, x + h, y + h, color, true, clip);
        drawBox(dst, x - h - 1, y - h - 1, x + h + 1, y + h + 1, kBlack, false, clip);
        return;
    }
}

void drawThickLine(PlotImage& dst, double x0, double y0, double x1, double y1, int width,
                   const PlotColor& color, const Clip& clip) {
    const int ix0 = static_cast<int>(std::lround(x0)), iy0 = static_cast<int>(std::lround(y0));
    const int ix1 = static_cast<int>(std::lround(x1)), iy1 = static_cast<int>(std::lround(y1));
    // Offset copies across the line's minor axis give it a width.
    const bool steep = std::abs(iy1 - iy0) > std::abs(ix1 - ix0);
    for (int o = -(width - 1) / 2; o <= width / 2; ++o) {
        const int dx = steep ? o : 0, dy = steep ? 0 : o;
        drawLine(dst, ix0 + dx, iy0 + dy, ix1 + dx, iy1 + dy, color, clip);
    }
}

} // namespace

PlotColor plotPalette(size_t index) {
    // Tableau 10: distinct hues that stay apart on white.
    static constexpr PlotColor kPalette[] = {{0.122f, 0.467f, 0.706f}, {1.000f, 0.498f, 0.055f},
                                             {0.173f, 0.627f, 0.173f}, {0.839f, 0.153f, 0.157f},
                                             {0.580f, 0.404f, 0.741f}, {0.549f, 0.337f, 0.294f},
                                             {0.890f, 0.467f, 0.761f}, {0.498f, 0.498f, 0.498f},
                                             {0.737f, 0.741f, 0.133f}, {0.090f, 0.745f, 0.812f}};
    return kPalette[index % std::size(kPalette)];
}

Result<PlotImage> renderPlot(const PlotSpec& spec) {
    if (spec.width < 200 || spec.height < 200)
        return Error{
            fmt::format("plot: size {}x{} is too small (at least 200x200)", spec.width, spec.height)};
    std::vector<double> xs, ys;
    for (const auto& s : spec.series) {
        if (s.x.size() != s.y.size())
            return Error{
                fmt::format("plot: series \"{}\" has {} x and {} y values", s.name, s.x.size(), s.y.size())};
        if (!s.pointLabels.empty() && s.pointLabels.size() != s.x.size())
            return Error{fmt::format("plot: series \"{}\" has {} labels for {} points", s.name,
                                     s.pointLabels.size(), s.x.size())};
        xs.insert(xs.end(), s.x.begin(), s.x.end());
        ys.insert(ys.end(), s.y.begin(), s.y.end());
    }
    const int fs = std::max(8, spec.fontSize);
    // Found first: an unknown font must fail before anything is drawn.
    const auto found = Font::find(spec.fontName);
    if (!found)
        return Error{fmt::format("plot: font \"{}\" not found (install fonts-dejavu-core): {}", spec.fontName,
                                 found.error())};
    const Font& font = **found;

    AxisMap ax = makeAxis(spec.x, xs);
    AxisMap ay = makeAxis(spec.y, ys);

    int yTickWidth = 0;
    for (const auto& t : ay.ticks)
        yTickWidth = std::max(yTickWidth, textWidth(font, t.label, fs - 2));
    // The legend: one entry a row down the right side, in as many columns as the height needs (an
    // entry below the image would be lost, and OpenImageIO aborts on text drawn wholly outside it).
    const int top = spec.title.empty() ? 20 : 2 * fs + 14;
    const int legendStep = fs + 10;
    const int legendRows = std::max(1, (spec.height - (top + 8) - 10) / legendStep);
    int legendWidth = 0, named = 0;
    for (const auto& s : spec.series)
        if (!s.name.empty()) {
            legendWidth = std::max(legendWidth, textWidth(font, s.name, fs - 1) + 48);
            ++named;
        }
    const int legendColumns = (named + legendRows - 1) / legendRows;

    const int left = 16 + fs + 12 + yTickWidth + 10;
    // A legend of several columns widens the image rather than squeezing the plot area below
    // kMinPlotWidth (or the title past the left edge).
    constexpr int kMinPlotWidth = 600;
    const int legendSpace = legendWidth > 0 ? legendColumns * legendWidth + 24 : 30;
    const int width = legendColumns > 1
                          ? std::max(spec.width, std::min(left + kMinPlotWidth + legendSpace, 4 * spec.width))
                          : spec.width;
    const int right = width - legendSpace;
    const int bottom = spec.height - (fs + 12 + fs + 20);
    if (right - left < 50 || bottom - top < 50) return Error{"plot: labels leave no room for the plot area"};
    ax.p0 = left, ax.p1 = right;
    ay.p0 = bottom, ay.p1 = top; // y grows upwards

    PlotImage img{width, spec.height, std::vector<float>(size_t(width) * size_t(spec.height) * 3, 1.0f)};
    const Clip plotRoi{left, right + 1, top, bottom + 1};

    // Grid and ticks.
    for (const auto& t : ax.ticks) {
        const int px = static_cast<int>(std::lround(ax.toPixel(t.value)));
        if (px < left || px > right) continue;
        drawLine(img, px, top, px, bottom, t.label.empty() ? kMinorGrid : kGrid);
        drawLine(img, px, bottom, px, bottom + (t.label.empty() ? 3 : 6), kBlack);
        drawText(img, font, px, bottom + 9, t.label, fs - 2, kBlack, AlignX::Center, AlignY::Top);
    }
    for (const auto& t : ay.ticks) {
        const int py = static_cast<int>(std::lround(ay.toPixel(t.value)));
        if (py < top || py > bottom) continue;
        drawLine(img, left, py, right, py, t.label.empty() ? kMinorGrid : kGrid);
        drawLine(img, left - (t.label.empty() ? 3 : 6), py, left, py, kBlack);
        drawText(img, font, left - 9, py, t.label, fs - 2, kBlack, AlignX::Right, AlignY::Center);
    }
    drawBox(img, left, top, right, bottom, kBlack, false, whole(img));

    // Series: lines under markers, labels on top.
    for (const auto& s : spec.series) {
        if (!s.line) continue;
        bool havePrev = false;
        double prevX = 0.0, prevY = 0.0;
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!ax.placeable(s.x[i]) || !ay.placeable(s.y[i])) {
                havePrev = false; // a gap, not a jump across the missing point
                continue;
            }
            const double px = ax.toPixel(s.x[i]), py = ay.toPixel(s.y[i]);
            if (havePrev)
                drawThickLine(img, prevX, prevY, px, py, std::max(1, s.lineWidth), s.color, plotRoi);
            prevX = px, prevY = py, havePrev = true;
        }
    }
    for (const auto& s : spec.series)
        for (size_t i = 0; i < s.x.size(); ++i)
            if (ax.placeable(s.x[i]) && ay.placeable(s.y[i]))
                drawMarker(img, ax.toPixel(s.x[i]), ay.toPixel(s.y[i]), s.marker, s.markerSize, s.color,
                           plotRoi);
    // Point labels never overlap: one whose box would meet a label already drawn moves down a line,
    // so coincident points (LEAN and the mixture's K = 1, which are the same lobe) list their labels
    // one under the other instead of printing them over each other.
    std::vector<TextBox> drawnLabels;
    const int labelSize = fs - 4, lineStep = labelSize + 2;
    for (const auto& s : spec.series)
        for (size_t i = 0; i < s.pointLabels.size(); ++i) {
            if (!ax.placeable(s.x[i]) || !ay.placeable(s.y[i]) || s.pointLabels[i].empty()) continue;
            const int px = static_cast<int>(std::lround(ax.toPixel(s.x[i]))) + s.markerSize / 2 + 3;
            int py = static_cast<int>(std::lround(ay.toPixel(s.y[i]))) - s.markerSize / 2 - 1;
            const TextBox extent = font.measure(s.pointLabels[i], labelSize); // about the origin
            auto boxAt = [&](int y) {
                return TextBox{px + extent.x0, px + extent.x1, y + extent.y0, y + extent.y1};
            };
            auto meets = [](const TextBox& a, const TextBox& b) { // with a pixel of air between them
                return a.x0 <= b.x1 && b.x0 <= a.x1 && a.y0 <= b.y1 && b.y0 <= a.y1;
            };
            for (int tries = 0; tries < 16; ++tries) {
                const TextBox box = boxAt(py);
                if (std::none_of(drawnLabels.begin(), drawnLabels.end(),
                                 [&](const TextBox& d) { return meets(box, d); }))
                    break;
                py += lineStep;
            }
            drawnLabels.push_back(boxAt(py));
            drawText(img, font, px, py, s.pointLabels[i], labelSize, kBlack, AlignX::Left, AlignY::Baseline);
        }

    // Title, axis labels (the y label rotated to read bottom to top), legend.
    // Centred over the plot area, moved right where it would start left of the image.
    const int titleX = std::max((left + right) / 2, textWidth(font, spec.title, fs + 2) / 2 + 8);
    drawText(img, font, titleX, 10, spec.title, fs + 2, kBlack, AlignX::Center, AlignY::Top);
    drawText(img, font, (left + right) / 2, spec.height - 10, spec.x.label, fs, kBlack, AlignX::Center,
             AlignY::Bottom);
    if (!spec.y.label.empty()) {
        // Drawn level on a white strip, then turned a quarter anticlockwise into place.
        const TextBox size = font.measure(spec.y.label, fs);
        const int lw = size.width() + 4, lh = fs + 10;
        PlotImage label{lw, lh, std::vector<float>(size_t(lw) * size_t(lh) * 3, 1.0f)};
        drawText(label, font, 2, lh / 2, spec.y.label, fs, kBlack, AlignX::Left, AlignY::Center);
        const int lx = 14;
        const int ly = std::max(0, (top + bottom) / 2 - lw / 2);
        // The rotated strip is lh wide and lw tall: its pixel (u, v) is the label's (lw − 1 − v, u).
        for (int v = 0; v < lw; ++v)
            for (int u = 0; u < lh; ++u) {
                const int x = lx + u, y = ly + v;
                if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
                const float* from = label.rgb.data() + 3 * (size_t(u) * size_t(lw) + size_t(lw - 1 - v));
                std::copy(from, from + 3, img.rgb.data() + 3 * (size_t(y) * size_t(img.width) + size_t(x)));
            }
    }
    int entry = 0;
    for (const auto& s : spec.series) {
        if (s.name.empty()) continue;
        const int legendX = right + 18 + (entry / legendRows) * legendWidth;
        const int cy = top + 8 + (entry % legendRows) * legendStep + fs / 2;
        ++entry;
        if (s.line)
            drawThickLine(img, legendX, cy, legendX + 26, cy, std::max(1, s.lineWidth), s.color, whole(img));
        drawMarker(img, legendX + 13, cy, s.marker, s.markerSize, s.color, whole(img));
        drawText(img, font, legendX + 36, cy, s.name, fs - 1, kBlack, AlignX::Left, AlignY::Center);
    }
    return img;
}

Result<std::string> encodePlotImage(const PlotImage& image) {
    if (image.width <= 0 || image.height <= 0 ||
        image.rgb.size() != size_t(image.width) * size_t(image.height) * 3)
        return Error{
            fmt::format("plot: a {}x{} image holds {} values", image.width, image.height, image.rgb.size())};
    PngPixels pixels;
    pixels.width = image.width;
    pixels.height = image.height;
    pixels.channels = 3;
    pixels.bitDepth = 8;
    const size_t rowValues = size_t(image.width) * 3;
    pixels.rows = [&image, rowValues](size_t y0, size_t y1, void* out) {
        auto* bytes = static_cast<uint8_t*>(out);
        for (size_t i = y0 * rowValues; i < y1 * rowValues; ++i) {
            const float v = image.rgb[i];
            // NaN reads as black; [0, 1] rounds to the nearest of 256 levels.
            *bytes++ = uint8_t(std::lround(std::clamp(v == v ? v : 0.0f, 0.0f, 1.0f) * 255.0f));
        }
    };
    auto bytes = encodePng(pixels);
    if (!bytes) return Error{"plot: cannot encode PNG: " + bytes.error()};
    return bytes;
}

Status savePlotImage(const PlotImage& image, const std::filesystem::path& path) {
    const auto bytes = encodePlotImage(image);
    if (!bytes) return Error{bytes.error()};
    return writeFileAtomic(path, *bytes);
}

Result<std::string> encodePlotPng(const PlotSpec& spec) {
    auto image = renderPlot(spec);
    if (!image) return Error{image.error()};
    return encodePlotImage(*image);
}

Status savePlotPng(const PlotSpec& spec, const std::filesystem::path& path) {
    auto image = renderPlot(spec);
    if (!image) return Error{image.error()};
    return savePlotImage(*image, path);
}

} // namespace burnish
