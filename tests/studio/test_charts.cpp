// The studio's charts: picks on the specular and gloss charts edit the document (one undo step),
// the BRDF plots hold core's values, and the error-against-cost chart measures every method in a
// worker with the results the texts predict (the naive mean normal is too shiny, LEAN is not).
#include "charts/brdf_plots.h"
#include "charts/chart_axes.h"
#include "charts/charts_panel.h"
#include "charts/error_cost_chart.h"
#include "charts/gloss_chart.h"
#include "charts/specular_chart.h"
#include "main_window.h"

#include <burnish/core/prefilter/methods.h>
#include <burnish/core/prefilter/sample_maps.h>
#include <burnish/core/shading/fresnel.h>
#include <burnish/core/shading/materials.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/spherical_gaussian.h>
#include <burnish/core/shading/visibility.h>

#include "temp_dir.h"

#include <gtest/gtest.h>

#include <QAction>
#include <QApplication>
#include <QChartView>
#include <QElapsedTimer>
#include <QImage>
#include <QLineSeries>
#include <QLogValueAxis>
#include <QMenu>
#include <QMenuBar>
#include <QPointer>
#include <QProgressBar>
#include <QPushButton>
#include <QScatterSeries>
#include <QSet>
#include <QSignalSpy>
#include <QTableWidget>
#include <QTest>
#include <QThread>
#include <QValueAxis>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <set>

namespace burnish::studio {
namespace {

// The plots sample core's double-precision functions and store doubles (QPointF): a point equals
// the function at its x up to the rounding of recomputing x (degrees → radians) — a few ulps.
constexpr double kPlotRelTolerance = 1e-12;
// Waiting for a worker: the 64² evaluation takes well under a second; generous for loaded CI.
constexpr int kWorkerTimeoutMs = 120000;
// Side of the small normal map the error-cost test evaluates.
constexpr int kSmallMap = 64;
// The mip where the 64² map's footprints (4×4 texels) hold a patch of detail: naive must lose to
// LEAN there. From mip 3 on (8×8 and 16×16 of 64²) a footprint spans several whole dents of the
// hammered sample plus the flat metal between them, a spike-plus-ring mixture no single lobe fits:
// there every variance method (LEAN, Toksvig, variance-to-gloss) measures worse than naive at the
// default power, so those mips are not asserted.
constexpr int kFootprintMip = 2;
// Width the specular chart is laid out at in the tests (a docked chart's usual width).
constexpr int kChartWidth = 1100;

bool near(double a, double b) {
    return std::abs(a - b) <= kPlotRelTolerance * std::max(1.0, std::max(std::abs(a), std::abs(b)));
}

/// Every point of a series equals f(x); the series is not empty.
void expectSeriesEquals(QXYSeries* s, const std::function<double(double)>& f, const char* name) {
    ASSERT_NE(s, nullptr) << name;
    // Each curve has kSamples points; the NDF plots drop only underflowed zeros of the far tail.
    ASSERT_GE(s->count(), BrdfPlots::kSamples / 2) << name;
    for (const QPointF& p : s->points())
        EXPECT_TRUE(near(p.y(), f(p.x())))
            << name << " at x = " << p.x() << ": " << p.y() << " vs " << f(p.x());
}

constexpr double kDeg = kPi<double> / 180.0;

// Error vs cost's axes carry several labels: values within one decade (the ns costs 1.4–4.4, errors
// 0.15–0.6) had a log axis labelled at the decade's two ends only, one of them cut off.
TEST(ErrorCostChart, AxesWithinOneDecadeAreLinearWithRoundedTicks) {
    std::unique_ptr<QAbstractAxis> narrow(errorCostAxis("relative L1 error", 0.15, 0.6));
    auto* linear = qobject_cast<QValueAxis*>(narrow.get());
    ASSERT_NE(linear, nullptr) << "a log axis within one decade";
    EXPECT_GE(linear->tickCount(), 5);
    EXPECT_LE(linear->min(), 0.15);
    EXPECT_GE(linear->max(), 0.6);
    EXPECT_LE(linear->max(), 1.0) << "rounded to the values, not to the decade";
    EXPECT_EQ(linear->titleText(), "relative L1 error");

    // Wider spans keep the log axis over whole decades, every value inside.
    std::unique_ptr<QAbstractAxis> wide(errorCostAxis("relative L1 error", 0.004, 0.6));
    auto* log = qobject_cast<QLogValueAxis*>(wide.get());
    ASSERT_NE(log, nullptr);
    EXPECT_DOUBLE_EQ(log->min(), 0.001);
    EXPECT_DOUBLE_EQ(log->max(), 1.0);
    // Nothing to show (no points, or non-finite ones) still gives a valid axis.
    std::unique_ptr<QAbstractAxis> empty(errorCostAxis("x", std::numeric_limits<double>::infinity(), 0.0));
    ASSERT_NE(empty, nullptr);
}

TEST(SpecularChart, ClickingAMarkerPicksThatMaterialAndUndoRestores) {
    MaterialDocument doc;
    SpecularChart chart(&doc);
    chart.resize(kChartWidth, chart.minimumSizeHint().height());
    chart.show();
    QApplication::processEvents();
    const MaterialTable& table = builtinMaterialTable();
    ASSERT_FALSE(table.materials.empty());
    for (const Material& m : table.materials) {
        const QString name = QString::fromStdString(m.name);
        const QRectF rect = chart.markerRect(name);
        ASSERT_FALSE(rect.isEmpty()) << m.name << " has a marker";
        const MaterialSettings before = doc.settings();
        const int steps = doc.undoStack()->count();
        QTest::mouseClick(&chart, Qt::LeftButton, {}, rect.center().toPoint());
        if (before.specularName.compare(name, Qt::CaseInsensitive) == 0) continue; // already picked
        EXPECT_EQ(doc.settings().specularName, name) << "the click lands on " << m.name << "'s marker only";
        EXPECT_EQ(doc.settings().specular, m.f0()) << m.name;
        EXPECT_EQ(doc.settings().materialClass, m.materialClass) << m.name;
        EXPECT_EQ(doc.undoStack()->count(), steps + 1) << "one undo step";
        doc.undoStack()->undo();
        EXPECT_EQ(doc.settings(), before) << "undo restores the colour before " << m.name;
        doc.undoStack()->redo();
    }
}

TEST(SpecularChart, ClickingTheStripPicksItsGreyAsOneUndoStep) {
    MaterialDocument doc;
    SpecularChart chart(&doc);
    chart.resize(kChartWidth, chart.minimumSizeHint().height());
    chart.show();
    QApplication::processEvents();
    // sRGB 60: inside the chart's dielectric gradient (40-75), so the class becomes dielectric.
    constexpr std::uint8_t kCode = 60;
    const double f0 = srgb8ToLinear(kCode);
    const QPointF at(chart.xForF0(f0), chart.stripRect().center().y());
    const MaterialSettings before = doc.settings();
    ASSERT_EQ(before.materialClass, MaterialClass::Metal) << "the default document is iron";
    QTest::mouseClick(&chart, Qt::LeftButton, {}, at.toPoint());
    EXPECT_EQ(toSrgb8(doc.settings().specular), (Srgb8{kCode, kCode, kCode}));
    EXPECT_TRUE(doc.settings().specularName.isEmpty()) << "a custom colour";
    EXPECT_EQ(doc.settings().materialClass, MaterialClass::Dielectric);
    doc.undoStack()->undo();
    EXPECT_EQ(doc.settings(), before) << "colour and class are one undo step";
}

TEST(GlossChart, ClickingASpherePicksItsGlossAndUndoRestores) {
    MaterialDocument doc;
    GlossChart chart(&doc);
    chart.resize(chart.sizeHint());
    chart.show();
    QApplication::processEvents();
    if (!chart.glAvailable()) {
        EXPECT_FALSE(chart.glMessage().isEmpty()) << "the chart says why it has no spheres";
        GTEST_SKIP() << chart.glMessage().toStdString();
    }
    ASSERT_TRUE(chart.renderSpheres()) << chart.glMessage().toStdString();
    EXPECT_TRUE(chart.glMessage().isEmpty());
    // The camera frames the unit sphere to ~97% of the image's half side: it covers ~74% of the
    // pixels. Half of them differing from the background (the corner) means a sphere was drawn.
    constexpr double kMinSphereCoverage = 0.5;
    // The highlight of the directional light, on the brightest channel, above the background:
    // even the g = 1 (n = 8192) lobe of iron lights a pixel to near white; a third of the range.
    constexpr int kMinHighlightContrast = 85;
    for (int i = 0; i < GlossChart::kSpheres; ++i) {
        const QImage& image = chart.sphereImage(i);
        ASSERT_EQ(image.width(), GlossChart::kSphereSize);
        const QRgb background = image.pixel(0, 0);
        int differing = 0, brightest = 0;
        for (int y = 0; y < image.height(); ++y)
            for (int x = 0; x < image.width(); ++x) {
                const QRgb c = image.pixel(x, y);
                differing += c != background;
                brightest = std::max({brightest, qRed(c), qGreen(c), qBlue(c)});
            }
        EXPECT_GE(differing, kMinSphereCoverage * image.width() * image.height())
            << "sphere " << i << " is drawn";
        EXPECT_GE(brightest - std::max({qRed(background), qGreen(background), qBlue(background)}),
                  kMinHighlightContrast)
            << "sphere " << i << " has its highlight";
    }

    constexpr int kSphere = 3; // g = 0.3
    const MaterialSettings before = doc.settings();
    QTest::mouseClick(&chart, Qt::LeftButton, {}, chart.sphereRect(kSphere).center());
    EXPECT_EQ(doc.settings().gloss, GlossChart::glossAt(kSphere));
    EXPECT_EQ(doc.power(), doc.preset().encoding.power(GlossChart::glossAt(kSphere)));
    doc.undoStack()->undo();
    EXPECT_EQ(doc.settings(), before);
}

TEST(GlossChart, SpheresFollowTheSpecularColour) {
    MaterialDocument doc;
    GlossChart chart(&doc);
    chart.resize(chart.sizeHint());
    chart.show();
    QApplication::processEvents();
    if (!chart.glAvailable()) {
        GTEST_SKIP() << chart.glMessage().toStdString();
    }
    QSignalSpy rendered(&chart, &GlossChart::spheresRendered);
    if (chart.renderCount() == 0) {
        ASSERT_TRUE(rendered.wait(kWorkerTimeoutMs)) << "the first render on show";
    }
    const QImage iron = chart.sphereImage(GlossChart::kSpheres / 2);
    const int renders = chart.renderCount();
    ASSERT_TRUE(doc.setSpecularMaterial("gold"));
    ASSERT_TRUE(rendered.wait(kWorkerTimeoutMs)) << "a colour change re-renders";
    EXPECT_EQ(chart.renderCount(), renders + 1);
    EXPECT_NE(chart.sphereImage(GlossChart::kSpheres / 2), iron) << "gold spheres differ from iron ones";
    doc.setGloss(0.2);
    QApplication::processEvents();
    EXPECT_EQ(chart.renderCount(), renders + 1) << "a gloss change only moves the marker";
}

// The NDF's log axis ended a part-decade above its last label (issue 48, point 9): every log axis
// now runs over whole decades, labelled at both ends.
TEST(BrdfPlots, LogAxesRunOverWholeDecades) {
    MaterialDocument doc;
    doc.setGloss(0.55);
    BrdfPlots plots(&doc);
    int logAxes = 0;
    for (int tab = 0; tab < plots.count(); ++tab) {
        QChartView* view = plots.view(tab);
        if (!view || !view->chart()) continue;
        for (QAbstractAxis* axis : view->chart()->axes()) {
            auto* log = qobject_cast<QLogValueAxis*>(axis);
            if (!log) continue;
            ++logAxes;
            for (double end : {log->min(), log->max()}) {
                const double decade = std::log10(end);
                EXPECT_NEAR(decade, std::round(decade), 1e-9)
                    << axis->titleText().toStdString() << " ends at " << end;
            }
        }
    }
    EXPECT_GE(logAxes, 3); // D, V, Blinn-Phong power
}

TEST(BrdfPlots, SeriesHoldCoresValues) {
    MaterialDocument doc;
    ASSERT_TRUE(doc.setSpecularMaterial("skin"));
    doc.setGloss(0.55);
    BrdfPlots plots(&doc);
    const double n = doc.power();
    const double m = beckmannRoughnessFromPower(n);
    const double alpha = ggxAlphaFromPower(n);
    const double s2 = 1.0 / n; // LEAN's I/s for a flat footprint
    auto cosDeg = [](double deg) { return std::cos(deg * kDeg); };

    expectSeriesEquals(
        plots.findSeries("ndf/blinn-phong"), [&](double x) { return blinnPhongNdf(cosDeg(x), n); },
        "ndf/blinn-phong");
    expectSeriesEquals(
        plots.findSeries("ndf/beckmann"), [&](double x) { return beckmannNdf(cosDeg(x), m); },
        "ndf/beckmann");
    expectSeriesEquals(
        plots.findSeries("ndf/ggx"), [&](double x) { return ggxNdf(cosDeg(x), alpha); }, "ndf/ggx");
    expectSeriesEquals(
        plots.findSeries("ndf/sg"),
        [&](double x) { return blinnPhongNdfNorm(n) * sgLobe(cosDeg(x), n, kSgOffsetLagarde); }, "ndf/sg");
    expectSeriesEquals(
        plots.findSeries("ndf/lean"),
        [&](double x) {
            return slopeGaussianNdf(glm::dvec3(std::sin(x * kDeg), 0.0, cosDeg(x)), glm::dvec2(0.0),
                                    {s2, s2, 0.0});
        },
        "ndf/lean");
    // Polar angles run over [0, 360): 360 − θ is the lobe at −θ, the same value by symmetry.
    expectSeriesEquals(
        plots.findSeries("polar/ggx"),
        [&](double a) { return ggxNdf(cosDeg(a > 180.0 ? 360.0 - a : a), alpha); }, "polar/ggx");

    const double f0 = luminance(doc.settings().specular);
    EXPECT_EQ(plots.plottedF0(), f0);
    expectSeriesEquals(
        plots.findSeries("fresnel/schlick"), [&](double x) { return fresnelSchlick(f0, cosDeg(x)); },
        "fresnel/schlick");
    expectSeriesEquals(
        plots.findSeries("fresnel/glossy"),
        [&](double x) { return fresnelGlossy(f0, cosDeg(x), doc.settings().gloss); }, "fresnel/glossy");
    expectSeriesEquals(
        plots.findSeries("fresnel/sg"), [&](double x) { return fresnelSchlickSg(f0, cosDeg(x)); },
        "fresnel/sg");
    expectSeriesEquals(
        plots.findSeries("fresnel/dielectric"), [&](double x) { return fresnelDielectric(f0, cosDeg(x)); },
        "fresnel/dielectric");

    expectSeriesEquals(
        plots.findSeries("visibility/schlick-smith"),
        [&](double v) { return visibilitySchlickSmith(v, v, n); }, "visibility/schlick-smith");
    expectSeriesEquals(
        plots.findSeries("visibility/smith-ggx"),
        [&](double v) { return visibilitySmithGgxCorrelated(v, v, alpha); }, "visibility/smith-ggx");
    expectSeriesEquals(
        plots.findSeries("visibility/kelemen"), [&](double v) { return visibilityKelemen(v); },
        "visibility/kelemen");

    const GlossEncoding& enc = doc.preset().encoding;
    expectSeriesEquals(
        plots.findSeries("gloss/power"), [&](double g) { return enc.power(g); }, "gloss/power");
    QXYSeries* current = plots.findSeries("gloss/current");
    ASSERT_NE(current, nullptr);
    ASSERT_EQ(current->count(), 1);
    EXPECT_EQ(current->at(0), QPointF(doc.settings().gloss, n));

    // An edit re-samples: the Blinn-Phong peak follows the new power.
    doc.setGloss(0.9);
    const double n2 = doc.power();
    ASSERT_NE(n2, n);
    expectSeriesEquals(
        plots.findSeries("ndf/blinn-phong"), [&](double x) { return blinnPhongNdf(cosDeg(x), n2); },
        "ndf/blinn-phong after the edit");
    EXPECT_EQ(plots.findSeries("gloss/current")->at(0), QPointF(0.9, n2));
}

TEST(ErrorCostChart, WorkerShowsOnePointPerMethodAndNaiveIsWorseThanLean) {
    test::TempDir dir;
    // The hammered sample at 64², through an 8-bit PNG as a user's map would come.
    const NormalMap sample = makeSampleNormalMap(SampleMapKind::Hammered, kSmallMap);
    QImage png(kSmallMap, kSmallMap, QImage::Format_RGB888);
    for (int y = 0; y < kSmallMap; ++y)
        for (int x = 0; x < kSmallMap; ++x) {
            const glm::vec3 nrm = sample.at(x, y);
            auto byte = [](float c) { return int(std::lround((c * 0.5f + 0.5f) * 255.0f)); };
            png.setPixel(x, y, qRgb(byte(nrm.x), byte(nrm.y), byte(nrm.z)));
        }
    const QString path = QString::fromStdString((dir / "hammered64.png").string());
    ASSERT_TRUE(png.save(path));
    MaterialDocument doc;
    ASSERT_TRUE(doc.loadMap(MapSlot::Normal, path));
    ASSERT_EQ(doc.maps().normal->width, kSmallMap);

    ErrorCostChart chart(&doc);
    QSignalSpy updated(&chart, &ErrorCostChart::methodsUpdated);
    chart.evaluateNow();
    EXPECT_TRUE(chart.evaluating()) << "the evaluation runs off the GUI thread";
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    ASSERT_FALSE(chart.evaluating());
    ASSERT_NE(chart.report(), nullptr) << chart.statusText().toStdString();
    ASSERT_GE(chart.report()->result.lastMip, kFootprintMip);
    for (int mip = chart.report()->result.firstMip; mip <= chart.report()->result.lastMip; ++mip) {
        chart.setMip(mip);
        std::map<Method, QPointF> points;
        for (Method method : allMethods()) {
            QScatterSeries* s = chart.methodSeries(method);
            ASSERT_NE(s, nullptr) << methodName(method) << " at mip " << mip;
            ASSERT_EQ(s->count(), 1) << methodName(method);
            const QPointF p = s->at(0);
            EXPECT_TRUE(std::isfinite(p.x()) && p.x() > 0.0) << methodName(method) << " cost " << p.x();
            EXPECT_TRUE(std::isfinite(p.y()) && p.y() > 0.0) << methodName(method) << " error " << p.y();
            points[method] = p;
        }
        for (const MipError& e : chart.report()->result.errors) {
            if (e.mip == mip && e.kernel == FilterKernel::Box) {
                EXPECT_EQ(points[e.method].y(), e.relativeL1) << "the chart shows core's number";
            }
        }
        // Baker & Hill 2012: the renormalized mean normal keeps the base power and is too shiny once
        // a footprint holds detail; LEAN's covariance keeps the spread.
        if (mip == kFootprintMip) {
            EXPECT_GT(points[Method::Naive].y(), points[Method::Lean].y()) << "mip " << mip;
        }
    }
    // Charts an artist can read a number from (issue 48, point 9): every method its own colour and
    // marker (naive and Toksvig overlapped, alike), and the value under the pointer.
    {
        std::set<std::pair<QRgb, int>> looks;
        for (Method method : allMethods()) {
            QScatterSeries* s = chart.methodSeries(method);
            looks.insert({s->color().rgb(), int(s->markerShape())});
        }
        EXPECT_EQ(looks.size(), allMethods().size());
        QScatterSeries* naive = chart.methodSeries(Method::Naive);
        emit naive->hovered(naive->at(0), true);
        const QString readout = naive->property(kHoverReadoutProperty).toString();
        EXPECT_TRUE(readout.startsWith(naive->name())) << readout.toStdString();
        EXPECT_TRUE(readout.contains("relative L1 error: " + QString::number(naive->at(0).y(), 'g', 4)))
            << readout.toStdString();
        emit naive->hovered(naive->at(0), false);
        EXPECT_TRUE(naive->property(kHoverReadoutProperty).toString().isEmpty());
    }
    // The Energy kept tab: evaluate's energy split of LEAN per mip, beside the mixture's energy.
    {
        const EvaluationResult& result = chart.report()->result;
        QTableWidget* energy = chart.energyTable();
        ASSERT_EQ(result.energySplits.size(), size_t(result.lastMip - result.firstMip + 1));
        ASSERT_EQ(energy->rowCount(), int(result.energySplits.size()));
        EXPECT_EQ(energy->horizontalHeaderItem(5)->text(), "mixture-k3 keeps");
        auto energyOf = [&](Method method, int mip) {
            for (const MipError& e : result.errors)
                if (e.method == method && e.mip == mip && e.kernel == FilterKernel::Box && !e.betweenTexels)
                    return e.energyRatio;
            return -1.0;
        };
        for (int r = 0; r < energy->rowCount(); ++r) {
            const LeanEnergySplit& e = result.energySplits[size_t(r)];
            EXPECT_EQ(energy->item(r, 0)->text().toInt(), e.mip);
            EXPECT_NEAR(e.energy, energyOf(Method::Lean, e.mip), 1e-12 * e.energy)
                << "LEAN's row, mip " << e.mip;
            EXPECT_NEAR(e.cosine * e.shape * e.steep, e.energy, 1e-12 * e.energy);
            const double shown[] = {e.energy, e.cosine, e.shape, e.steep, energyOf(Method::Mixture, e.mip)};
            for (int c = 1; c <= 5; ++c) {
                ASSERT_NE(energy->item(r, c), nullptr) << "row " << r << ", column " << c;
                EXPECT_EQ(energy->item(r, c)->text(), QString::number(shown[c - 1], 'f', 3));
            }
        }
    }

    // Storage as the cost axis: LEAN stores more per texel than the naive normal map.
    chart.setCostAxis(ErrorCostChart::CostAxis::BytesPerTexel);
    EXPECT_GT(chart.methodSeries(Method::Lean)->at(0).x(), chart.methodSeries(Method::Naive)->at(0).x());

    // The mixture's point is the document's lobe count: another K is another evaluation.
    auto mixtureLobes = [&] {
        std::set<int> lobes;
        for (const MipError& e : chart.report()->result.errors)
            if (e.method == Method::Mixture) lobes.insert(e.lobes);
        return lobes;
    };
    EXPECT_EQ(mixtureLobes(), std::set<int>{kDefaultMixtureLobes});
    doc.setMixtureLobes(2);
    chart.evaluateNow();
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    ASSERT_NE(chart.report(), nullptr) << chart.statusText().toStdString();
    EXPECT_EQ(mixtureLobes(), std::set<int>{2});
    EXPECT_TRUE(chart.methodSeries(Method::Mixture)->name().startsWith("mixture-k2"))
        << chart.methodSeries(Method::Mixture)->name().toStdString();
    EXPECT_EQ(chart.energyTable()->horizontalHeaderItem(5)->text(), "mixture-k2 keeps");
}

/// Loads the hammered sample at `size`² into `doc` through an 8-bit PNG written in `dir`.
void loadHammered(MaterialDocument& doc, const test::TempDir& dir, int size) {
    const NormalMap sample = makeSampleNormalMap(SampleMapKind::Hammered, size);
    QImage png(size, size, QImage::Format_RGB888);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const glm::vec3 nrm = sample.at(x, y);
            auto byte = [](float c) { return int(std::lround((c * 0.5f + 0.5f) * 255.0f)); };
            png.setPixel(x, y, qRgb(byte(nrm.x), byte(nrm.y), byte(nrm.z)));
        }
    const QString path = QString::fromStdString((dir / "hammered.png").string());
    ASSERT_TRUE(png.save(path));
    ASSERT_TRUE(doc.loadMap(MapSlot::Normal, path));
    ASSERT_EQ(doc.maps().normal->width, size);
}

// The document's default normal map (the 512² sample) evaluates for seconds: long enough to act
// while it runs. Waiting for its first visible progress:
constexpr int kFirstProgressTimeoutMs = 60000;

/// Processes events until the progress bar shows more than 0% (the worker is past its first steps).
bool waitForProgress(ErrorCostChart& chart) {
    QElapsedTimer timer;
    timer.start();
    while (chart.progressBar()->value() <= 0 && timer.elapsed() < kFirstProgressTimeoutMs)
        QTest::qWait(10);
    return chart.progressBar()->value() > 0;
}

// The chart evaluates a small map by itself when shown; a map larger than 1024² only when asked
// (an 8192² map started by itself, ran for minutes and took 17 GB), and it says so.
TEST(ErrorCostChart, BigMapsAreEvaluatedOnlyWhenAsked) {
    test::TempDir dir;
    MaterialDocument doc;
    loadHammered(doc, dir, kSmallMap);
    {
        ErrorCostChart chart(&doc);
        QSignalSpy updated(&chart, &ErrorCostChart::methodsUpdated);
        chart.show();
        EXPECT_TRUE(chart.evaluatesByItself());
        ASSERT_TRUE(updated.wait(kWorkerTimeoutMs)) << "a small map is evaluated when the chart shows";
    }
    QImage big(1040, 1024, QImage::Format_RGB888); // just above 1024²
    big.fill(QColor(128, 128, 255));
    const QString path = QString::fromStdString((dir / "big.png").string());
    ASSERT_TRUE(big.save(path));
    ASSERT_TRUE(doc.loadMap(MapSlot::Normal, path));
    ErrorCostChart chart(&doc);
    EXPECT_FALSE(chart.evaluatesByItself());
    chart.show();
    QTest::qWait(1000); // well past the debounce
    EXPECT_FALSE(chart.evaluating());
    EXPECT_EQ(chart.report(), nullptr);
    EXPECT_TRUE(chart.statusText().contains("1040×1024")) << chart.statusText().toStdString();
    EXPECT_TRUE(chart.statusText().contains("Evaluate now")) << chart.statusText().toStdString();
    chart.evaluateNow();
    EXPECT_TRUE(chart.evaluating()) << "pressing Evaluate now runs it";
    chart.cancelEvaluation();
}

TEST(ErrorCostChart, ProgressBarShowsWhileRunningAndReaches100) {
    test::TempDir dir;
    MaterialDocument doc;
    loadHammered(doc, dir, kSmallMap);
    ErrorCostChart chart(&doc);
    QProgressBar* bar = chart.progressBar();
    ASSERT_NE(bar, nullptr);
    EXPECT_FALSE(bar->isVisibleTo(&chart)) << "no bar before anything runs";
    QList<int> values;
    QObject::connect(bar, &QProgressBar::valueChanged, [&](int v) { values << v; });
    QSignalSpy updated(&chart, &ErrorCostChart::methodsUpdated);
    chart.evaluateNow();
    EXPECT_TRUE(bar->isVisibleTo(&chart)) << "the bar shows in the tab while the worker runs";
    EXPECT_TRUE(chart.cancelButton()->isVisibleTo(&chart));
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    ASSERT_NE(chart.report(), nullptr) << chart.statusText().toStdString();
    EXPECT_EQ(bar->value(), bar->maximum()) << "a finished run ends at 100%";
    EXPECT_EQ(bar->maximum(), 100);
    ASSERT_FALSE(values.isEmpty());
    // 0 at the start, then steps in between (the evaluation reports each direction pair), then 100.
    EXPECT_TRUE(std::any_of(values.begin(), values.end(), [](int v) { return v > 0 && v < 100; }))
        << "the bar moves while the worker runs, not only at its end";
    EXPECT_TRUE(std::is_sorted(values.begin() + 1, values.end())) << "progress never goes back";
    EXPECT_FALSE(bar->isVisibleTo(&chart)) << "the bar goes when the run is done";
    EXPECT_FALSE(chart.cancelButton()->isVisibleTo(&chart));
}

TEST(ErrorCostChart, CancelStopsALongRunWithACancelledStateAndNoPoints) {
    MaterialDocument doc; // the 512² sample
    ErrorCostChart chart(&doc);
    QSignalSpy updated(&chart, &ErrorCostChart::methodsUpdated);
    chart.evaluateNow();
    ASSERT_TRUE(waitForProgress(chart)) << chart.statusText().toStdString();
    const int atCancel = chart.progressBar()->value();
    EXPECT_LT(atCancel, 100) << "cancelled before the end";
    ASSERT_TRUE(chart.cancelButton()->isVisibleTo(&chart));
    ASSERT_TRUE(chart.cancelButton()->isEnabled());
    QTest::mouseClick(chart.cancelButton(), Qt::LeftButton);
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    EXPECT_FALSE(chart.evaluating());
    EXPECT_EQ(chart.report(), nullptr) << "a cancelled run leaves no report";
    EXPECT_TRUE(chart.statusText().contains("cancelled")) << chart.statusText().toStdString();
    for (Method method : allMethods())
        EXPECT_EQ(chart.methodSeries(method), nullptr) << methodName(method) << " has no point";
    EXPECT_FALSE(chart.progressBar()->isVisibleTo(&chart));
    EXPECT_FALSE(chart.cancelButton()->isVisibleTo(&chart));
}

TEST(ErrorCostChart, ANewerEvaluationReplacesTheRunningOne) {
    test::TempDir dir;
    MaterialDocument doc;
    loadHammered(doc, dir, kSmallMap);
    ErrorCostChart chart(&doc);
    QSignalSpy updated(&chart, &ErrorCostChart::methodsUpdated);
    chart.evaluateNow();
    chart.evaluateNow();
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    ASSERT_NE(chart.report(), nullptr) << chart.statusText().toStdString();
    // Let the first worker's own result (cancelled or finished) arrive: it is dropped, not shown.
    constexpr int kSettleMs = 500;
    QTest::qWait(kSettleMs);
    EXPECT_EQ(updated.count(), 1) << "only the newer evaluation reports";
    EXPECT_FALSE(chart.evaluating());
}

TEST(ErrorCostChart, DestroyingTheChartMidRunJoinsItsWorker) {
    MaterialDocument doc; // the 512² sample: seconds of work left when the chart goes
    auto* chart = new ErrorCostChart(&doc);
    chart->evaluateNow();
    ASSERT_TRUE(waitForProgress(*chart)) << chart->statusText().toStdString();
    const QList<QThread*> threads = chart->findChildren<QThread*>();
    ASSERT_EQ(threads.size(), 1) << "one worker runs";
    QPointer<QThread> worker = threads.front();
    ASSERT_TRUE(worker->isRunning());
    std::atomic<bool> finished{false};
    QObject::connect(
        worker.data(), &QThread::finished, worker.data(), [&finished] { finished = true; },
        Qt::DirectConnection);
    delete chart; // a running QThread destroyed with its parent would abort the process
    EXPECT_TRUE(finished) << "the worker ended before the chart was gone";
    EXPECT_TRUE(worker.isNull()) << "and its thread object went with the chart";
    // The worker's queued results find no chart: nothing happens.
    QApplication::processEvents();
}

TEST(ErrorCostChart, CancellingTheApproximationsShowsCancelled) {
    MaterialDocument doc;
    ErrorCostChart chart(&doc);
    QSignalSpy updated(&chart, &ErrorCostChart::approximationsUpdated);
    chart.measureApproximationsNow();
    ASSERT_TRUE(chart.measuring());
    chart.cancelApproximations();
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    EXPECT_FALSE(chart.measuring());
    EXPECT_TRUE(chart.approximationSeries().isEmpty()) << "a cancelled measurement shows no points";
}

TEST(ChartsPanel, TheMainWindowHasAChartsDockWithAViewToggle) {
    MainWindow window;
    window.setAutosaveDelay(0);
    auto* panel = window.findChild<ChartsPanel*>("chartsDock");
    ASSERT_NE(panel, nullptr);
    window.document()->setGloss(0.25);
    EXPECT_EQ(panel->brdfPlots()->findSeries("gloss/current")->at(0).x(), 0.25)
        << "the charts show the window's document";
    QAction* toggle = panel->toggleViewAction();
    bool inViewMenu = false;
    for (QAction* menu : window.menuBar()->actions())
        if (menu->menu() && menu->menu()->actions().contains(toggle)) inViewMenu = true;
    EXPECT_TRUE(inViewMenu) << "the View menu toggles the Charts dock";
}

TEST(ErrorCostChart, ARoughnessPresetIsEvaluatedUnderGgxWithTheFittedLobe) {
    // The gltf preset's engine shades GGX: the chart evaluates the methods with a GGX form, the fitted
    // lobe among them (never above naive or vmf), and names the truth; LEAN has no point there.
    MaterialDocument doc;
    ASSERT_TRUE(doc.setPreset("gltf")) << "gltf preset";
    ErrorCostChart chart(&doc);
    QSignalSpy updated(&chart, &ErrorCostChart::methodsUpdated);
    chart.evaluateNow();
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    ASSERT_NE(chart.report(), nullptr) << chart.statusText().toStdString();
    EXPECT_EQ(chart.report()->options.brdf, Brdf::Ggx);
    EXPECT_NE(chart.methodSeries(Method::Fitted), nullptr);
    EXPECT_EQ(chart.methodSeries(Method::Lean), nullptr);
    EXPECT_NE(chart.statusText().indexOf("GGX"), -1) << chart.statusText().toStdString();
    auto error = [&](Method m, int mip) {
        for (const MipError& e : chart.report()->result.errors)
            if (e.method == m && e.mip == mip && e.kernel == FilterKernel::Box && !e.betweenTexels)
                return e.relativeL1;
        return -1.0;
    };
    for (int mip = chart.report()->result.firstMip; mip <= chart.report()->result.lastMip; ++mip) {
        EXPECT_LE(error(Method::Fitted, mip), error(Method::Naive, mip) + 1e-12) << mip;
        EXPECT_LE(error(Method::Fitted, mip), error(Method::Vmf, mip) + 1e-12) << mip;
    }
}

} // namespace
} // namespace burnish::studio
