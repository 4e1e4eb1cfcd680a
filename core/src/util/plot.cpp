#include <burnish/core/util/plot.h>

#include <burnish/core/util/files.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string_view>

namespace burnish {

namespace {

using OIIO::ImageBuf;
using OIIO::ROI;
namespace IBA = OIIO::ImageBufAlgo;

constexpr PlotColor kBlack = {0.0f, 0.0f, 0.0f};
constexpr PlotColor kGrid = {0.88f, 0.88f, 0.88f};
constexpr PlotColor kMinorGrid = {0.95f, 0.95f, 0.95f};
constexpr PlotColor kWhite = {1.0f, 1.0f, 1.0f};
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

/// Draws text or returns the renderer's error (an unknown font is the usual one).
Status drawText(ImageBuf& dst, int x, int y, std::string_view text, int size, const std::string& font,
                const PlotColor& color, IBA::TextAlignX ax, IBA::TextAlignY ay) {
    if (text.empty()) return Status::success();
    if (!IBA::render_text(dst, x, y, text, size, font, color, ax, ay))
        return Error{fmt::format("plot: cannot render text with font \"{}\": {}", font, dst.geterror())};
    return Status::success();
}

int textWidth(std::string_view text, int size, const std::string& font) {
    if (text.empty()) return 0;
    const ROI r = IBA::text_size(text, size, font);
    return r.defined() ? r.width() : 0;
}

void drawMarker(ImageBuf& dst, double px, double py, MarkerShape shape, int size, const PlotColor& color,
                const ROI& clip) {
    const int h = std::max(1, size / 2);
    const int x = static_cast<int>(std::lround(px)), y = static_cast<int>(std::lround(py));
    switch (shape) {
    case MarkerShape::None:
        return;
    case MarkerShape::Square:
        IBA::render_box(dst, x - h, y - h, x + h, y + h, color, true, clip);
        return;
    case MarkerShape::HollowSquare:
        // Two nested outlines so a hollow marker is as visible as a filled one.
        IBA::render_box(dst, x - h, y - h, x + h, y + h, color, false, clip);
        IBA::render_box(dst, x - h + 1, y - h + 1, x + h - 1, y + h - 1, color, false, clip);
        return;
    case MarkerShape::OutlinedSquare:
        IBA::render_box(dst, x - h, y - h, x + h, y + h, color, true, clip);
        IBA::render_box(dst, x - h - 1, y - h - 1, x + h + 1, y + h + 1, kBlack, false, clip);
        return;
    }
}

void drawThickLine(ImageBuf& dst, double x0, double y0, double x1, double y1, int width,
                   const PlotColor& color, const ROI& clip) {
    const int ix0 = static_cast<int>(std::lround(x0)), iy0 = static_cast<int>(std::lround(y0));
    const int ix1 = static_cast<int>(std::lround(x1)), iy1 = static_cast<int>(std::lround(y1));
    // Offset copies across the line's minor axis give it a width.
    const bool steep = std::abs(iy1 - iy0) > std::abs(ix1 - ix0);
    for (int o = -(width - 1) / 2; o <= width / 2; ++o) {
        const int dx = steep ? o : 0, dy = steep ? 0 : o;
        IBA::render_line(dst, ix0 + dx, iy0 + dy, ix1 + dx, iy1 + dy, color, false, clip);
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

Result<ImageBuf> renderPlot(const PlotSpec& spec) {
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
    const std::string& font = spec.fontName;
    // Measure first: an unknown font must fail before anything is drawn.
    if (!IBA::text_size("0", fs, font).defined())
        return Error{fmt::format("plot: font \"{}\" not found (install fonts-dejavu-core)", font)};

    AxisMap ax = makeAxis(spec.x, xs);
    AxisMap ay = makeAxis(spec.y, ys);

    int yTickWidth = 0;
    for (const auto& t : ay.ticks)
        yTickWidth = std::max(yTickWidth, textWidth(t.label, fs - 2, font));
    // The legend: one entry a row down the right side, in as many columns as the height needs (an
    // entry below the image would be lost, and OpenImageIO aborts on text drawn wholly outside it).
    const int top = spec.title.empty() ? 20 : 2 * fs + 14;
    const int legendStep = fs + 10;
    const int legendRows = std::max(1, (spec.height - (top + 8) - 10) / legendStep);
    int legendWidth = 0, named = 0;
    for (const auto& s : spec.series)
        if (!s.name.empty()) {
            legendWidth = std::max(legendWidth, textWidth(s.name, fs - 1, font) + 48);
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

    ImageBuf img(OIIO::ImageSpec(width, spec.height, 3, OIIO::TypeDesc::FLOAT));
    IBA::fill(img, kWhite);
    const ROI plotRoi(left, right + 1, top, bottom + 1, 0, 1, 0, 3);

    // Grid and ticks.
    for (const auto& t : ax.ticks) {
        const int px = static_cast<int>(std::lround(ax.toPixel(t.value)));
        if (px < left || px > right) continue;
        IBA::render_line(img, px, top, px, bottom, t.label.empty() ? kMinorGrid : kGrid);
        IBA::render_line(img, px, bottom, px, bottom + (t.label.empty() ? 3 : 6), kBlack);
        if (auto st = drawText(img, px, bottom + 9, t.label, fs - 2, font, kBlack, IBA::TextAlignX::Center,
                               IBA::TextAlignY::Top);
            !st)
            return Error{st.error()};
    }
    for (const auto& t : ay.ticks) {
        const int py = static_cast<int>(std::lround(ay.toPixel(t.value)));
        if (py < top || py > bottom) continue;
        IBA::render_line(img, left, py, right, py, t.label.empty() ? kMinorGrid : kGrid);
        IBA::render_line(img, left - (t.label.empty() ? 3 : 6), py, left, py, kBlack);
        if (auto st = drawText(img, left - 9, py, t.label, fs - 2, font, kBlack, IBA::TextAlignX::Right,
                               IBA::TextAlignY::Center);
            !st)
            return Error{st.error()};
    }
    IBA::render_box(img, left, top, right, bottom, kBlack, false);

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
    for (const auto& s : spec.series)
        for (size_t i = 0; i < s.pointLabels.size(); ++i) {
            if (!ax.placeable(s.x[i]) || !ay.placeable(s.y[i])) continue;
            const int px = static_cast<int>(std::lround(ax.toPixel(s.x[i]))) + s.markerSize / 2 + 3;
            const int py = static_cast<int>(std::lround(ay.toPixel(s.y[i]))) - s.markerSize / 2 - 1;
            if (auto st = drawText(img, px, py, s.pointLabels[i], fs - 4, font, kBlack, IBA::TextAlignX::Left,
                                   IBA::TextAlignY::Baseline);
                !st)
                return Error{st.error()};
        }

    // Title, axis labels (the y label rotated to read bottom to top), legend.
    // Centred over the plot area, moved right where it would start left of the image.
    const int titleX = std::max((left + right) / 2, textWidth(spec.title, fs + 2, font) / 2 + 8);
    if (auto st = drawText(img, titleX, 10, spec.title, fs + 2, font, kBlack, IBA::TextAlignX::Center,
                           IBA::TextAlignY::Top);
        !st)
        return Error{st.error()};
    if (auto st = drawText(img, (left + right) / 2, spec.height - 10, spec.x.label, fs, font, kBlack,
                           IBA::TextAlignX::Center, IBA::TextAlignY::Bottom);
        !st)
        return Error{st.error()};
    if (!spec.y.label.empty()) {
        const ROI size = IBA::text_size(spec.y.label, fs, font);
        if (!size.defined()) return Error{fmt::format("plot: font \"{}\" cannot measure the y label", font)};
        ImageBuf label(OIIO::ImageSpec(size.width() + 4, fs + 10, 3, OIIO::TypeDesc::FLOAT));
        IBA::fill(label, kWhite);
        if (auto st = drawText(label, 2, (fs + 10) / 2, spec.y.label, fs, font, kBlack, IBA::TextAlignX::Left,
                               IBA::TextAlignY::Center);
            !st)
            return Error{st.error()};
        const ImageBuf rotated = IBA::rotate270(label);
        const int lx = 14;
        const int ly = std::max(0, (top + bottom) / 2 - rotated.spec().height / 2);
        if (!IBA::paste(img, lx, ly, 0, 0, rotated)) return Error{"plot: " + img.geterror()};
    }
    int entry = 0;
    for (const auto& s : spec.series) {
        if (s.name.empty()) continue;
        const int legendX = right + 18 + (entry / legendRows) * legendWidth;
        const int cy = top + 8 + (entry % legendRows) * legendStep + fs / 2;
        ++entry;
        if (s.line)
            drawThickLine(img, legendX, cy, legendX + 26, cy, std::max(1, s.lineWidth), s.color, ROI());
        drawMarker(img, legendX + 13, cy, s.marker, s.markerSize, s.color, ROI());
        if (auto st = drawText(img, legendX + 36, cy, s.name, fs - 1, font, kBlack, IBA::TextAlignX::Left,
                               IBA::TextAlignY::Center);
            !st)
            return Error{st.error()};
    }
    return img;
}

Status savePng(const ImageBuf& image, const std::filesystem::path& path) {
    const auto bytes = encodePng(image, path.filename().string());
    if (!bytes) return Error{bytes.error()};
    return writeFileAtomic(path, *bytes);
}

Result<std::string> encodePng(const ImageBuf& image, const std::string& name) {
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput memory(bytes);
    auto out = OIIO::ImageOutput::create("png");
    if (!out) return Error{"plot: OpenImageIO has no PNG writer: " + OIIO::geterror()};
    if (!out->set_ioproxy(&memory)) return Error{"plot: the PNG writer cannot write to memory"};
    OIIO::ImageSpec spec(image.spec().width, image.spec().height, image.spec().nchannels,
                         OIIO::TypeDesc::UINT8);
    if (!out->open(name, spec)) return Error{"plot: cannot encode PNG: " + out->geterror()};
    if (!image.write(out.get())) {
        out->close();
        return Error{"plot: cannot encode PNG: " + image.geterror()};
    }
    if (!out->close()) return Error{"plot: cannot encode PNG: " + out->geterror()};
    return std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

Result<std::string> encodePlotPng(const PlotSpec& spec) {
    auto image = renderPlot(spec);
    if (!image) return Error{image.error()};
    return encodePng(*image, "plot.png");
}

Status savePlotPng(const PlotSpec& spec, const std::filesystem::path& path) {
    auto image = renderPlot(spec);
    if (!image) return Error{image.error()};
    return savePng(*image, path);
}

} // namespace burnish
