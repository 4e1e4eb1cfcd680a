// The plotting module: a PNG that OpenImageIO reads back at the requested size, not blank, with
// text where labels go; clear errors instead of unlabeled plots; FreeType's text measured and placed.
#include <burnish/core/io/plot.h>

#include "../../core/src/io/font.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>

namespace burnish {
namespace {

namespace fs = std::filesystem;

// Text is drawn black on white: a channel mean below this is a glyph (anti-aliased edges included).
constexpr float kDarkThreshold = 0.35f;

PlotSpec sampleSpec() {
    PlotSpec s;
    s.title = "Error per mip";
    s.x = {"mip level", AxisScale::Linear, {}, {}};
    s.y = {"RMS error", AxisScale::Log, {}, {}};
    PlotSeries a;
    a.name = "Toksvig";
    a.x = {0, 1, 2, 3, 4};
    a.y = {1e-3, 3e-3, 1e-2, 2e-2, 5e-2};
    a.color = plotPalette(0);
    a.line = true;
    PlotSeries b;
    b.name = "naive";
    b.x = {0, 1, 2, 3, 4};
    b.y = {1e-3, 1e-2, 0.1, 0.3, 0.6};
    b.color = plotPalette(1);
    b.marker = MarkerShape::HollowSquare;
    b.pointLabels = {"a", "b", "c", "d", "e"};
    s.series = {a, b};
    s.width = 640;
    s.height = 420;
    return s;
}

/// Pixels whose mean over RGB is below kDarkThreshold inside [x0, x1) × [y0, y1).
int darkPixels(const OIIO::ImageBuf& img, int x0, int x1, int y0, int y1) {
    int count = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            float px[3];
            img.getpixel(x, y, px, 3);
            if ((px[0] + px[1] + px[2]) / 3.0f < kDarkThreshold) ++count;
        }
    return count;
}

int darkPixels(const PlotImage& img, int x0, int x1, int y0, int y1) {
    int count = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const float* px = img.pixel(x, y);
            if ((px[0] + px[1] + px[2]) / 3.0f < kDarkThreshold) ++count;
        }
    return count;
}

class PlotTest : public ::testing::Test {
protected:
    void SetUp() override {
        m_dir = fs::temp_directory_path() / ("burnish_plot_" + std::to_string(::getpid()) + "_" +
                                             ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(m_dir);
    }
    void TearDown() override { fs::remove_all(m_dir); }
    fs::path m_dir;
};

TEST_F(PlotTest, WritesAReadablePngWithContentAndText) {
    const PlotSpec spec = sampleSpec();
    const fs::path png = m_dir / "plot.png";
    const Status st = savePlotPng(spec, png);
    ASSERT_TRUE(st.ok()) << st.error();

    OIIO::ImageBuf img(png.string());
    ASSERT_TRUE(img.read(0, 0, true, OIIO::TypeDesc::FLOAT)) << img.geterror();
    EXPECT_EQ(img.spec().width, spec.width);
    EXPECT_EQ(img.spec().height, spec.height);
    EXPECT_EQ(img.spec().nchannels, 3);

    const auto stats = OIIO::ImageBufAlgo::computePixelStats(img);
    for (int c = 0; c < 3; ++c)
        EXPECT_GT(stats.stddev[c], 0.0f) << "blank channel " << c;

    // The title band holds only the title's glyphs: dark pixels there mean text was rendered.
    constexpr int kTitleBand = 30;
    EXPECT_GT(darkPixels(img, 0, spec.width, 0, kTitleBand), 0);

    // Same plot without a title: that band is empty, so the dark pixels above came from the text.
    PlotSpec untitled = spec;
    untitled.title.clear();
    auto plain = renderPlot(untitled);
    ASSERT_TRUE(plain.ok()) << plain.error();
    EXPECT_EQ(darkPixels(*plain, 0, spec.width, 0, 10), 0);

    // The file holds the rendered plot, each value rounded to the nearest of 256 levels.
    auto rendered = renderPlot(spec);
    ASSERT_TRUE(rendered.ok()) << rendered.error();
    int mismatches = 0;
    for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x) {
            float px[3];
            img.getpixel(x, y, px, 3);
            for (int c = 0; c < 3; ++c)
                if (std::lround(px[c] * 255.0f) != std::lround(rendered->pixel(x, y)[c] * 255.0f))
                    ++mismatches;
        }
    EXPECT_EQ(mismatches, 0);

    // Series colours reach the image: some pixel is far more orange (series b) than grey.
    bool sawOrange = false;
    for (int y = 0; y < spec.height && !sawOrange; ++y)
        for (int x = 0; x < spec.width && !sawOrange; ++x) {
            float px[3];
            img.getpixel(x, y, px, 3);
            sawOrange = px[0] > 0.8f && px[2] < 0.3f; // palette 1 is (1.0, 0.5, 0.06)
        }
    EXPECT_TRUE(sawOrange);
}

TEST_F(PlotTest, ALegendTallerThanThePlotWrapsIntoColumns) {
    // 40 named series (evaluate's error-against-cost plot with several powers and kernels): one
    // column of entries would run past the bottom (OpenImageIO aborted on the text below it).
    PlotSpec spec = sampleSpec();
    spec.series.clear();
    for (int i = 0; i < 40; ++i) {
        PlotSeries s;
        s.name = "method " + std::to_string(i) + " (gaussian), s = 1024";
        s.x = {double(i + 1), double(i + 2)};
        s.y = {1e-3 * (i + 1), 2e-3 * (i + 1)};
        s.color = plotPalette(i);
        s.marker = MarkerShape::Square;
        spec.series.push_back(s);
    }
    auto plot = renderPlot(spec);
    ASSERT_TRUE(plot.ok()) << plot.error();
    // The image widens for the second column instead of squeezing the plot area.
    const int w = plot->width, h = plot->height;
    EXPECT_GT(w, spec.width);
    EXPECT_EQ(h, spec.height);
    // The second column holds text; no entry runs into the bottom rows.
    EXPECT_GT(darkPixels(*plot, w - 200, w, 0, h / 2), 0);
    EXPECT_EQ(darkPixels(*plot, w - 200, w, h - 8, h), 0);
}

TEST_F(PlotTest, UnknownFontIsAnErrorNotAnUnlabeledPlot) {
    PlotSpec spec = sampleSpec();
    spec.fontName = "NoSuchFontBurnishTest";
    const fs::path png = m_dir / "nofont.png";
    const Status st = savePlotPng(spec, png);
    EXPECT_FALSE(st.ok());
    EXPECT_NE(st.error().find("NoSuchFontBurnishTest"), std::string::npos) << st.error();
    EXPECT_FALSE(fs::exists(png));
}

TEST_F(PlotTest, BadSeriesAndSizesAreErrors) {
    PlotSpec spec = sampleSpec();
    spec.series[0].y.pop_back();
    EXPECT_FALSE(renderPlot(spec).ok());
    spec = sampleSpec();
    spec.series[1].pointLabels.pop_back();
    EXPECT_FALSE(renderPlot(spec).ok());
    spec = sampleSpec();
    spec.width = 50;
    EXPECT_FALSE(renderPlot(spec).ok());
}

// Two points at the same place (LEAN and the mixture's K = 1 are the same lobe, so evaluate's error
// against cost plot puts them on one spot) get both labels readable: the second moves below the first
// instead of printing over it. The rows the labels ink number about the two labels' own rows added up;
// printed over each other they would number those of the taller one.
TEST_F(PlotTest, LabelsOfCoincidentPointsDoNotOverlap) {
    auto specWith = [](const std::string& first, const std::string& second) {
        PlotSpec spec;
        spec.title = "Error against cost";
        spec.x = {"cost", AxisScale::Log, {}, {}};
        spec.y = {"error", AxisScale::Log, {}, {}};
        for (size_t i = 0; i < 2; ++i) {
            PlotSeries s;
            s.name = i == 0 ? "a" : "b";
            s.x = {1.0, 2.0, 4.0};
            s.y = {0.5, 0.2, 0.05};
            s.marker = MarkerShape::None;
            s.pointLabels = {"", i == 0 ? first : second, ""};
            spec.series.push_back(s);
        }
        spec.width = 640;
        spec.height = 420;
        return spec;
    };
    auto plain = renderPlot(specWith("", ""));
    ASSERT_TRUE(plain.ok()) << plain.error();
    // The rows where a plot differs from the unlabelled one: the rows its labels ink.
    auto labelRows = [&](const std::string& first, const std::string& second) {
        auto plot = renderPlot(specWith(first, second));
        EXPECT_TRUE(plot.ok()) << plot.error();
        int rows = 0;
        for (int y = 0; y < plot->height; ++y) {
            bool inked = false;
            for (int x = 0; x < plot->width && !inked; ++x)
                for (int c = 0; c < 3; ++c)
                    inked = inked || plot->pixel(x, y)[c] != plain->pixel(x, y)[c];
            rows += inked;
        }
        return rows;
    };
    const int lean = labelRows("lean", ""), mixture = labelRows("", "mixture-k1");
    ASSERT_GT(lean, 5);
    ASSERT_GT(mixture, 5);
    EXPECT_GE(labelRows("lean", "mixture-k1"), lean + mixture - 1);
}

TEST_F(PlotTest, UnplaceablePointsAreSkippedNotFatal) {
    PlotSpec spec = sampleSpec();
    // Zero, negative, NaN and Inf cannot sit on a log axis; the rest of the plot still renders.
    spec.series[0].y = {0.0, -1.0, std::nan(""), INFINITY, 0.01};
    auto img = renderPlot(spec);
    ASSERT_TRUE(img.ok()) << img.error();
    for (const float v : img->rgb)
        ASSERT_TRUE(std::isfinite(v) && v >= 0.0f && v <= 1.0f);

    // No placeable data at all still gives labelled axes (one default decade).
    PlotSpec empty = sampleSpec();
    for (auto& s : empty.series)
        s.x.clear(), s.y.clear(), s.pointLabels.clear();
    EXPECT_TRUE(renderPlot(empty).ok());
}

TEST_F(PlotTest, SaveIntoMissingFolderFailsCleanly) {
    const fs::path png = m_dir / "missing" / "plot.png";
    EXPECT_FALSE(savePlotPng(sampleSpec(), png).ok());
    EXPECT_FALSE(fs::exists(png));
}

TEST(PlotFont, MeasuresAndPlacesUtf8Text) {
    auto font = Font::find("DejaVuSans");
    ASSERT_TRUE(font.ok()) << font.error();
    const TextBox zero = (*font)->measure("0", 16);
    EXPECT_GT(zero.width(), 4);
    EXPECT_LT(zero.y0, 0); // above the baseline
    EXPECT_GT((*font)->measure("00", 16).width(), zero.width());
    EXPECT_GT((*font)->measure("0", 32).height(), zero.height());
    EXPECT_EQ((*font)->measure("", 16).width(), 0);
    // Two-byte code points (σ, ²) are one glyph each, not two replacement glyphs.
    const int sigma = (*font)->measure("\xCF\x83", 16).width();
    const int replacement = (*font)->measure("\xEF\xBF\xBD", 16).width();
    EXPECT_GT(sigma, 0);
    EXPECT_LT(sigma, 2 * replacement);
    // A cut-off or stray byte reads as one replacement glyph, never past the end of the text.
    EXPECT_EQ((*font)->measure("\xCF", 16).width(), replacement);
    EXPECT_EQ((*font)->measure("\x80", 16).width(), replacement);

    // Drawn coverage lies inside the measured box, placed at the origin.
    const TextBox box = (*font)->measure("Burnish", 20);
    struct Extent {
        int x0 = 1 << 20, x1 = -(1 << 20), y0 = 1 << 20, y1 = -(1 << 20), pixels = 0;
    } e;
    bool coverageInRange = true;
    (*font)->draw("Burnish", 20, 100, 50, [&](int x, int y, float coverage) {
        coverageInRange = coverageInRange && coverage > 0.0f && coverage <= 1.0f;
        e.x0 = std::min(e.x0, x), e.x1 = std::max(e.x1, x + 1);
        e.y0 = std::min(e.y0, y), e.y1 = std::max(e.y1, y + 1);
        ++e.pixels;
    });
    EXPECT_TRUE(coverageInRange);
    EXPECT_GT(e.pixels, 50);
    EXPECT_EQ(e.x0, 100 + box.x0);
    EXPECT_EQ(e.x1, 100 + box.x1);
    EXPECT_EQ(e.y0, 50 + box.y0);
    EXPECT_EQ(e.y1, 50 + box.y1);

    EXPECT_FALSE(Font::find("NoSuchFontBurnishTest").ok());
    EXPECT_FALSE(Font::find("/no/such/folder/font.ttf").ok());
}

TEST(PlotImageFile, ASizeThatDoesNotMatchItsValuesIsAnError) {
    PlotImage bad{4, 4, std::vector<float>(10, 1.0f)};
    EXPECT_FALSE(encodePlotImage(bad).ok());
    PlotImage ok{4, 4, std::vector<float>(48, 0.5f)};
    EXPECT_TRUE(encodePlotImage(ok).ok());
}

} // namespace
} // namespace burnish
