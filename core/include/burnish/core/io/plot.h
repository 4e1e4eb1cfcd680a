// A small plotting module: renders line and scatter series on linear or logarithmic axes into an
// RGB float image (white background) with ticks, tick labels, a title, axis labels and a legend, its
// text anti-aliased by FreeType, and saves it as PNG (core's encoder) through writeFileAtomic. Used by the
// approximations report (error against cost) and the bake report (error per mip).
#pragma once

#include <burnish/core/util/result.h>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace burnish {

enum class AxisScale { Linear, Log };

struct PlotAxis {
    std::string label; // with units, e.g. "cost (ns per evaluation)"
    AxisScale scale = AxisScale::Linear;
    /// Range; when unset, fitted to the data (whole decades on a log axis, nice steps on a linear one).
    std::optional<double> min;
    std::optional<double> max;
};

/// Linear RGB in [0, 1].
using PlotColor = std::array<float, 3>;

enum class MarkerShape { None, Square, HollowSquare, OutlinedSquare };

struct PlotSeries {
    std::string name; // legend text; an empty name keeps the series out of the legend
    std::vector<double> x;
    std::vector<double> y;
    PlotColor color = {0.0f, 0.0f, 0.0f};
    bool line = false; // join consecutive points in the given order
    int lineWidth = 2; // pixels
    MarkerShape marker = MarkerShape::Square;
    int markerSize = 7; // pixels, edge of the square
    /// Optional text drawn beside each point (same length as x, or empty).
    std::vector<std::string> pointLabels;
};

struct PlotSpec {
    std::string title;
    PlotAxis x;
    PlotAxis y;
    std::vector<PlotSeries> series;
    /// The image width; a legend of several columns (many series) widens it to keep the plot area.
    int width = 1100;
    int height = 720;
    int fontSize = 16;
    std::string fontName = "DejaVuSans";
};

/// A rendered plot: linear RGB in [0, 1], 3 floats a pixel, row-major, top row first.
struct PlotImage {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;

    const float* pixel(int x, int y) const {
        return rgb.data() + 3 * (size_t(y) * size_t(width) + size_t(x));
    }
};

/// Renders the plot. Points with a NaN/Inf coordinate, or a non-positive one on a log axis, are
/// skipped (they cannot be placed). Fails with a message when the font cannot be found (no plot
/// is ever produced without its labels), when x and y lengths differ, or when the size is < 200 px.
Result<PlotImage> renderPlot(const PlotSpec& spec);

/// Encodes a plot as 8-bit RGB PNG in memory and writes it with writeFileAtomic.
Status savePlotImage(const PlotImage& image, const std::filesystem::path& path);
/// The PNG file's bytes of a plot (errors: a size that does not match its values, encoder failures).
Result<std::string> encodePlotImage(const PlotImage& image);
/// renderPlot, encoded as a PNG file's bytes (for a file set that stages them).
Result<std::string> encodePlotPng(const PlotSpec& spec);

/// renderPlot then savePlotImage.
Status savePlotPng(const PlotSpec& spec, const std::filesystem::path& path);

/// A qualitative palette of `index`-th distinct colour (cycles after 10).
PlotColor plotPalette(size_t index);

} // namespace burnish
