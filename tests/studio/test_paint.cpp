// Painting in the studio: strokes on the texture view, undo/redo, the eyedropper, the layers saved
// beside a project and loaded back, the texture pane's authored and baked views of the painted gloss,
// and the export of it (the bytes `burnish bake --gloss` writes for the same values). main() is
// test_studio.cpp's (one QApplication).
#include "bake_dialog.h"
#include "main_window.h"
#include "material_document.h"
#include "paint_tool.h"
#include "project.h"
#include "texture_pane.h"
#include "texture_view.h"
#include "viewport.h"
#include "viewport_panel.h"

#include "cli_run.h"
#include "temp_dir.h"

#include <burnish/core/util/files.h>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <QApplication>
#include <QComboBox>
#include <QDockWidget>
#include <QImage>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QRegularExpression>
#include <QSignalSpy>
#include <QTest>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>

using namespace burnish;
using namespace burnish::studio;

namespace {

// Composited gloss is computed in double and stored in float: within a float ulp of the value.
constexpr float kGlossTol = 1e-6f;

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// A press-drag-release with the left button across the view's centre row.
void dragAcross(TextureView* view) {
    const QPoint a(view->width() / 3, view->height() / 2), b(2 * view->width() / 3, view->height() / 2);
    QTest::mousePress(view, Qt::LeftButton, {}, a);
    QMouseEvent move(QEvent::MouseMove, QPointF(b), view->mapToGlobal(QPointF(b)), Qt::NoButton,
                     Qt::LeftButton, {});
    QApplication::sendEvent(view, &move);
    QTest::mouseRelease(view, Qt::LeftButton, {}, b);
}

// Waiting for a worker thread (a 512² bake takes well under a second; generous for loaded CI).
constexpr int kWorkerTimeoutMs = 60000;

// One stroke through the paint tool (one undo step) on `kind`, from `a` to `b` in texels.
void stroke(PaintTool& tool, PaintLayerKind kind, float value, double radius, QPointF a, QPointF b) {
    tool.setLayer(kind);
    Brush brush;
    brush.radius = radius;
    brush.hardness = 1.0;
    brush.opacity = 1.0;
    brush.value = value;
    tool.setBrush(brush);
    tool.pressAt(a);
    tool.moveTo(b);
    tool.release();
}

uchar grey(const QImage& image, int x, int y) {
    return uchar(qGray(image.pixel(x, y)));
}

// The gloss channel of core's bake of the document's composited gloss, at a mip, as the pane shows it.
QImage coreBakedGloss(const MaterialDocument& doc, int mip) {
    BakeOptions options;
    options.method = doc.settings().method;
    options.encoding = doc.preset().encoding;
    options.basePower = doc.power();
    if (doc.authoredGloss()) options.authoredGloss = *doc.authoredGloss();
    const auto baked = bake(*doc.maps().normal, options);
    EXPECT_TRUE(baked) << baked.error();
    if (!baked) return {};
    const BakedTexture* gloss = baked->find(TextureRole::Gloss);
    EXPECT_NE(gloss, nullptr);
    return gloss ? bakedChannelImage(gloss->mips[size_t(mip)], gloss->channels, 0) : QImage();
}

namespace fs = std::filesystem;

std::map<std::string, std::string> folderBytes(const fs::path& folder) {
    std::map<std::string, std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(folder))
        if (e.is_regular_file()) {
            auto bytes = readFile(e.path());
            files[fs::relative(e.path(), folder).string()] = bytes ? *bytes : "<unreadable>";
        }
    return files;
}

// The values as a one-channel float EXR (exact: the CLI reads back the same floats).
bool writeFloatExr(const fs::path& path, const std::vector<float>& values, int width, int height) {
    const auto out = OIIO::ImageOutput::create(path.string());
    return out && out->open(path.string(), OIIO::ImageSpec(width, height, 1, OIIO::TypeDesc::FLOAT)) &&
           out->write_image(OIIO::TypeDesc::FLOAT, values.data()) && out->close();
}

} // namespace

TEST(StudioPaint, StrokeOnTheViewChangesTheLayerAndUndoRestoresIt) {
    MainWindow window;
    window.setAutosaveDelay(0);
    window.resize(1200, 800);
    window.show();
    PaintTool* tool = window.paintTool();
    MaterialDocument* doc = window.document();
    TextureView* view = window.texturePane()->view();
    view->fit();
    const PaintLayer before = doc->paintLayer(PaintLayerKind::Gloss);
    ASSERT_FALSE(before.painted());
    Brush b;
    b.radius = 12.0;
    b.hardness = 1.0;
    b.opacity = 1.0;
    b.value = 0.95f;
    tool->setBrush(b);
    tool->setPaintMode(true);
    ASSERT_NE(tool->liveBake(), nullptr);
    const int steps = doc->undoStack()->count();
    dragAcross(view);
    EXPECT_EQ(doc->undoStack()->count(), steps + 1); // one stroke, one undo step
    const PaintLayer painted = doc->paintLayer(PaintLayerKind::Gloss);
    ASSERT_TRUE(painted.painted());
    ASSERT_TRUE(doc->authoredGloss());
    // The live bake follows the stroke and equals a full bake of the painted gloss's region.
    EXPECT_GT(tool->lastRecomputedTexels(), 0u);
    EXPECT_TRUE(sameBits(tool->liveBake()->authoredGloss(), *doc->authoredGloss()));
    // The over-shine count is in texels of the mip it names, never more than that mip has (it once
    // counted finest texels: "13941 texels over-shine at mip 3" where mip 3 had 4096).
    const auto* status = tool->findChild<QLabel*>("paintStatus");
    ASSERT_NE(status, nullptr);
    const QRegularExpression counted("(\\d+) of (\\d+) texels over-shine at mip (\\d+)");
    const QRegularExpressionMatch match = counted.match(status->text());
    ASSERT_TRUE(match.hasMatch()) << status->text().toStdString();
    const int mip = match.captured(3).toInt();
    const qulonglong texels =
        qulonglong(tool->liveBake()->levelWidth(mip)) * qulonglong(tool->liveBake()->levelHeight(mip));
    EXPECT_EQ(match.captured(2).toULongLong(), texels);
    EXPECT_GT(match.captured(1).toULongLong(), 0u); // 0.95 on the sample's bumps over-shines at mip 3
    EXPECT_LE(match.captured(1).toULongLong(), texels);

    doc->undoStack()->undo();
    EXPECT_TRUE(samePaint(doc->paintLayer(PaintLayerKind::Gloss), before));
    EXPECT_FALSE(doc->authoredGloss()); // nothing painted, no gloss map: the base power again
    doc->undoStack()->redo();
    EXPECT_TRUE(samePaint(doc->paintLayer(PaintLayerKind::Gloss), painted));

    // The eyedropper reads the painted gloss under the stroke's middle.
    const QPointF middle = view->texelAt(QPointF(view->width() / 2.0, view->height() / 2.0));
    tool->setEyedropper(true);
    tool->pressAt(middle);
    EXPECT_FALSE(tool->eyedropper()); // one pick, then back to the brush
    EXPECT_NEAR(tool->brush().value, 0.95f, kGlossTol);
    EXPECT_NEAR(tool->pickAt(middle), 0.95f, kGlossTol);

    // Clear layer: one undo step over the painted rectangle only, and undo brings the paint back.
    const int beforeClear = doc->undoStack()->count();
    tool->clearLayer();
    EXPECT_EQ(doc->undoStack()->count(), beforeClear + 1);
    EXPECT_FALSE(doc->paintLayer(PaintLayerKind::Gloss).painted());
    tool->clearLayer(); // nothing left to clear: no step
    EXPECT_EQ(doc->undoStack()->count(), beforeClear + 1);
    doc->undoStack()->undo();
    EXPECT_TRUE(samePaint(doc->paintLayer(PaintLayerKind::Gloss), painted));
    tool->setPaintMode(false);
}

TEST(StudioPaint, LayersSurviveASaveAndLoad) {
    test::TempDir dir;
    const QString file = QString::fromStdString((dir.path() / "painted.burnish").string());
    MainWindow window;
    window.setAutosaveDelay(0);
    MaterialDocument* doc = window.document();
    PaintTool* tool = window.paintTool();
    Brush b;
    b.radius = 20.0;
    b.value = 0.2f;
    tool->setBrush(b);
    tool->setLayer(PaintLayerKind::VarianceOffset);
    tool->pressAt({100.0, 100.0});
    tool->moveTo({180.0, 140.0});
    tool->release();
    tool->setLayer(PaintLayerKind::Gloss);
    b.value = 0.9f;
    tool->setBrush(b);
    tool->pressAt({300.0, 300.0});
    tool->release();
    const PaintLayer gloss = doc->paintLayer(PaintLayerKind::Gloss);
    const PaintLayer offset = doc->paintLayer(PaintLayerKind::VarianceOffset);
    const std::vector<float> authored = *doc->authoredGloss();
    ASSERT_TRUE(window.saveProjectAs(file));
    const QString glossFile = layerPathFor(file, gloss), offsetFile = layerPathFor(file, offset);
    EXPECT_TRUE(QFileInfo::exists(glossFile));
    EXPECT_TRUE(QFileInfo::exists(offsetFile));

    MainWindow other;
    other.setAutosaveDelay(0);
    other.showMessage = [](const QString&, const QString& text) { ADD_FAILURE() << text.toStdString(); };
    ASSERT_TRUE(other.openProject(file));
    const MaterialDocument* loaded = other.document();
    EXPECT_TRUE(samePaint(loaded->paintLayer(PaintLayerKind::Gloss), gloss));
    EXPECT_TRUE(samePaint(loaded->paintLayer(PaintLayerKind::VarianceOffset), offset));
    ASSERT_TRUE(loaded->authoredGloss());
    EXPECT_TRUE(sameBits(*loaded->authoredGloss(), authored));

    // A project naming a missing layer file loads nothing half-way.
    QFile::remove(glossFile);
    MainWindow third;
    third.setAutosaveDelay(0);
    QString message;
    third.showMessage = [&](const QString&, const QString& text) { message = text; };
    EXPECT_FALSE(third.openProject(file));
    EXPECT_TRUE(message.contains(QFileInfo(glossFile).fileName())) << message.toStdString();
    EXPECT_FALSE(third.document()->paintLayer(PaintLayerKind::VarianceOffset).painted());
}

// Loading a normal map of another size used to throw the painted layers away (undo brought the
// map back but not the paint, and the next save wrote none). Now they are resampled to the new
// size with a notice, and undo puts back exactly what was there: paint, load a map of another size,
// undo, save, reopen, compare bit for bit.
TEST(StudioPaint, PaintSurvivesAMapOfAnotherSizeAndUndoRestoresItExactly) {
    test::TempDir dir;
    MainWindow window;
    window.setAutosaveDelay(0);
    MaterialDocument* doc = window.document();
    QStringList notices;
    QObject::connect(doc, &MaterialDocument::notice, [&](const QString& text) { notices << text; });
    PaintTool* tool = window.paintTool();
    stroke(*tool, PaintLayerKind::Gloss, 0.9f, 30.0, {100.0, 100.0}, {300.0, 200.0});
    stroke(*tool, PaintLayerKind::VarianceOffset, 0.3f, 20.0, {50.0, 400.0}, {200.0, 420.0});
    const PaintLayer gloss = doc->paintLayer(PaintLayerKind::Gloss);
    const PaintLayer offset = doc->paintLayer(PaintLayerKind::VarianceOffset);
    ASSERT_TRUE(gloss.painted() && offset.painted());
    ASSERT_EQ(gloss.width, kSampleSize);

    for (const int size : {1, 1024, 300}) {
        const fs::path map = dir / ("flat-" + std::to_string(size) + ".png");
        QImage flat(size, size, QImage::Format_RGB888);
        flat.fill(QColor(128, 128, 255));
        ASSERT_TRUE(flat.save(QString::fromStdString(map.string())));
        notices.clear();
        ASSERT_TRUE(doc->loadMap(MapSlot::Normal, QString::fromStdString(map.string()))) << size;
        const PaintLayer& carried = doc->paintLayer(PaintLayerKind::Gloss);
        EXPECT_EQ(carried.width, size);
        EXPECT_TRUE(carried.painted()) << "the paint goes with the map (" << size << ")";
        EXPECT_TRUE(doc->paintLayer(PaintLayerKind::VarianceOffset).painted());
        ASSERT_EQ(notices.size(), 1);
        EXPECT_TRUE(notices[0].contains(QString("to %1×%1").arg(size))) << notices[0].toStdString();
        if (size == 1024) {
            // Twice the size: each texel copied into its 2×2 block, at the same place in UV.
            EXPECT_EQ(carried.value[carried.index(400, 300)], gloss.value[gloss.index(200, 150)]);
            EXPECT_EQ(carried.coverage[carried.index(401, 301)], gloss.coverage[gloss.index(200, 150)]);
        }
        doc->undoStack()->undo();
        EXPECT_TRUE(samePaint(doc->paintLayer(PaintLayerKind::Gloss), gloss)) << size;
        EXPECT_TRUE(samePaint(doc->paintLayer(PaintLayerKind::VarianceOffset), offset)) << size;
    }
    // Redo gives the carried layers again, and a stroke on them undoes on them.
    doc->undoStack()->redo();
    EXPECT_EQ(doc->paintLayer(PaintLayerKind::Gloss).width, 300);
    EXPECT_TRUE(doc->paintLayer(PaintLayerKind::Gloss).painted());
    doc->undoStack()->undo();

    const QString file = QString::fromStdString((dir / "carried.burnish").string());
    ASSERT_TRUE(window.saveProjectAs(file));
    MainWindow reopened;
    reopened.setAutosaveDelay(0);
    reopened.showMessage = [](const QString&, const QString& text) { ADD_FAILURE() << text.toStdString(); };
    ASSERT_TRUE(reopened.openProject(file));
    const MaterialDocument* loaded = reopened.document();
    EXPECT_TRUE(samePaint(loaded->paintLayer(PaintLayerKind::Gloss), gloss));
    EXPECT_TRUE(samePaint(loaded->paintLayer(PaintLayerKind::VarianceOffset), offset));
}

// A preset of another gloss encoding keeps the painted powers, as it keeps the base gloss's power;
// undo gives back the values as painted.
TEST(StudioPaint, APresetChangeReencodesThePaintedGlossAndUndoRestoresIt) {
    MainWindow window;
    window.setAutosaveDelay(0);
    MaterialDocument* doc = window.document();
    ASSERT_EQ(doc->settings().preset, "blackops");
    stroke(*window.paintTool(), PaintLayerKind::Gloss, 0.6f, 25.0, {200.0, 200.0}, {260.0, 240.0});
    const PaintLayer painted = doc->paintLayer(PaintLayerKind::Gloss);
    const GlossEncoding before = doc->preset().encoding;
    ASSERT_TRUE(doc->setPreset("gltf"));
    const GlossEncoding& after = doc->preset().encoding;
    const PaintLayer& reencoded = doc->paintLayer(PaintLayerKind::Gloss);
    const size_t i = painted.index(230, 220);
    ASSERT_GT(painted.coverage[i], 0.0f);
    EXPECT_NEAR(after.power(reencoded.value[i]), before.power(painted.value[i]),
                1e-3 * before.power(painted.value[i]))
        << "the same power under the new encoding";
    EXPECT_EQ(reencoded.coverage[i], painted.coverage[i]);
    doc->undoStack()->undo();
    EXPECT_TRUE(samePaint(doc->paintLayer(PaintLayerKind::Gloss), painted));
}

// Saves write layer files named by their content and remove those no longer named; removing an
// autosave copy removes its layers, so no stray *.layers folders are left behind.
TEST(StudioPaint, SavesAndAutosavesLeaveNoStrayLayerFiles) {
    test::TempDir dir;
    const QString file = QString::fromStdString((dir / "m.burnish").string());
    MainWindow window;
    window.setAutosaveDelay(0);
    MaterialDocument* doc = window.document();
    stroke(*window.paintTool(), PaintLayerKind::Gloss, 0.9f, 20.0, {100.0, 100.0}, {150.0, 100.0});
    ASSERT_TRUE(window.saveProjectAs(file));
    const QDir layers(layerFolderFor(file));
    EXPECT_EQ(layers.entryList(QDir::Files).size(), 1);
    // A stranger's file in the folder is never touched.
    QFile note(layers.absoluteFilePath("notes.txt"));
    ASSERT_TRUE(note.open(QIODevice::WriteOnly));
    note.close();
    stroke(*window.paintTool(), PaintLayerKind::Gloss, 0.2f, 20.0, {300.0, 300.0}, {350.0, 300.0});
    ASSERT_TRUE(window.saveProjectAs(file));
    const auto project = loadProject(file);
    ASSERT_TRUE(project);
    ASSERT_EQ(project->layers.size(), 1u);
    EXPECT_EQ(layers.entryList(QDir::Files),
              QStringList({QFileInfo(project->layers[0].path).fileName(), "notes.txt"}))
        << "the first save's layer file is gone, the new one and the stranger's file stay";
    // Nothing painted any more: the layer folder is emptied of Burnish's files.
    doc->editablePaintLayer(PaintLayerKind::Gloss).clear();
    doc->layerEdited(PaintLayerKind::Gloss, TexelRect::full(kSampleSize, kSampleSize));
    ASSERT_TRUE(window.saveProjectAs(file));
    EXPECT_EQ(layers.entryList(QDir::Files), QStringList({"notes.txt"}));

    // An autosave with paint, then the project saved: the copy and its layer folder are removed.
    stroke(*window.paintTool(), PaintLayerKind::Gloss, 0.7f, 20.0, {200.0, 200.0}, {250.0, 200.0});
    ASSERT_TRUE(window.autosave());
    ASSERT_TRUE(window.waitForAutosave());
    const QString copy = autosavePathFor(file);
    ASSERT_TRUE(QFileInfo::exists(copy));
    ASSERT_TRUE(QDir(layerFolderFor(copy)).exists());
    ASSERT_TRUE(window.saveProjectAs(file));
    EXPECT_FALSE(QFileInfo::exists(copy));
    EXPECT_FALSE(QDir(layerFolderFor(copy)).exists()) << "no stray autosave layer folder";
}

// Choosing a preset or method in the export dialog used to set it on the document: the Material
// panel's preset changed, History grew, the project was marked modified and painted layers were
// re-encoded. The choice is now the export's own; only the export fields (folder, format, mips) go
// into the project's export settings, one undo step.
TEST(StudioPaint, TheExportDialogsPresetAndMethodAreTheExportsOwn) {
    const auto exportWith = [](MaterialDocument& doc, const fs::path& out, const QString& preset) {
        BakeDialog dialog(&doc);
        if (!preset.isEmpty()) dialog.choosePreset(preset);
        dialog.outputEdit()->setText(QString::fromStdString(out.string()));
        QSignalSpy finished(&dialog, &BakeDialog::bakeFinished);
        dialog.startBake();
        EXPECT_TRUE(finished.count() > 0 || finished.wait(kWorkerTimeoutMs));
        EXPECT_TRUE(!finished.isEmpty() && finished.at(0).at(0).toBool())
            << dialog.resultLabel()->text().toStdString();
    };
    test::TempDir dir;
    // No paint, no gloss map: the dialog's unreal writes what a document set to unreal writes.
    {
        MaterialDocument doc, unreal;
        ASSERT_TRUE(doc.setPreset("blackops"));
        doc.setGloss(0.6);
        ASSERT_TRUE(unreal.setPreset("blackops"));
        unreal.setGloss(0.6);
        ASSERT_TRUE(unreal.setPreset("unreal"));
        exportWith(doc, dir / "dialog", "unreal");
        exportWith(unreal, dir / "document", {});
        EXPECT_EQ(doc.settings().preset, "blackops");
        const auto a = folderBytes(dir / "dialog"), b = folderBytes(dir / "document");
        ASSERT_FALSE(b.empty());
        ASSERT_EQ(a.size(), b.size());
        for (const auto& [name, bytes] : b) {
            ASSERT_TRUE(a.count(name)) << name;
            if (name != "bake.json") {
                EXPECT_TRUE(a.at(name) == bytes) << name << " differs";
                continue;
            }
            // The document set to unreal holds its gloss in unreal's encoding: its power comes back
            // from that gloss a rounding away (222.86094420380775 against ...78).
            auto dialogRecord = nlohmann::json::parse(a.at(name)),
                 documentRecord = nlohmann::json::parse(bytes);
            EXPECT_NEAR(dialogRecord["options"]["power"].get<double>() /
                            documentRecord["options"]["power"].get<double>(),
                        1.0, 1e-12);
            dialogRecord["options"].erase("power");
            documentRecord["options"].erase("power");
            // The options' hash covers that power too.
            dialogRecord["options"].erase("fnv1a64");
            documentRecord["options"].erase("fnv1a64");
            EXPECT_EQ(dialogRecord, documentRecord);
        }
    }
    // Painted: the document, its layers and its history stay as they were; the export keeps the powers.
    MaterialDocument doc;
    ASSERT_TRUE(doc.setPreset("blackops"));
    doc.setGloss(0.6);
    {
        TextureView canvas;
        PaintTool tool(&doc, &canvas);
        stroke(tool, PaintLayerKind::Gloss, 0.95f, 40.0, {60.0, 60.0}, {300.0, 200.0});
    }
    doc.undoStack()->setClean();
    const int steps = doc.undoStack()->count();
    const MaterialSettings before = doc.settings();
    const PaintLayer layer = doc.paintLayer(PaintLayerKind::Gloss);
    ASSERT_TRUE(doc.authoredGloss());
    const std::vector<float> authored = *doc.authoredGloss();
    {
        BakeDialog dialog(&doc);
        dialog.choosePreset("unreal");
        EXPECT_EQ(dialog.presetCombo()->currentData().toString(), "unreal");
        const Preset* unreal = nullptr;
        for (const auto& p : builtinPresets())
            if (p.name == "unreal") unreal = &p;
        ASSERT_NE(unreal, nullptr);
        const auto methods = compatibleMethods(*unreal);
        EXPECT_NE(std::find(methods.begin(), methods.end(), dialog.exportMethod()), methods.end());
        dialog.chooseMethod(methods.front());
        EXPECT_EQ(dialog.exportMethod(), methods.front());
        // The spec carries the painted gloss in unreal's encoding at the document's powers.
        const BakeJobSpec spec = bakeJobSpecFor(doc, "unreal", methods.front());
        ASSERT_TRUE(spec.authoredGloss);
        ASSERT_EQ(spec.authoredGloss->size(), authored.size());
        for (size_t i = 0; i < authored.size(); i += 997) {
            const double want = doc.preset().encoding.power(authored[i]);
            EXPECT_NEAR(unreal->encoding.power((*spec.authoredGloss)[i]) / want, 1.0, 1e-3) << i;
        }
        dialog.outputEdit()->setText(QString::fromStdString((dir / "painted").string()));
        QSignalSpy finished(&dialog, &BakeDialog::bakeFinished);
        dialog.startBake();
        ASSERT_TRUE(finished.count() > 0 || finished.wait(kWorkerTimeoutMs));
        ASSERT_TRUE(finished.at(0).at(0).toBool()) << dialog.resultLabel()->text().toStdString();
    }
    auto record = readFile(dir / "painted" / "bake.json");
    ASSERT_TRUE(record);
    EXPECT_EQ(nlohmann::json::parse(*record)["preset"]["name"], "unreal");
    MaterialSettings after = doc.settings();
    EXPECT_EQ(after.exportSettings.outputFolder, QString::fromStdString((dir / "painted").string()));
    after.exportSettings = before.exportSettings;
    EXPECT_TRUE(after == before) << "preset, method and gloss as they were";
    EXPECT_EQ(doc.undoStack()->count(), steps + 1) << "one step: the export settings";
    EXPECT_EQ(doc.undoStack()->text(steps), "Export settings");
    EXPECT_TRUE(samePaint(doc.paintLayer(PaintLayerKind::Gloss), layer)) << "the layer is not re-encoded";
    EXPECT_EQ(*doc.authoredGloss(), authored);
}

TEST(StudioPaint, TexturePaneShowsThePaintedGlossAndItsBake) {
    MaterialDocument doc;
    TexturePane pane(&doc);
    PaintTool tool(&doc, pane.view());
    pane.setMode(TextureMode::Gloss);
    // 8-bit view of the base gloss, before anything is painted.
    const uchar base = grey(pane.view()->image(), 400, 400);
    // The base gloss as the authored gloss stores it (float).
    EXPECT_EQ(base, uchar(std::lround(double(float(doc.settings().gloss)) * 255.0)));

    constexpr float kPainted = 0.2f;
    constexpr double kRadius = 20.0;
    stroke(tool, PaintLayerKind::Gloss, kPainted, kRadius, {100.5, 100.5}, {100.5, 100.5});
    const QImage authored = pane.view()->image();
    EXPECT_EQ(grey(authored, 100, 100), uchar(std::lround(kPainted * 255.0))) << "the painted texel";
    EXPECT_EQ(grey(authored, 400, 400), base) << "a texel far from the dab keeps the base gloss";

    // The baked view bakes the composited gloss: the same image as core's bake of it, per mip.
    QSignalSpy updated(&pane, &TexturePane::imageUpdated);
    pane.setMode(TextureMode::BakedGloss);
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    ASSERT_FALSE(pane.baking());
    const QImage expected = coreBakedGloss(doc, 0);
    EXPECT_EQ(pane.view()->image().convertToFormat(QImage::Format_Grayscale8), expected);
    constexpr int kMip = 2;
    pane.setMip(kMip);
    EXPECT_EQ(pane.view()->image().convertToFormat(QImage::Format_Grayscale8), coreBakedGloss(doc, kMip));

    // The paint makes a difference there: undo, and the bake without it differs at the dab.
    pane.setMip(0);
    doc.undoStack()->undo();
    ASSERT_FALSE(doc.authoredGloss());
    ASSERT_TRUE(pane.baking()) << "an undone stroke is baked again";
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    EXPECT_NE(grey(pane.view()->image(), 100, 100), grey(expected, 100, 100));
    EXPECT_EQ(pane.view()->image().convertToFormat(QImage::Format_Grayscale8), coreBakedGloss(doc, 0));
}

TEST(StudioPaint, ExportOfPaintedLayersWritesTheBytesOfBurnishBakeWithTheSameGloss) {
    struct Case {
        const char* preset;
        const char* format;
        bool glossMap; // paint over a gloss map rather than over the base gloss
    };
    for (const Case c : {Case{"blackops", "png16", false}, Case{"gltf", "exr-float", true}}) {
        SCOPED_TRACE(c.preset);
        test::TempDir dir;
        MaterialDocument doc;
        ASSERT_TRUE(doc.setPreset(c.preset));
        doc.setGloss(0.6);
        if (c.glossMap) {
            QImage gloss(kSampleSize, kSampleSize, QImage::Format_Grayscale8);
            gloss.fill(90);
            const QString path = QString::fromStdString((dir / "under.png").string());
            ASSERT_TRUE(gloss.save(path));
            ASSERT_TRUE(doc.loadMap(MapSlot::Gloss, path));
        }
        {
            TextureView canvas;
            PaintTool tool(&doc, &canvas);
            stroke(tool, PaintLayerKind::Gloss, 0.95f, 40.0, {60.0, 60.0}, {300.0, 200.0});
            stroke(tool, PaintLayerKind::VarianceOffset, 0.05f, 30.0, {400.0, 100.0}, {420.0, 450.0});
        }
        ASSERT_TRUE(doc.authoredGloss());

        BakeDialog dialog(&doc);
        dialog.formatCombo()->setCurrentIndex(dialog.formatCombo()->findData(QString(c.format)));
        dialog.outputEdit()->setText(QString::fromStdString((dir / "studio").string()));
        QSignalSpy finished(&dialog, &BakeDialog::bakeFinished);
        dialog.startBake();
        ASSERT_TRUE(finished.count() > 0 || finished.wait(kWorkerTimeoutMs));
        ASSERT_TRUE(finished.at(0).at(0).toBool()) << finished.at(0).at(1).toString().toStdString();

        // The same values through a file and the command line.
        const fs::path exr = dir / "painted.exr";
        ASSERT_TRUE(writeFloatExr(exr, *doc.authoredGloss(), kSampleSize, kSampleSize));
        std::string args = std::string("bake ") + kSampleInputPrefix.data() + kSampleName + " --preset " +
                           c.preset + " --method " + std::string(methodName(doc.settings().method)) +
                           " --gloss " + test::shellQuote(exr.string()) + " --format " + c.format +
                           " --out " + test::shellQuote((dir / "cli").string());
        if (doc.preset().findParameter("metallic")) args += " --metallic 1";
        const LinearRgb f0 = doc.settings().specular; // the picked colour, as the studio passes it
        char specular[128];
        std::snprintf(specular, sizeof specular, "%.17g,%.17g,%.17g", f0.r, f0.g, f0.b);
        args += std::string(" --specular ") + specular + " --material-class metal";
        const auto cli = test::runBurnish(args);
        ASSERT_EQ(cli.exitCode, 0) << cli.err;

        const auto studio = folderBytes(dir / "studio");
        const auto reference = folderBytes(dir / "cli");
        ASSERT_GT(reference.size(), 1u) << "textures beside bake.json";
        ASSERT_EQ(studio.size(), reference.size());
        for (const auto& [name, bytes] : reference) {
            ASSERT_TRUE(studio.count(name)) << name;
            if (name != "bake.json") {
                EXPECT_TRUE(studio.at(name) == bytes) << name << " differs";
            }
        }
        // bake.json: the same but for where the gloss came from.
        auto studioRecord = nlohmann::json::parse(studio.at("bake.json"));
        auto cliRecord = nlohmann::json::parse(reference.at("bake.json"));
        const auto& source = studioRecord["inputs"]["gloss"];
        EXPECT_EQ(source["source"], std::string(kPaintedGlossSource));
        EXPECT_EQ(source["paintedOver"], c.glossMap ? nlohmann::json((dir / "under.png").string()) : nullptr);
        EXPECT_EQ(cliRecord["inputs"]["glossMap"], exr.string());
        studioRecord["inputs"].erase("gloss");
        cliRecord["inputs"].erase("glossMap");
        // The hashes of the inputs read and of the command line differ with it: the studio reads no
        // gloss file (the painted one is hashed in inputs.gloss) and the CLI names the EXR.
        EXPECT_TRUE(studioRecord["inputs"]["fnv1a64"]["glossMap"].is_null());
        EXPECT_TRUE(cliRecord["inputs"]["fnv1a64"]["glossMap"].is_string());
        for (auto* record : {&studioRecord, &cliRecord}) {
            (*record)["inputs"]["fnv1a64"].erase("glossMap");
            (*record)["options"].erase("fnv1a64");
        }
        EXPECT_EQ(studioRecord, cliRecord);
    }
}

namespace burnish::studio {
namespace {

QString kNormalMapPath() {
    return QString(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png";
}

// The authored gloss as a full composite of the document's layers now (what recomposite() writes
// over the whole map).
std::vector<float> fullComposite(const MaterialDocument& doc) {
    const NormalMap& map = *doc.maps().normal;
    std::vector<float> out(map.texelCount());
    EXPECT_TRUE(compositeAuthoredGloss(nullptr, doc.settings().gloss, &doc.paintLayer(PaintLayerKind::Gloss),
                                       &doc.paintLayer(PaintLayerKind::VarianceOffset), doc.preset().encoding,
                                       map.width, map.height, TexelRect::full(map.width, map.height), out));
    return out;
}

} // namespace

// A stroke on a big map copied the whole authored gloss (and more) on every dab. Snapshots are now
// handed out from reused buffers brought up to date rectangle by rectangle: each must still equal the
// whole composite at its moment, and one held must never change.
TEST(StudioPaint, AuthoredSnapshotsAreExactAndNeverChangeUnderTheirHolder) {
    MaterialDocument doc;
    TextureView canvas;
    PaintTool tool(&doc, &canvas);
    std::vector<std::shared_ptr<const std::vector<float>>> held;
    std::vector<std::vector<float>> expected;
    for (int i = 0; i < 8; ++i) {
        stroke(tool, i % 3 == 2 ? PaintLayerKind::VarianceOffset : PaintLayerKind::Gloss, 0.1f * float(i + 1),
               12.0 + i, {30.0 + 50.0 * i, 40.0}, {60.0 + 40.0 * i, 300.0 - 20.0 * i});
        const auto snapshot = doc.authoredGloss();
        ASSERT_TRUE(snapshot);
        EXPECT_EQ(doc.authoredGloss(), snapshot) << "no edit, the same snapshot";
        const std::vector<float> now = fullComposite(doc);
        EXPECT_TRUE(sameBits(*snapshot, now)) << "stroke " << i;
        ASSERT_NE(doc.authoredValues(), nullptr);
        EXPECT_TRUE(sameBits(*doc.authoredValues(), now)) << "stroke " << i;
        // Hold every other one (as the renderer's cache would); the rest go back for reuse.
        if (i % 2 == 0) {
            held.push_back(snapshot);
            expected.push_back(now);
        }
    }
    for (size_t k = 0; k < held.size(); ++k)
        EXPECT_TRUE(sameBits(*held[k], expected[k])) << "held snapshot " << k << " changed";
    // Undo and redo go through the same path.
    doc.undoStack()->undo();
    EXPECT_TRUE(sameBits(*doc.authoredGloss(), fullComposite(doc)));
    doc.undoStack()->redo();
    EXPECT_TRUE(sameBits(*doc.authoredGloss(), fullComposite(doc)));
}

// Paint on: the arrays of the first stroke are made on a worker. The stroke must come out bit for bit
// as without them.
TEST(StudioPaint, PreparedArraysGiveTheSameStrokeAsNone) {
    MaterialDocument prepared, plain;
    ASSERT_TRUE(prepared.loadMap(MapSlot::Normal, kNormalMapPath()));
    ASSERT_TRUE(plain.loadMap(MapSlot::Normal, kNormalMapPath()));
    prepared.prepareForPainting(PaintLayerKind::Gloss);
    ASSERT_TRUE(QTest::qWaitFor([&] { return prepared.paintLayer(PaintLayerKind::Gloss).allocated(); },
                                kWorkerTimeoutMs));
    QTest::qWait(50); // the landing call also brought the prepared authored values
    EXPECT_FALSE(prepared.paintLayer(PaintLayerKind::Gloss).painted());
    EXPECT_EQ(prepared.authoredGloss(), nullptr) << "prepared, nothing painted: the base power applies";
    for (MaterialDocument* doc : {&prepared, &plain}) {
        TextureView canvas;
        PaintTool tool(doc, &canvas);
        stroke(tool, PaintLayerKind::Gloss, 0.9f, 20.0, {100.0, 100.0}, {300.0, 140.0});
        stroke(tool, PaintLayerKind::Gloss, 0.2f, 10.0, {120.0, 300.0}, {140.0, 310.0});
    }
    EXPECT_TRUE(
        samePaint(prepared.paintLayer(PaintLayerKind::Gloss), plain.paintLayer(PaintLayerKind::Gloss)));
    ASSERT_TRUE(prepared.authoredGloss() && plain.authoredGloss());
    EXPECT_TRUE(sameBits(*prepared.authoredGloss(), *plain.authoredGloss()));
    EXPECT_TRUE(sameBits(*prepared.authoredGloss(), fullComposite(prepared)));
}

// The overlay of a big map is drawn from a minified copy kept up to date rectangle by rectangle: the
// view after an edit must look exactly as a view given the edited overlay whole.
TEST(StudioPaint, OverlayEditsInPlaceDrawAsTheWholeOverlay) {
    QImage overlay(1000, 700, QImage::Format_RGB32);
    for (int y = 0; y < overlay.height(); ++y)
        for (int x = 0; x < overlay.width(); ++x)
            overlay.setPixel(x, y, qRgb((x * 7) % 256, (y * 5) % 256, (x + y) % 256));
    TextureView edited, whole;
    for (TextureView* view : {&edited, &whole}) {
        view->resize(300, 240);
        view->setImage(overlay);
        view->fit();
    }
    edited.setOverlay(overlay);
    (void)edited.grab(); // draws once: the minified copy is made
    QImage& image = edited.overlayForEdit();
    const QRect rect(333, 101, 57, 211);
    for (int y = rect.top(); y <= rect.bottom(); ++y)
        for (int x = rect.left(); x <= rect.right(); ++x)
            image.setPixel(x, y, qRgb(255 - (x % 256), 200, y % 256));
    edited.overlayChanged(rect);
    whole.setOverlay(edited.overlay().copy());
    EXPECT_EQ(edited.grab().toImage(), whole.grab().toImage());
}

// Autosave keeps its own copy of a painted layer and brings only the edited texels up to date: what
// it writes must still be the document's layer, after every stroke, for a map above the size whose copy
// is made on a worker too.
TEST(StudioPaint, AutosaveCopiesOfPaintedLayersFollowEveryStroke) {
    test::TempDir dir;
    // 4096×1100: over 2048² texels, so the writer's copy is made off the GUI thread.
    const fs::path big = dir / "big.png";
    {
        QImage flat(4096, 1100, QImage::Format_RGB888);
        flat.fill(QColor(128, 128, 255));
        ASSERT_TRUE(flat.save(QString::fromStdString(big.string())));
    }
    for (const QString& map : {kNormalMapPath(), QString::fromStdString(big.string())}) {
        SCOPED_TRACE(map.toStdString());
        MainWindow window;
        window.setAutosaveDelay(0);
        window.ask = [](const QString&, const QString&, QMessageBox::StandardButtons) {
            return QMessageBox::Discard;
        };
        MaterialDocument& doc = *window.document();
        ASSERT_TRUE(doc.loadMap(MapSlot::Normal, map));
        const QString copy = window.autosaveCopy();
        // Autosaves and reads back the copy's painted layer: the document's, texel for texel?
        auto autosavedAsTheDocument = [&] {
            // The first autosave of a big layer waits for its copy's memory: try until it starts.
            EXPECT_TRUE(QTest::qWaitFor([&] { return window.autosave(); }, kWorkerTimeoutMs));
            EXPECT_TRUE(window.waitForAutosave());
            const auto project = loadProject(copy);
            if (!project || project->layers.size() != 1) return false;
            const PaintLayer& layer = doc.paintLayer(PaintLayerKind::Gloss);
            const auto read = readPaintLayerExr(project->layers[0].path.toStdString(), PaintLayerKind::Gloss,
                                                layer.width, layer.height);
            return read && samePaint(*read, layer);
        };
        for (int i = 0; i < 3; ++i) {
            stroke(*window.paintTool(), PaintLayerKind::Gloss, 0.3f * float(i + 1), 15.0,
                   {40.0 + 90.0 * i, 30.0 + 20.0 * i}, {200.0 + 60.0 * i, 90.0});
            EXPECT_TRUE(autosavedAsTheDocument()) << "after stroke " << i;
        }
        // Undo is an edit like any other.
        doc.undoStack()->undo();
        EXPECT_TRUE(autosavedAsTheDocument()) << "after undo";
        (void)removeProject(copy);
    }
}

// Paint on an 8192² map held the GUI for half a minute building the live bake; it is now built on a
// worker while strokes go on. When it lands it must have caught up with them: the same baked gloss and
// the same overlay as a tool that built it at once and painted the same strokes.
TEST(StudioPaint, ABackgroundLiveBakeCatchesUpWithStrokesPaintedMeanwhile) {
    MaterialDocument background, atOnce;
    for (MaterialDocument* doc : {&background, &atOnce})
        ASSERT_TRUE(doc->loadMap(MapSlot::Normal, kNormalMapPath()));
    TextureView backgroundView, atOnceView;
    PaintTool backgroundTool(&background, &backgroundView), atOnceTool(&atOnce, &atOnceView);
    backgroundTool.setBackgroundBakes(true);
    for (PaintTool* tool : {&backgroundTool, &atOnceTool}) {
        tool->setPaintMode(true);
        // Painted at once: for the background tool, before its live bake (and maybe its overlay) lands.
        stroke(*tool, PaintLayerKind::Gloss, 0.95f, 24.0, {80.0, 90.0}, {350.0, 160.0});
        stroke(*tool, PaintLayerKind::VarianceOffset, 0.1f, 12.0, {300.0, 300.0}, {320.0, 420.0});
    }
    EXPECT_TRUE(backgroundTool.liveBuilding()) << "a 512² live bake takes longer than two strokes";
    ASSERT_TRUE(QTest::qWaitFor([&] { return !backgroundTool.liveBuilding(); }, kWorkerTimeoutMs));
    QTest::qWait(50); // the overlay's own worker
    ASSERT_NE(backgroundTool.liveBake(), nullptr);
    ASSERT_NE(atOnceTool.liveBake(), nullptr);
    const auto& a = backgroundTool.liveBake()->gloss().mips;
    const auto& b = atOnceTool.liveBake()->gloss().mips;
    ASSERT_EQ(a.size(), b.size());
    for (size_t k = 0; k < a.size(); ++k)
        EXPECT_TRUE(a[k].texels == b[k].texels) << "mip " << k;
    EXPECT_EQ(backgroundTool.overShineMap().flaggedCount, atOnceTool.overShineMap().flaggedCount);
    EXPECT_EQ(backgroundView.overlay(), atOnceView.overlay());
}

// The Paint button looked the same on and off (issue 44, point 7): it now says so and is highlighted.
TEST(StudioPaint, ThePaintButtonShowsItsState) {
    MaterialDocument doc;
    TextureView canvas;
    PaintTool tool(&doc, &canvas);
    auto* button = tool.findChild<QPushButton*>("paintButton");
    ASSERT_NE(button, nullptr);
    EXPECT_EQ(button->text(), "Paint");
    button->resize(200, 30);
    // The button's face beside its text: the highlight colour while on, far from it while off.
    const QColor highlight = button->palette().color(QPalette::Highlight);
    auto faceDistance = [&] {
        const QColor face = button->grab().toImage().pixelColor(12, 15);
        return std::abs(face.red() - highlight.red()) + std::abs(face.green() - highlight.green()) +
               std::abs(face.blue() - highlight.blue());
    };
    const int off = faceDistance(); // a dark grey face: about 180 from the highlight
    button->click();
    EXPECT_TRUE(tool.paintMode());
    EXPECT_EQ(button->text(), "Painting");
    const int on = faceDistance(); // the highlight, a little lighter: about 50
    EXPECT_LT(2 * on, off) << "on does not show the highlight (distance " << on << " against " << off
                           << " off)";
    button->click();
    EXPECT_FALSE(tool.paintMode());
    EXPECT_EQ(button->text(), "Paint");
}

// Painting by accident (issue 48, point 6): with Paint on and its panel hidden behind a tab, a drag on
// the 3D view painted; an eyedropper armed with Paint off fired after Paint came on; a pick was no
// undo step.
TEST(StudioPaint, TheViewsPaintOnlyWhileThePaintPanelIsInViewAndAPickIsAnUndoStep) {
    MainWindow window;
    window.setAutosaveDelay(0);
    window.resize(1152, 648); // compact: the Paint panel is a tab behind the Material panel
    window.show();
    window.resetLayout(); // whatever layout a test before saved
    QApplication::processEvents();
    ASSERT_TRUE(window.tabifiedDockWidgets(window.findChild<QDockWidget*>("materialDock"))
                    .contains(window.findChild<QDockWidget*>("paintDock")));
    PaintTool* tool = window.paintTool();
    auto* dock = window.findChild<QDockWidget*>("paintDock");
    auto* materialDock = window.findChild<QDockWidget*>("materialDock");
    ASSERT_NE(dock, nullptr);
    ASSERT_NE(materialDock, nullptr);
    Viewport* viewport = window.findChild<ViewportPanel*>()->viewport();
    TextureView* view = window.texturePane()->view();

    // The eyedropper cannot be armed with Paint off.
    auto* eyedropper = tool->findChild<QPushButton*>("paintEyedropper");
    ASSERT_NE(eyedropper, nullptr);
    EXPECT_FALSE(eyedropper->isEnabled());
    tool->setEyedropper(true);
    EXPECT_FALSE(tool->eyedropper());

    // Turning Paint on brings its panel into view; both views paint.
    tool->setPaintMode(true);
    QApplication::processEvents();
    EXPECT_FALSE(dock->visibleRegion().isEmpty());
    EXPECT_TRUE(tool->armed());
    EXPECT_TRUE(viewport->paintMode());
    EXPECT_TRUE(view->paintMode());
    // The Material tab raised over it: the views orbit and pan again, Paint stays on for later.
    materialDock->raise();
    QApplication::processEvents();
    EXPECT_TRUE(dock->visibleRegion().isEmpty()); // its tab is behind Material's
    EXPECT_TRUE(tool->paintMode());
    EXPECT_FALSE(tool->armed());
    EXPECT_FALSE(viewport->paintMode());
    EXPECT_FALSE(view->paintMode());
    dock->raise();
    QApplication::processEvents();
    EXPECT_TRUE(viewport->paintMode());

    // A pick is one undo step, and Ctrl+Z gives the value back.
    MaterialDocument* doc = window.document();
    Brush b = tool->brush();
    b.value = 0.25f;
    tool->setBrush(b);
    const int steps = doc->undoStack()->count();
    tool->setEyedropper(true);
    EXPECT_TRUE(tool->eyedropper());
    tool->pressAt(QPointF(10.0, 10.0)); // the sample's base gloss, nothing painted
    EXPECT_FALSE(tool->eyedropper());
    const float picked = tool->brush().value;
    EXPECT_NEAR(picked, float(doc->settings().gloss), kGlossTol);
    ASSERT_EQ(doc->undoStack()->count(), steps + 1);
    EXPECT_TRUE(doc->undoStack()->undoText().startsWith("Pick gloss"))
        << doc->undoStack()->undoText().toStdString();
    doc->undoStack()->undo();
    EXPECT_FLOAT_EQ(tool->brush().value, 0.25f);
    doc->undoStack()->redo();
    EXPECT_FLOAT_EQ(tool->brush().value, picked);
    // Paint off disarms an eyedropper left armed.
    tool->setEyedropper(true);
    tool->setPaintMode(false);
    EXPECT_FALSE(tool->eyedropper());
    tool->setPaintMode(true);
    EXPECT_FALSE(tool->eyedropper());
}

// In Paint mode the texture view showed the painted layer under the words "normal map 512×512"
// (issue 44, point 7): the info line now says what is drawn, in the preset's own term.
TEST(StudioPaint, TheTextureViewSaysWhatPaintModeShows) {
    MainWindow window;
    window.setAutosaveDelay(0);
    TexturePane& pane = *window.texturePane();
    EXPECT_EQ(pane.infoText(), "normal map 512×512");
    window.paintTool()->setPaintMode(true);
    EXPECT_TRUE(pane.infoText().startsWith("Authored gloss shown (Paint on; orange: over-shine)"))
        << pane.infoText().toStdString();
    EXPECT_TRUE(pane.infoText().contains("normal map 512×512"));
    ASSERT_TRUE(window.document()->setPreset("gltf"));
    EXPECT_TRUE(pane.infoText().startsWith("Authored roughness shown")) << pane.infoText().toStdString();
    window.paintTool()->setPaintMode(false);
    EXPECT_EQ(pane.infoText(), "normal map 512×512");
}

} // namespace burnish::studio
