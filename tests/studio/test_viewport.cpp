// The 3D viewport: it draws the document's material, follows the document, splits A/B, picks UVs
// and meters shimmer. Under the offscreen platform (ctest's) it draws in its own headless EGL context;
// under a display (xvfb-run with QT_QPA_PLATFORM=xcb) in a QOpenGLWidget. Both run the same tests.
#include "main_window.h"
#include "paint_tool.h"
#include "scene_from_document.h"
#include "texture_view.h"
#include "viewport.h"
#include "viewport_panel.h"

#include <burnish/render/context.h>
#include <burnish/render/mesh.h>
#include <burnish/render/renderer.h>
#include <burnish/render/shimmer.h>

#include "brush_of.h"
#include "temp_dir.h"
#include <fstream>
#include <gtest/gtest.h>

#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QElapsedTimer>
#include <QImage>
#include <QLabel>
#include <QProgressDialog>
#include <QSignalSpy>
#include <QTest>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

namespace burnish::studio {
namespace {

// A small view: the software rasterizer draws it in tens of milliseconds.
constexpr int kWidth = 320;
constexpr int kHeight = 240;
// A distance at which the 512² sample's bumps are a few texels per pixel: the methods differ most.
constexpr float kFarDistance = 8.0f;

struct Stats {
    double mean = 0.0;
    double stddev = 0.0;
};

// Mean and standard deviation of the 8-bit luma over columns [x0, x1).
Stats lumaStats(const QImage& image, int x0, int x1) {
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    for (int y = 0; y < image.height(); ++y)
        for (int x = x0; x < x1; ++x) {
            const QRgb p = image.pixel(x, y);
            const double Y = 0.2126 * qRed(p) + 0.7152 * qGreen(p) + 0.0722 * qBlue(p);
            sum += Y;
            sum2 += Y * Y;
            ++n;
        }
    Stats s;
    s.mean = sum / std::max(n, 1);
    s.stddev = std::sqrt(std::max(sum2 / std::max(n, 1) - s.mean * s.mean, 0.0));
    return s;
}

// Mean absolute difference of the RGB channels (0..255) over columns [x0, x1).
double meanAbsDiff(const QImage& a, const QImage& b, int x0, int x1) {
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < a.height(); ++y)
        for (int x = x0; x < x1; ++x) {
            const QRgb p = a.pixel(x, y), q = b.pixel(x, y);
            sum +=
                std::abs(qRed(p) - qRed(q)) + std::abs(qGreen(p) - qGreen(q)) + std::abs(qBlue(p) - qBlue(q));
            n += 3;
        }
    return sum / std::max(n, 1);
}

/// A shown viewport of kWidth × kHeight over its own document.
// An axis-aligned box from `lo` to `hi` as an OBJ, each face with the unit square's UVs.
void writeBoxObj(const std::filesystem::path& path, const glm::vec3& lo, const glm::vec3& hi) {
    std::ofstream obj(path);
    for (int i = 0; i < 8; ++i)
        obj << "v " << (i & 1 ? hi.x : lo.x) << ' ' << (i & 2 ? hi.y : lo.y) << ' ' << (i & 4 ? hi.z : lo.z)
            << "\n";
    obj << "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
    for (const char* face : {"1 3 4 2", "5 6 8 7", "1 2 6 5", "3 7 8 4", "1 5 7 3", "2 4 8 6"}) {
        int a, b, c, d;
        std::sscanf(face, "%d %d %d %d", &a, &b, &c, &d);
        obj << "f " << a << "/1 " << b << "/2 " << c << "/3 " << d << "/4\n";
    }
}

struct TestViewport {
    MaterialDocument doc;
    Viewport view{&doc};
    TestViewport() {
        view.resize(kWidth, kHeight);
        view.show();
        QApplication::processEvents();
    }
    QImage grab() {
        QImage image = view.grabFrame().convertToFormat(QImage::Format_RGB32);
        EXPECT_EQ(view.lastError(), QString()) << "rendering failed";
        return image;
    }
};

TEST(Viewport, RendersTheSampleNonBlank) {
    TestViewport t;
    const QImage frame = t.grab();
    ASSERT_FALSE(frame.isNull()) << t.view.contextDescription().toStdString();
    ASSERT_EQ(frame.width(), kWidth);
    RecordProperty("surface", t.view.usesOpenGlWidget() ? "QOpenGLWidget" : "headless image");
    RecordProperty("context", t.view.contextDescription().toStdString());
    // A lit, bumpy sphere over the environment: the luma spreads over much of the 8-bit range;
    // a blank or uniform frame has a deviation of 0.
    constexpr double kMinLumaDeviation = 10.0;
    EXPECT_GT(lumaStats(frame, 0, kWidth).stddev, kMinLumaDeviation);
    // The sphere is in the middle, the corners are background: the environment (the procedural
    // studio) by default, black once "Show as background" is off, and back with undo.
    auto cornerSum = [](const QImage& image) {
        const QRgb corner = image.pixel(1, 1);
        return qRed(corner) + qGreen(corner) + qBlue(corner);
    };
    EXPECT_TRUE(t.doc.settings().environment.background);
    EXPECT_GT(cornerSum(frame), 0) << "the environment is drawn behind the sphere";
    EnvironmentSettings off = t.doc.settings().environment;
    off.background = false;
    t.doc.setEnvironment(off);
    EXPECT_EQ(cornerSum(t.grab()), 0) << "without the background the cleared frame is black";
    t.doc.undoStack()->undo();
    EXPECT_GT(cornerSum(t.grab()), 0) << "undo brings the background back";
    EXPECT_GT(t.view.frameMs(), 0.0);
}

// An OBJ mesh as a user loads one: a valid mesh is drawn (its own silhouette, not the sphere's); a
// file that is not a mesh is refused with the reason and leaves the mesh as it was.
TEST(Viewport, ObjMeshesDrawAndBadOnesAreRefused) {
    TestViewport t;
    const QImage sphere = t.grab();
    const QString quad = QString(BURNISH_SOURCE_DIR) + "/tests/fuzz/corpus/obj/quad.obj";
    ASSERT_TRUE(t.view.setMesh(render::MeshKind::Obj, quad)) << quad.toStdString();
    EXPECT_EQ(t.view.viewSettings().mesh, render::MeshKind::Obj);
    const QImage mesh = t.grab();
    EXPECT_GT(lumaStats(mesh, 0, kWidth).stddev, 1.0) << "the quad is lit";
    EXPECT_GT(meanAbsDiff(sphere, mesh, 0, kWidth), 1.0) << "another silhouette than the sphere's";

    test::TempDir dir;
    std::ofstream(dir / "junk.obj") << "this is not a mesh\n";
    const Status bad =
        t.view.setMesh(render::MeshKind::Obj, QString::fromStdString((dir / "junk.obj").string()));
    ASSERT_FALSE(bad);
    EXPECT_NE(bad.error().find("junk.obj"), std::string::npos) << bad.error();
    EXPECT_EQ(t.view.viewSettings().objPath, quad) << "the mesh drawn before stays";
}

// A refused OBJ is said where the user looks (issue 48, point 3: it hid in the mesh box's tooltip,
// with the path twice, and stayed there): the window shows one message naming the file once, the
// mesh drawn before stays, and nothing is left in the tooltips.
TEST(Viewport, ARefusedMeshIsShownToTheUser) {
    MainWindow window;
    window.setAutosaveDelay(0);
    QStringList shown;
    window.showMessage = [&](const QString& title, const QString& text) { shown << title + ": " + text; };
    auto* panel = window.findChild<ViewportPanel*>();
    ASSERT_NE(panel, nullptr);
    test::TempDir dir;
    const QString junk = QString::fromStdString((dir / "renamed.obj").string());
    std::ofstream(dir / "renamed.obj") << "\x89PNG this was an image";
    EXPECT_FALSE(panel->loadMesh(render::MeshKind::Obj, junk));
    ASSERT_EQ(shown.size(), 1);
    EXPECT_TRUE(shown[0].startsWith("Cannot use this mesh: ")) << shown[0].toStdString();
    EXPECT_EQ(shown[0].count("renamed.obj"), 1) << shown[0].toStdString();
    EXPECT_EQ(panel->viewport()->viewSettings().mesh, render::MeshKind::Sphere) << "the sphere stays";
    EXPECT_TRUE(panel->meshCombo()->toolTip().isEmpty() ||
                !panel->meshCombo()->toolTip().contains("renamed"));
    const QString quad = QString(BURNISH_SOURCE_DIR) + "/tests/fuzz/corpus/obj/quad.obj";
    EXPECT_TRUE(panel->loadMesh(render::MeshKind::Obj, quad));
    EXPECT_EQ(shown.size(), 1) << "a mesh that loads says nothing";
}

// The distance counts in the mesh's radii: at the closest setting the camera stays outside an OBJ
// ten times the sphere's size (a cube of half-size 10: its corners 17.3 from the centre), where a
// distance in the sphere's radii would put it inside; the built-in meshes keep radius 1.
TEST(Viewport, TheClosestDistanceStaysOutsideABigMesh) {
    TestViewport t;
    t.view.setDistance(0.0f);
    EXPECT_FLOAT_EQ(t.view.cameraDistance(), Viewport::kMinDistance) << "the sphere's radius is 1";
    test::TempDir dir;
    writeBoxObj(dir / "box.obj", glm::vec3(-10.0f), glm::vec3(10.0f));
    ASSERT_TRUE(t.view.setMesh(render::MeshKind::Obj, QString::fromStdString((dir / "box.obj").string())));
    const float corner = std::sqrt(300.0f);
    EXPECT_NEAR(t.view.meshRadius(), corner, 1e-3f);
    EXPECT_GE(t.view.cameraDistance(), Viewport::kMinDistance * corner * 0.999f);
    const QImage frame = t.grab();
    EXPECT_GT(lumaStats(frame, 0, kWidth).stddev, 1.0) << "the box draws";
    ASSERT_TRUE(t.view.setMesh(render::MeshKind::Torus));
    EXPECT_FLOAT_EQ(t.view.cameraDistance(), Viewport::kMinDistance);
}

// The camera aimed at an OBJ's origin, not its bounds (issue 48, point 7): a tall mesh standing
// beside its origin was cut off. Now a new mesh is framed by its bounding box's centre, and
// frameObject() aims there again after the camera moved.
TEST(Viewport, AMeshIsFramedByItsBoundsAndFrameObjectAimsThereAgain) {
    TestViewport t;
    test::TempDir dir;
    // A post 2 wide and 6 tall standing at x = 20: its origin lies far outside it.
    writeBoxObj(dir / "post.obj", glm::vec3(19.0f, 0.0f, -1.0f), glm::vec3(21.0f, 6.0f, 1.0f));
    ASSERT_TRUE(t.view.setMesh(render::MeshKind::Obj, QString::fromStdString((dir / "post.obj").string())));
    const glm::vec3 centre(20.0f, 3.0f, 0.0f);
    EXPECT_LT(glm::length(t.view.viewSettings().target - centre), 1e-4f);
    EXPECT_NEAR(t.view.meshRadius(), std::sqrt(11.0f), 1e-4f); // a corner from the centre: (1, 3, 1)
    t.grab();
    EXPECT_TRUE(t.view.uvAt(QPoint(kWidth / 2, kHeight / 2)).has_value()) << "the post fills the centre";

    // Panned away and zoomed out, then framed again: aimed at its centre from the default distance.
    ViewSettings moved = t.view.viewSettings();
    moved.target = glm::vec3(0.0f);
    t.view.setViewSettings(moved);
    t.view.setDistance(40.0f);
    t.grab();
    EXPECT_FALSE(t.view.uvAt(QPoint(kWidth / 2, kHeight / 2)).has_value()) << "looking past it";
    const float yaw = t.view.viewSettings().yawDegrees;
    t.view.frameObject();
    EXPECT_LT(glm::length(t.view.viewSettings().target - centre), 1e-4f);
    EXPECT_FLOAT_EQ(t.view.viewSettings().distance, ViewSettings{}.distance);
    EXPECT_FLOAT_EQ(t.view.viewSettings().yawDegrees, yaw) << "its direction kept";
    t.grab();
    EXPECT_TRUE(t.view.uvAt(QPoint(kWidth / 2, kHeight / 2)).has_value());
    // The built-in meshes sit on the origin.
    ASSERT_TRUE(t.view.setMesh(render::MeshKind::Sphere));
    EXPECT_EQ(t.view.viewSettings().target, glm::vec3(0.0f));
}

// A 4-million-triangle OBJ froze the window for seconds and was parsed twice (issue 48, point 8):
// the panel reads it on a worker thread, the bounds and the renderer's upload share that one parse,
// and a cancelled read leaves the mesh drawn before.
TEST(Viewport, AnObjIsReadInTheBackgroundOnceAndACancelKeepsTheMeshBefore) {
    test::TempDir dir;
    auto writeGrid = [&](const std::string& name, int n) {
        std::ofstream obj(dir / name);
        for (int y = 0; y <= n; ++y)
            for (int x = 0; x <= n; ++x)
                obj << "v " << x << " 0 " << y << "\nvt " << double(x) / n << ' ' << double(y) / n << "\n";
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const int a = y * (n + 1) + x + 1, b = a + 1, c = a + n + 2, d = a + n + 1;
                obj << "f " << a << '/' << a << ' ' << b << '/' << b << ' ' << c << '/' << c << ' ' << d
                    << '/' << d << "\n";
            }
        return QString::fromStdString((dir / name).string());
    };
    const QString grid = writeGrid("grid.obj", 150); // 45 000 triangles
    const QString other = writeGrid("other.obj", 120);
    MaterialDocument doc;
    ViewportPanel panel(&doc);
    panel.resize(kWidth, kHeight + 80);
    panel.show();
    QApplication::processEvents();
    panel.setBackgroundLoads(true);
    QSignalSpy done(&panel, &ViewportPanel::meshLoaded);
    const std::uint64_t parsedBefore = render::objFilesParsed();
    panel.loadMeshInBackground(grid);
    EXPECT_TRUE(panel.meshLoading());
    EXPECT_EQ(panel.viewport()->viewSettings().mesh, render::MeshKind::Sphere) << "drawn once read";
    ASSERT_TRUE(done.wait(60000));
    EXPECT_TRUE(done.at(0).at(0).toBool());
    EXPECT_FALSE(panel.meshLoading());
    EXPECT_EQ(panel.viewport()->viewSettings().objPath, grid);
    const QImage frame = panel.viewport()->grabFrame();
    EXPECT_EQ(panel.viewport()->lastError(), QString());
    EXPECT_EQ(render::objFilesParsed(), parsedBefore + 1)
        << "the worker's read, the bounds and the upload: one parse";

    // Cancelled: the mesh before stays, and the read's late result is dropped.
    panel.loadMeshInBackground(other);
    auto* progress = panel.findChild<QProgressDialog*>();
    ASSERT_NE(progress, nullptr);
    emit progress->canceled(); // its Cancel button
    ASSERT_EQ(done.size(), 2);
    EXPECT_FALSE(done.at(1).at(0).toBool());
    QElapsedTimer waited;
    waited.start();
    while (render::objFilesParsed() < parsedBefore + 2 && waited.elapsed() < 30000)
        QApplication::processEvents(QEventLoop::AllEvents, 50);
    for (int i = 0; i < 10; ++i)
        QApplication::processEvents(QEventLoop::AllEvents, 20); // its queued result, if any, arrives
    EXPECT_EQ(panel.viewport()->viewSettings().objPath, grid);
    EXPECT_EQ(done.size(), 2);
}

TEST(Viewport, ChangingTheDocumentsMethodChangesTheImage) {
    TestViewport t;
    t.view.setDistance(kFarDistance);
    ASSERT_TRUE(t.doc.setMethod(Method::Naive));
    const QImage naive = t.grab();
    ASSERT_TRUE(t.doc.setMethod(Method::VarianceToGloss));
    const QImage baked = t.grab();
    // Naive keeps the base power where the bumps have averaged out, variance-to-gloss widens the
    // lobe: the highlight's shape changes over many pixels. Identical images differ by 0.
    constexpr double kMinMeanDifference = 0.2;
    EXPECT_GT(meanAbsDiff(naive, baked, 0, kWidth), kMinMeanDifference);
    // Undo restores the method and the picture.
    t.doc.undoStack()->undo();
    const QImage undone = t.grab();
    constexpr double kSameImage = 1e-9; // the same scene draws the same bytes
    EXPECT_LT(meanAbsDiff(naive, undone, 0, kWidth), kSameImage);
}

// With background bakes a change of method draws the last baked material meanwhile and says it is
// baking; the frame that takes the bake in draws the new method and the note goes.
TEST(Viewport, ABackgroundBakeIsShownUntilItLands) {
    TestViewport t;
    t.view.setBackgroundBakes(true);
    t.view.setDistance(kFarDistance);
    const QImage first = t.grab(); // the first bake is taken in at once
    EXPECT_FALSE(t.view.bakingShown());
    ASSERT_TRUE(t.doc.setMethod(Method::Naive));
    const QImage meanwhile = t.grab();
    EXPECT_TRUE(t.view.bakingShown());
    EXPECT_LT(meanAbsDiff(first, meanwhile, 0, kWidth), 1e-9) << "the last baked material is drawn";
    QImage landed;
    for (int i = 0; i < 400 && t.view.bakingShown(); ++i) {
        QTest::qWait(10);
        landed = t.grab();
    }
    EXPECT_FALSE(t.view.bakingShown());
    EXPECT_GT(meanAbsDiff(first, landed, 0, kWidth), 0.2) << "naive drawn once baked";
    // A request that comes back to what is drawn draws it at once, and the bake started for the
    // withdrawn one is never taken in.
    ASSERT_TRUE(t.doc.setMethod(Method::Vmf));
    t.grab();
    EXPECT_TRUE(t.view.bakingShown());
    t.doc.undoStack()->undo(); // back to naive, which is drawn
    const QImage back = t.grab();
    EXPECT_FALSE(t.view.bakingShown());
    EXPECT_LT(meanAbsDiff(landed, back, 0, kWidth), 1e-9);
    QTest::qWait(500); // the vMF bake finishes meanwhile
    EXPECT_LT(meanAbsDiff(landed, t.grab(), 0, kWidth), 1e-9);
    EXPECT_FALSE(t.view.bakingShown());
}

using test::brushOf;

/// Paints one gloss stroke through the paint tool (one undo step): a brush as wide as the sample,
/// dragged across its middle row, so the whole visible surface takes the painted gloss.
void paintAcross(MaterialDocument& doc, float gloss) {
    TextureView canvas;
    PaintTool tool(&doc, &canvas);
    tool.setBrush(brushOf(kSampleSize, 1.0, 1.0, gloss)); // covers the map from the middle row, wrapping
    tool.pressAt(QPointF(0.0, kSampleSize / 2.0));
    tool.moveTo(QPointF(kSampleSize, kSampleSize / 2.0));
    tool.release();
}

TEST(Viewport, APaintedStrokeChangesTheImageAndUndoRestoresIt) {
    TestViewport t;
    t.view.setDistance(kFarDistance);
    const QImage before = t.grab();
    // Gloss 0 is the encoding's lowest power (1 for Black Ops' 8192^g) against the default 0.7
    // (power ~550): the highlight spreads over the whole sphere.
    paintAcross(t.doc, 0.0f);
    ASSERT_TRUE(t.doc.paintLayer(PaintLayerKind::Gloss).painted());
    const QImage painted = t.grab();
    constexpr double kMinMeanDifference = 0.2; // as the method change: many pixels move visibly
    EXPECT_GT(meanAbsDiff(before, painted, 0, kWidth), kMinMeanDifference)
        << "the viewport draws the painted gloss, not the base gloss";
    t.doc.undoStack()->undo();
    const QImage undone = t.grab();
    constexpr double kSameImage = 1e-9; // the same scene draws the same bytes
    EXPECT_LT(meanAbsDiff(before, undone, 0, kWidth), kSameImage);
}

TEST(Viewport, EachDabOfAStrokeRedrawsBeforeTheStrokeEnds) {
    TestViewport t;
    // Close up: the sphere fills much of the view, so a half-map dab moves many pixels.
    const QImage before = t.grab();
    QSignalSpy frames(&t.view, &Viewport::frameRendered);
    QSignalSpy strokeEnds(&t.doc, &MaterialDocument::changed);
    TextureView canvas;
    PaintTool tool(&t.doc, &canvas);
    // Half the map wide, hard, full strength, gloss 0 (power ~1 against the base 0.7): a dab
    // visibly flattens the highlight where it lands.
    tool.setBrush(brushOf(kSampleSize / 2.0, 1.0, 1.0, 0.0f));
    // A redraw, its re-bake included, must come within this on a loaded software rasterizer.
    constexpr int kFrameTimeoutMs = 30000;

    // Dab 1 at the map's left edge (wrapping): a frame follows without the stroke ending.
    tool.pressAt(QPointF(0.0, kSampleSize / 2.0));
    ASSERT_TRUE(frames.wait(kFrameTimeoutMs)) << "the viewport redraws on a dab, not only at stroke end";
    const double dabFrameMs = frames.last().at(0).toDouble();
    const QImage afterFirst = t.grab();
    // Dab 2 half a map away: the stroke sweeps the middle of the map.
    frames.clear();
    tool.moveTo(QPointF(kSampleSize / 2.0, kSampleSize / 2.0));
    ASSERT_TRUE(frames.wait(kFrameTimeoutMs)) << "the second dab redraws too (throttled, not dropped)";
    const QImage afterSecond = t.grab();
    EXPECT_EQ(strokeEnds.count(), 0) << "both dabs belong to one stroke still in progress";

    // As the stroke test: identical images differ by 0, a visible change of gloss by far more.
    constexpr double kMinMeanDifference = 0.2;
    EXPECT_GT(meanAbsDiff(before, afterFirst, 0, kWidth), kMinMeanDifference) << "dab 1 shows";
    EXPECT_GT(meanAbsDiff(afterFirst, afterSecond, 0, kWidth), kMinMeanDifference) << "dab 2 shows";

    // The cost of a dab's frame (the 512² re-bake of the authored gloss included) against a plain
    // redraw of the same scene, for the record (not a pass/fail timing).
    frames.clear();
    t.view.update();
    for (QWidget* w : t.view.findChildren<QWidget*>())
        w->update();
    const bool plain = frames.wait(kFrameTimeoutMs);
    RecordProperty("dab_frame_ms", std::to_string(dabFrameMs));
    if (plain) RecordProperty("plain_frame_ms", std::to_string(frames.last().at(0).toDouble()));
    std::printf("dab frame %.1f ms, plain frame %.1f ms\n", dabFrameMs,
                plain ? frames.last().at(0).toDouble() : -1.0);

    tool.release();
    EXPECT_EQ(strokeEnds.count(), 1) << "the stroke ends as one undo step";
}

// Painting with Paint on, the view draws each dab from the paint tool's live bake (only the texels
// it rebaked uploaded) instead of baking the map again, and draws exactly what a bake draws: after
// every dab, at the stroke's end and after undo, the frame equals a new view's, which bakes.
TEST(Viewport, StrokesDrawnFromTheLiveBakeAreTheFramesOfABake) {
    TestViewport t;
    t.view.setDistance(2.5f);
    TextureView canvas;
    PaintTool tool(&t.doc, &canvas);
    tool.attachViewport(&t.view);
    tool.setPaintMode(true); // the live bake is built at once (no background bakes)
    ASSERT_NE(tool.currentLive(), nullptr);
    (void)t.grab();
    auto bakedFrame = [&] {
        // The same document: a new view over it bakes what it draws.
        Viewport view{&t.doc};
        view.resize(kWidth, kHeight);
        view.show();
        view.setDistance(2.5f);
        QApplication::processEvents();
        return view.grabFrame().convertToFormat(QImage::Format_RGB32);
    };
    tool.setBrush(brushOf(kSampleSize / 6.0, 0.5, 1.0, 0.1f));
    const int before = t.view.liveGlossFrames();
    tool.pressAt(QPointF(kSampleSize * 0.3, kSampleSize * 0.5));
    const QImage firstDab = t.grab();
    EXPECT_EQ(t.view.liveGlossFrames(), before + 1);
    EXPECT_LT(meanAbsDiff(firstDab, bakedFrame(), 0, kWidth), 1e-9) << "the whole live chain, once";
    tool.moveTo(QPointF(kSampleSize * 0.6, kSampleSize * 0.45));
    const QImage secondDab = t.grab();
    EXPECT_EQ(t.view.liveGlossFrames(), before + 2) << "a region of the live chain";
    EXPECT_GT(meanAbsDiff(firstDab, secondDab, 0, kWidth), 0.01) << "the dab shows";
    EXPECT_LT(meanAbsDiff(secondDab, bakedFrame(), 0, kWidth), 1e-9) << "the region, exactly";
    tool.release();
    EXPECT_LT(meanAbsDiff(t.grab(), bakedFrame(), 0, kWidth), 1e-9) << "the stroke's end";
    // A second stroke, undone: the first one's paint stays, drawn from the live bake's region.
    tool.setBrush(brushOf(kSampleSize / 6.0, 0.5, 1.0, 0.95f));
    tool.pressAt(QPointF(kSampleSize * 0.5, kSampleSize * 0.2));
    tool.release();
    (void)t.grab();
    const int beforeUndo = t.view.liveGlossFrames();
    t.doc.undoStack()->undo();
    EXPECT_LT(meanAbsDiff(t.grab(), secondDab, 0, kWidth), 1e-9) << "undo";
    EXPECT_EQ(t.view.liveGlossFrames(), beforeUndo + 1);
}

TEST(SceneFromDocument, HandsOverThePaintedGlossKeepingItsIdentityUntilItChanges) {
    MaterialDocument doc;
    SceneFromDocument mapper;
    const auto plain = mapper.material(doc);
    ASSERT_TRUE(plain) << plain.error();
    EXPECT_FALSE(plain->glossMap) << "no gloss map, nothing painted: the base power";

    paintAcross(doc, 0.25f);
    const auto painted = mapper.material(doc);
    ASSERT_TRUE(painted) << painted.error();
    ASSERT_TRUE(painted->glossMap);
    ASSERT_TRUE(doc.authoredGloss());
    EXPECT_EQ(*painted->glossMap, *doc.authoredGloss()) << "the composited gloss, value for value";
    const std::vector<float> firstValues = *painted->glossMap;

    // The renderer keys its bake on the pointer: unchanged gloss, same pointer, no bake.
    const auto again = mapper.material(doc);
    ASSERT_TRUE(again);
    EXPECT_EQ(again->glossMap, painted->glossMap);
    doc.setCustomSpecular({0.5, 0.5, 0.5});
    const auto otherEdit = mapper.material(doc);
    ASSERT_TRUE(otherEdit);
    EXPECT_EQ(otherEdit->glossMap, painted->glossMap) << "an edit that leaves the gloss alone";

    // Another stroke: a new pointer, and the values the renderer holds are not written over.
    paintAcross(doc, 0.75f);
    const auto repainted = mapper.material(doc);
    ASSERT_TRUE(repainted);
    ASSERT_TRUE(repainted->glossMap);
    EXPECT_NE(repainted->glossMap, painted->glossMap);
    EXPECT_EQ(*painted->glossMap, firstValues);
    EXPECT_NE(*repainted->glossMap, firstValues);
}

TEST(Viewport, SplitShowsTheSecondMethodOnTheRight) {
    TestViewport t;
    t.view.setDistance(kFarDistance);
    ASSERT_TRUE(t.doc.setMethod(Method::Naive));
    t.view.setSplitPosition(0.5f);
    t.view.setSplit(true);
    t.view.setRightSide(SplitSide{false, Method::Naive});
    const QImage naiveNaive = t.grab();
    t.view.setRightSide(SplitSide{false, Method::Lean});
    const QImage naiveLean = t.grab();
    t.view.setSplit(false);
    const QImage whole = t.grab();

    const int half = kWidth / 2;
    // Columns kept clear of the divider on each side (its rounding and the sphere's middle).
    constexpr int kGuard = 2;
    constexpr double kSameImage = 1e-9; // the same scene draws the same bytes
    EXPECT_LT(meanAbsDiff(naiveNaive, whole, 0, kWidth), kSameImage)
        << "naive | naive is the whole naive frame";
    EXPECT_LT(meanAbsDiff(naiveLean, whole, 0, half - kGuard), kSameImage) << "A stays on the left";
    // LEAN's anisotropic lobe from the slope moments against the naive mirror-like highlight.
    constexpr double kMinMeanDifference = 0.2;
    EXPECT_GT(meanAbsDiff(naiveLean, whole, half + kGuard, kWidth), kMinMeanDifference)
        << "B (LEAN) differs from naive on the right";
}

TEST(Viewport, ReferenceSideDraws) {
    TestViewport t;
    t.view.setDistance(kFarDistance);
    t.view.setSplit(true);
    t.view.setReferenceSamples(4); // a few passes: this checks the wiring, not the convergence
    t.view.setRightSide(SplitSide{true, Method::Naive});
    const QImage frame = t.grab();
    constexpr double kMinLumaDeviation = 5.0; // the reference half shows a lit sphere, not black
    EXPECT_GT(lumaStats(frame, kWidth / 2 + 1, kWidth).stddev, kMinLumaDeviation);
}

TEST(Viewport, UvAtPicksTheObjectAndNothingOffIt) {
    TestViewport t;
    t.grab();
    const auto centre = t.view.uvAt(QPoint(kWidth / 2, kHeight / 2));
    ASSERT_TRUE(centre.has_value()) << "the sphere covers the view's centre";
    EXPECT_GE(centre->x(), 0.0);
    EXPECT_LT(centre->x(), 1.0);
    EXPECT_GE(centre->y(), 0.0);
    EXPECT_LT(centre->y(), 1.0);
    EXPECT_FALSE(t.view.uvAt(QPoint(2, 2)).has_value()) << "the corner is background";
    EXPECT_FALSE(t.view.uvAt(QPoint(-5, kHeight / 2)).has_value()) << "outside the widget";
    // The texture coordinate follows the surface: a point to the right has another u.
    constexpr int kStep = 20;
    const auto right = t.view.uvAt(QPoint(kWidth / 2 + kStep, kHeight / 2));
    ASSERT_TRUE(right.has_value());
    // One sphere around is 2 texture repeats (makeSphere's uvRepeat) over 2π: 20 px of a sphere
    // ~110 px in radius at the centre turn it by ~0.18 rad, ~0.06 in u; well above float noise.
    constexpr double kMinUvChange = 0.01;
    EXPECT_GT(std::abs(right->x() - centre->x()), kMinUvChange);
    // After turning the camera the same pixel shows another texel.
    t.view.orbit(30.0f, 0.0f);
    const auto turned = t.view.uvAt(QPoint(kWidth / 2, kHeight / 2));
    ASSERT_TRUE(turned.has_value());
    EXPECT_GT(std::abs(turned->x() - centre->x()), kMinUvChange) << "the pick follows the camera";
}

TEST(Viewport, ShimmerMeterReadsAfterAutoOrbitFrames) {
    TestViewport t;
    t.view.setDistance(kFarDistance);
    t.view.setReferenceSamples(4); // the meter's reference side: a few passes keep the test quick
    EXPECT_FALSE(t.view.shimmer().has_value());
    t.view.setAutoOrbit(true);
    constexpr int kFrames = 4; // three frame-to-frame deltas
    for (int i = 0; i < kFrames; ++i) {
        t.view.stepOrbit();
        t.grab();
    }
    t.view.setAutoOrbit(false);
    ASSERT_TRUE(t.view.shimmer().has_value());
    const ShimmerReading r = *t.view.shimmer();
    EXPECT_GE(r.deltas, kFrames - 1);
    EXPECT_TRUE(std::isfinite(r.a) && std::isfinite(r.b) && std::isfinite(r.ratio));
    // Turning a bumpy sphere under a fixed light moves its highlights: the method's frames change.
    EXPECT_GT(r.a, 0.0);
    EXPECT_GE(r.b, 0.0);
    // A view change other than the orbit starts the meter again.
    t.view.setExposure(1.0f);
    EXPECT_FALSE(t.view.shimmer().has_value());
}

TEST(Viewport, TheShimmerMeterReadsWhatRenderSequenceMeasuresOfTheSameOrbit) {
    // The meter and `burnish render --sequence` (render::measureShimmer) are one measurement: the
    // same orbit gives the same figures, the reference's noise included.
    TestViewport t;
    ASSERT_TRUE(t.doc.setMethod(Method::Naive));
    t.view.setDistance(kFarDistance);
    constexpr int kSamples = 4;
    t.view.setReferenceSamples(kSamples);
    t.grab();
    const auto start = t.view.scene();
    ASSERT_TRUE(start) << start.error();
    t.view.setAutoOrbit(true);
    constexpr int kFrames = 5;
    for (int i = 0; i < kFrames; ++i) {
        t.view.stepOrbit();
        t.grab();
    }
    t.view.setAutoOrbit(false);
    ASSERT_TRUE(t.view.shimmer().has_value());
    const ShimmerReading meter = *t.view.shimmer();
    EXPECT_EQ(meter.deltas, kFrames - 1);
    EXPECT_TRUE(meter.reference);

    // The first metered frame is one orbit step from the scene before; a renderer of the test's own.
    render::Scene first = *start;
    first.camera.yawDegrees += Viewport::kOrbitDegreesPerFrame;
    auto context = render::createHeadlessContext();
    ASSERT_TRUE(context) << context.error();
    ASSERT_TRUE((*context)->makeCurrent());
    auto renderer = render::Renderer::create();
    ASSERT_TRUE(renderer) << renderer.error();
    render::ShimmerOptions options;
    options.frames = kFrames;
    options.degreesPerFrame = Viewport::kOrbitDegreesPerFrame;
    options.width = options.height = 128; // the meter's size, `render --sequence`'s default
    options.referenceSamples = kSamples;
    options.estimateReferenceNoise = true;
    const auto report = render::measureShimmer(**renderer, first, options);
    ASSERT_TRUE(report) << report.error();
    std::cout << "meter: A " << meter.a << ", truth " << meter.b << " (noise " << meter.noise
              << "); render --sequence: " << report->methodMean << ", " << report->referenceMean << " ("
              << report->referenceNoise << ")\n";
    EXPECT_GT(meter.a, 0.0);
    EXPECT_DOUBLE_EQ(meter.a, report->methodMean);
    EXPECT_DOUBLE_EQ(meter.b, report->referenceMean);
    EXPECT_DOUBLE_EQ(meter.noise, report->referenceNoise);
}

TEST(Viewport, TheMixtureFilteredAfterShadingDrawsAndTheCheckFollowsTheMethod) {
    // The panel's "filter after shading" is enabled while A (or B) draws the mixture, and the view
    // then draws the stochastic filtering's average: lit, another image than the moment-filtered one
    // (the sample's lobes differ between texels), and back to it when turned off.
    MaterialDocument doc;
    auto* panel = new ViewportPanel(&doc);
    panel->resize(kWidth, kHeight + 80);
    panel->show();
    QApplication::processEvents();
    QCheckBox* check = panel->afterShadingCheck();
    EXPECT_FALSE(check->isEnabled());      // the default method, variance-to-gloss
    ASSERT_TRUE(doc.setPreset("mixture")); // the preset that stores the mixture's lobes
    ASSERT_TRUE(doc.setMethod(Method::Mixture));
    EXPECT_TRUE(check->isEnabled());
    Viewport* view = panel->viewport();
    view->setDistance(kFarDistance);
    view->setReferenceSamples(4); // a few passes: this checks the wiring, not the convergence
    auto grab = [&] {
        QImage image = view->grabFrame().convertToFormat(QImage::Format_RGB32);
        EXPECT_EQ(view->lastError(), QString());
        return image;
    };
    EXPECT_TRUE(check->isChecked()) << "on by default";
    check->setChecked(false);
    EXPECT_FALSE(view->viewSettings().filterAfterShading);
    const QImage moments = grab();
    check->setChecked(true);
    EXPECT_TRUE(view->viewSettings().filterAfterShading);
    const QImage after = grab();
    const int w = after.width();
    EXPECT_GT(lumaStats(after, 0, w).stddev, 5.0);
    EXPECT_GT(meanAbsDiff(moments, after, 0, w), 1e-3);
    check->setChecked(false);
    EXPECT_LT(meanAbsDiff(moments, grab(), 0, w), 1e-9);
    delete panel;
}

TEST(Viewport, AtRestTheMixtureFilteredAfterShadingAddsAPassAFrame) {
    // The view shows the average so far and asks for the next frame itself, up to the reference's
    // count of passes; a change of view starts again from one pass.
    MaterialDocument doc;
    auto* panel = new ViewportPanel(&doc);
    panel->resize(kWidth, kHeight + 80);
    panel->show();
    ASSERT_TRUE(doc.setPreset("mixture"));
    ASSERT_TRUE(doc.setMethod(Method::Mixture));
    Viewport* view = panel->viewport();
    view->setReferenceSamples(4);
    panel->afterShadingCheck()->setChecked(true);
    // Frames drawn by the event loop alone (each pass once the events before it are handled), with
    // the passes each frame shows.
    std::vector<int> frames;
    QObject::connect(view, &Viewport::frameRendered, view,
                     [&] { frames.push_back(view->progressivePasses()); });
    // The panel's frame readout (updated first, connected first) says how far the average has come
    // while passes are added.
    QStringList readouts;
    QObject::connect(view, &Viewport::frameRendered, view, [&] {
        for (const QLabel* label : panel->findChildren<QLabel*>())
            if (label->text().endsWith(" ms") || label->text().contains(" ms · pass")) {
                readouts << label->text();
                break;
            }
    });
    auto passesSeen = [&] {
        frames.clear();
        QElapsedTimer clock;
        clock.start();
        while (clock.elapsed() < 30000 && (frames.empty() || frames.back() < 4))
            QApplication::processEvents(QEventLoop::AllEvents, 20);
        return frames;
    };
    EXPECT_EQ(passesSeen(), (std::vector<int>{1, 2, 3, 4}));
    EXPECT_EQ(view->lastError(), QString());
    ASSERT_EQ(readouts.size(), 4);
    EXPECT_TRUE(readouts[1].endsWith(" ms · pass 2/4")) << readouts[1].toStdString();
    EXPECT_TRUE(readouts[3].endsWith(" ms")) << readouts[3].toStdString(); // every pass in
    view->setDistance(view->viewSettings().distance * 1.1f);
    EXPECT_EQ(passesSeen(), (std::vector<int>{1, 2, 3, 4}));
    // Nothing more is drawn once every pass is in.
    frames.clear();
    for (int i = 0; i < 20; ++i)
        QApplication::processEvents(QEventLoop::AllEvents, 10);
    EXPECT_TRUE(frames.empty());
    EXPECT_EQ(view->progressivePasses(), 4);
    // Beside the reference, which each frame would draw whole again, every pass in one frame.
    SplitSide reference;
    reference.reference = true;
    view->setRightSide(reference);
    view->setSplit(true);
    view->setDistance(view->viewSettings().distance * 1.1f); // a view side A has not drawn yet
    frames.clear();
    for (int i = 0; i < 30 && frames.empty(); ++i)
        QApplication::processEvents(QEventLoop::AllEvents, 20);
    for (int i = 0; i < 20; ++i)
        QApplication::processEvents(QEventLoop::AllEvents, 10);
    EXPECT_EQ(frames.size(), 1u);
    EXPECT_EQ(view->lastError(), QString());
    delete panel;
}

TEST(Viewport, MainWindowShowsTheRenderedViewport) {
    MainWindow window;
    window.setAutosaveDelay(0);
    window.resize(1400, 880);
    window.show();
    QApplication::processEvents();
    auto* panel = window.findChild<ViewportPanel*>();
    ASSERT_NE(panel, nullptr) << "the viewport is in the central area";
    Viewport* view = panel->viewport();
    ASSERT_GT(view->width(), 0);
    // The window grab (what --screenshot saves) holds the rendered sphere inside the viewport.
    const QImage shot = window.grab().toImage().convertToFormat(QImage::Format_RGB32);
    const QRect r(view->mapTo(&window, QPoint(0, 0)), view->size());
    const QImage inView = shot.copy(r);
    constexpr double kMinLumaDeviation = 10.0; // as RendersTheSampleNonBlank
    EXPECT_GT(lumaStats(inView, 0, inView.width()).stddev, kMinLumaDeviation);
    EXPECT_EQ(view->lastError(), QString());
}

} // namespace
} // namespace burnish::studio
