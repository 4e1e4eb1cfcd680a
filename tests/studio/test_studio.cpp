// The studio shell under the offscreen platform: panels edit the document and undo restores it,
// projects round-trip (environment included) and refuse bad files without touching the document,
// autosave and recovery, the Bake & Export dialog writes the bytes `burnish bake` writes, the window
// draws something, and burnish-studio --help/--version work without a display.
#include "bake_dialog.h"
#include "charts/error_cost_chart.h"
#include "gltf_import.h"
#include "main_window.h"
#include "material_panel.h"
#include "paint_tool.h"
#include "project.h"
#include "scene_from_document.h"
#include "studio_app.h"
#include "texture_pane.h"
#include "viewport.h"
#include "viewport_panel.h"

#include <burnish/core/util/files.h>

#include "cli_run.h"
#include "temp_dir.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <QAction>
#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QDateTime>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QDragEnterEvent>
#include <QDropEvent>
#include <QFile>
#include <QImage>
#include <QLabel>
#include <QLineEdit>
#include <QMenu>
#include <QMenuBar>
#include <QMimeData>
#include <QSet>
#include <QSettings>
#include <QSignalSpy>
#include <QSlider>
#include <QSpinBox>
#include <QStandardPaths>
#include <QStatusBar>
#include <QTest>
#include <QUrl>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <tuple>

namespace burnish::studio {
namespace {

namespace fs = std::filesystem;

const QString kNormalMap = QString(BURNISH_TEST_DATA_DIR) + "/trak-rust1_nm.png";
// Waiting for a worker thread (a 512² bake takes well under a second; generous for loaded CI).
constexpr int kWorkerTimeoutMs = 60000;
// Doubles written to JSON by nlohmann round-trip exactly; settings compare with ==.

QString q(const fs::path& p) {
    return QString::fromStdString(p.string());
}

/// A main window whose messages and questions are recorded instead of shown in modal boxes.
struct TestWindow {
    MainWindow window;
    QStringList messages;
    QStringList results;   // showResult's summaries
    QStringList questions; // every question asked, in order
    QMessageBox::StandardButton answer = QMessageBox::Discard;
    TestWindow() {
        window.showMessage = [this](const QString&, const QString& text) { messages << text; };
        window.showResult = [this](const QString&, const QString& text) { results << text; };
        window.ask = [this](const QString&, const QString& text, QMessageBox::StandardButtons) {
            questions << text;
            return answer;
        };
        window.setAutosaveDelay(0);
    }
};

/// A grey 8-bit PNG gloss map of the given size.
QString writeGlossMap(const fs::path& path, int size, int grey) {
    QImage image(size, size, QImage::Format_Grayscale8);
    image.fill(grey);
    EXPECT_TRUE(image.save(q(path)));
    return q(path);
}

/// A small equirectangular float EXR (a sky brighter at the top) to light the viewport with.
QString writeEnvironment(const fs::path& path) {
    constexpr int kWidth = 16, kHeight = 8; // 2:1, as an equirectangular map is
    std::vector<float> rgb;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth * 3; ++x)
            rgb.push_back(float(kHeight - y) / kHeight);
    const auto out = OIIO::ImageOutput::create(path.string());
    EXPECT_TRUE(out && out->open(path.string(), OIIO::ImageSpec(kWidth, kHeight, 3, OIIO::TypeDesc::FLOAT)) &&
                out->write_image(OIIO::TypeDesc::FLOAT, rgb.data()) && out->close());
    return q(path);
}

TEST(MaterialPanel, GlossSliderEditsTheDocumentAndUndoRestores) {
    MaterialDocument doc;
    MaterialPanel panel(&doc);
    const double before = doc.settings().gloss;
    constexpr int kSliderValue = 250; // gloss 0.25
    panel.glossSlider()->setValue(kSliderValue);
    EXPECT_EQ(doc.settings().gloss, double(kSliderValue) / MaterialPanel::kGlossSteps);
    EXPECT_EQ(panel.glossSpin()->value(), doc.settings().gloss) << "the spin box follows the document";
    doc.undoStack()->undo();
    EXPECT_EQ(doc.settings().gloss, before);
    EXPECT_EQ(panel.glossSlider()->value(), int(std::lround(before * MaterialPanel::kGlossSteps)));
}

// Types `text` into a spin box as a user does (select all, type, Enter).
void typeInto(QAbstractSpinBox* box, const QString& text) {
    box->selectAll();
    QTest::keyClicks(box, text);
}

// Typing into a numeric field commits the whole number on Enter, as one undo step named by the
// final value: each keystroke used to be committed and the box reformatted before the rest was
// typed ("0.45" gave 0.000). The locale's decimal point is what the box takes.
TEST(MaterialPanel, TypedGlossCommitsWholeOnEnterAsOneUndoStep) {
    MaterialDocument doc;
    MaterialPanel panel(&doc);
    QDoubleSpinBox* spin = panel.glossSpin();
    const int steps = doc.undoStack()->count();
    typeInto(spin, "0.45");
    EXPECT_EQ(doc.undoStack()->count(), steps) << "nothing is committed while typing";
    QTest::keyClick(spin, Qt::Key_Return);
    EXPECT_DOUBLE_EQ(doc.settings().gloss, 0.45);
    ASSERT_EQ(doc.undoStack()->count(), steps + 1);
    EXPECT_EQ(doc.undoStack()->text(steps).toStdString(), "Gloss 0.450");
    doc.undoStack()->undo();
    EXPECT_NE(doc.settings().gloss, 0.45);
    // Four places are kept (issue 44: 0.4567 became 0.456).
    typeInto(spin, "0.4567");
    QTest::keyClick(spin, Qt::Key_Return);
    EXPECT_DOUBLE_EQ(doc.settings().gloss, 0.4567);
    EXPECT_EQ(doc.undoStack()->text(doc.undoStack()->index() - 1).toStdString(), "Gloss 0.4567");
    doc.undoStack()->undo();

    const QLocale before;
    QLocale::setDefault(QLocale(QLocale::German, QLocale::Germany));
    {
        MaterialPanel german(&doc);
        typeInto(german.glossSpin(), "0,62");
        QTest::keyClick(german.glossSpin(), Qt::Key_Return);
        EXPECT_DOUBLE_EQ(doc.settings().gloss, 0.62);
    }
    QLocale::setDefault(before);
}

// A slider drag is one undo step named by the value where it ended (it was named by the first
// value of the drag).
TEST(MaterialPanel, ASliderDragIsOneStepNamedByItsLastValue) {
    MaterialDocument doc;
    MaterialPanel panel(&doc);
    QSlider* slider = panel.glossSlider();
    const int steps = doc.undoStack()->count();
    slider->setSliderDown(true);
    for (int v : {387, 500, 650, 810})
        slider->setValue(v);
    slider->setSliderDown(false); // emits sliderReleased: the drag's step is closed
    ASSERT_EQ(doc.undoStack()->count(), steps + 1);
    EXPECT_EQ(doc.undoStack()->text(steps).toStdString(), "Gloss 0.810");
    EXPECT_DOUBLE_EQ(doc.settings().gloss, 0.81);
    doc.undoStack()->undo();
    EXPECT_NE(doc.settings().gloss, 0.81);
}

// Every other numeric field of the window takes what is typed: the environment's intensity and
// sample count, and the paint brush's radius, hardness, opacity and value.
TEST(MainWindow, EveryNumericFieldTakesWhatIsTyped) {
    TestWindow w;
    auto* intensity = w.window.findChild<QDoubleSpinBox*>("environmentIntensity");
    ASSERT_NE(intensity, nullptr);
    typeInto(intensity, "2.5");
    QTest::keyClick(intensity, Qt::Key_Return);
    EXPECT_DOUBLE_EQ(w.window.document()->settings().environment.intensity, 2.5);
    auto* fis = w.window.findChild<QCheckBox*>("environmentFis");
    ASSERT_NE(fis, nullptr);
    fis->setChecked(true); // the sample count is offered with filtered importance sampling
    auto* samples = w.window.findChild<QSpinBox*>("environmentSamples");
    ASSERT_NE(samples, nullptr);
    ASSERT_TRUE(samples->isEnabled());
    typeInto(samples, "48");
    QTest::keyClick(samples, Qt::Key_Return);
    EXPECT_EQ(w.window.document()->settings().environment.fisSamples, 48);
    for (const auto& [name, text, value] :
         std::vector<std::tuple<const char*, const char*, double>>{{"paintRadius", "37.5", 37.5},
                                                                   {"paintHardness", "0.35", 0.35},
                                                                   {"paintOpacity", "0.6", 0.6},
                                                                   {"paintValue", "0.2", 0.2}}) {
        auto* box = w.window.findChild<QDoubleSpinBox*>(name);
        ASSERT_NE(box, nullptr) << name;
        typeInto(box, text);
        QTest::keyClick(box, Qt::Key_Return);
        EXPECT_DOUBLE_EQ(box->value(), value) << name;
    }
    EXPECT_FLOAT_EQ(w.window.paintTool()->brush().value, 0.2f);
    EXPECT_DOUBLE_EQ(w.window.paintTool()->brush().radius, 37.5);
}

TEST(MaterialPanel, SpecularComboTakesACalibratedMaterialAndUndoRestores) {
    MaterialDocument doc;
    MaterialPanel panel(&doc);
    const MaterialSettings before = doc.settings();
    const int gold = panel.specularCombo()->findData(QString("gold"));
    ASSERT_GE(gold, 0) << "core's table has gold";
    panel.specularCombo()->setCurrentIndex(gold);
    emit panel.specularCombo()->activated(gold);
    const Material* m = builtinMaterialTable().find("gold");
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(doc.settings().specular, m->f0());
    EXPECT_EQ(doc.settings().specularName, "gold");
    doc.undoStack()->undo();
    EXPECT_EQ(doc.settings(), before);
}

TEST(MaterialPanel, PresetComboFiltersMethodsAndKeepsThePower) {
    MaterialDocument doc;
    MaterialPanel panel(&doc);
    const double power = doc.power();
    const int lean = panel.presetCombo()->findData(QString("lean"));
    ASSERT_GE(lean, 0);
    emit panel.presetCombo()->activated(lean);
    EXPECT_EQ(doc.settings().preset, "lean");
    // The gloss is re-encoded for the new preset: the power moves only by the encoding's rounding.
    constexpr double kPowerRelativeTolerance = 1e-9;
    EXPECT_NEAR(doc.power(), power, power * kPowerRelativeTolerance);
    ASSERT_EQ(panel.methodCombo()->count(), int(doc.availableMethods().size()));
    for (int i = 0; i < panel.methodCombo()->count(); ++i)
        EXPECT_TRUE(checkPresetMethod(doc.preset(), Method(panel.methodCombo()->itemData(i).toInt())));
}

// The mixture's lobe count K: a row of the Material panel while the method is the mixture, an undo
// step, clamped to 1..4, drawn by the viewport's material and exported as that many lobe files.
TEST(MaterialPanel, LobesRowSetsTheMixturesLobeCount) {
    MaterialDocument doc;
    MaterialPanel panel(&doc);
    panel.show();
    ASSERT_TRUE(doc.setPreset("mixture"));
    ASSERT_EQ(doc.settings().method, Method::Mixture);
    EXPECT_TRUE(panel.lobesSpin()->isVisible());
    EXPECT_EQ(panel.lobesSpin()->value(), kDefaultMixtureLobes);
    const int steps = doc.undoStack()->count();
    panel.lobesSpin()->setValue(4);
    EXPECT_EQ(doc.settings().mixtureLobes, 4);
    EXPECT_EQ(doc.undoStack()->count(), steps + 1);
    doc.setMixtureLobes(9);
    EXPECT_EQ(doc.settings().mixtureLobes, kMaxMixtureLobes) << "clamped; the same count adds no step";
    EXPECT_EQ(doc.undoStack()->count(), steps + 1);
    doc.setMixtureLobes(0);
    EXPECT_EQ(doc.settings().mixtureLobes, 1);
    EXPECT_EQ(panel.lobesSpin()->value(), 1);
    doc.undoStack()->undo();
    EXPECT_EQ(doc.settings().mixtureLobes, 4);
    EXPECT_EQ(panel.lobesSpin()->value(), 4);

    SceneFromDocument scene;
    const auto material = scene.material(doc);
    ASSERT_TRUE(material) << material.error();
    EXPECT_EQ(material->methodParams.mixtureLobes, 4);
    const BakeJobSpec spec = bakeJobSpecFor(doc);
    ASSERT_TRUE(spec.lobes);
    EXPECT_EQ(*spec.lobes, 4);

    ASSERT_TRUE(doc.setPreset("lean"));
    EXPECT_FALSE(panel.lobesSpin()->isVisible()) << "only the mixture has lobes to count";
    EXPECT_FALSE(bakeJobSpecFor(doc).lobes);
    MaterialSettings bad = doc.settings();
    bad.mixtureLobes = 5;
    EXPECT_FALSE(MaterialDocument::validate(bad));
}

TEST(MaterialDocument, ASliderDragIsOneUndoStep) {
    MaterialDocument doc;
    doc.setGloss(0.1, true);
    doc.setGloss(0.2, true);
    doc.setGloss(0.3, true);
    EXPECT_EQ(doc.undoStack()->count(), 1);
    doc.endMerge();
    doc.setGloss(0.4, true);
    EXPECT_EQ(doc.undoStack()->count(), 2) << "a new drag starts a new step";
    doc.undoStack()->undo();
    EXPECT_EQ(doc.settings().gloss, 0.3);
}

TEST(MaterialDocument, AMapThatFailsToLoadChangesNothing) {
    test::TempDir dir;
    MaterialDocument doc;
    const MaterialSettings before = doc.settings();
    const Status missing = doc.loadMap(MapSlot::Normal, q(dir / "missing.png"));
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().find("missing.png"), std::string::npos) << missing.error();
    // A gloss map of another size than the normal map (the sample is 512²).
    const Status wrongSize = doc.loadMap(MapSlot::Gloss, writeGlossMap(dir / "g.png", 16, 128));
    ASSERT_FALSE(wrongSize);
    EXPECT_EQ(doc.settings(), before);
    EXPECT_EQ(doc.undoStack()->count(), 0);
}

TEST(Project, SaveLoadRoundTripsEveryField) {
    test::TempDir dir;
    fs::create_directories(dir / "project");
    TestWindow a;
    MaterialDocument* doc = a.window.document();
    ASSERT_TRUE(doc->setPreset("gltf"));
    ASSERT_TRUE(doc->loadMap(MapSlot::Normal, kNormalMap));
    ASSERT_TRUE(doc->loadMap(MapSlot::Gloss, writeGlossMap(dir / "gloss.png", 512, 100)));
    ASSERT_TRUE(doc->loadMap(MapSlot::Detail, kNormalMap));
    doc->setCustomSpecular({0.05, 0.04, 0.03});
    doc->setMaterialClass(MaterialClass::Dielectric);
    doc->setAlbedo({0.5, 0.25, 0.125});
    doc->setGloss(0.4375);
    ASSERT_TRUE(doc->setMethod(Method::Vmf) || doc->setMethod(Method::VarianceToGloss));
    doc->setMixtureLobes(2); // kept with another method, and the default is 3: the round trip must carry it
    doc->setExportSettings({"png16", "", 4, q(dir / "out"), true});
    EnvironmentSettings environment;
    environment.choice = EnvironmentChoice::File;
    environment.path = writeEnvironment(dir / "sky.exr");
    environment.rotationDegrees = -37.25;
    environment.intensity = 2.125;
    environment.lobe = LobeModel::Phong;
    environment.fis = true;
    environment.fisSamples = 96;
    environment.background = false; // the default is true: the round trip must carry it
    doc->setEnvironment(environment);
    ASSERT_EQ(doc->settings().environment, environment) << "every value inside its range";
    const MaterialSettings saved = doc->settings();
    ASSERT_NE(saved.environment, EnvironmentSettings{}) << "the round trip would not see a lost environment";

    const QString file = q(dir / "project" / "m.burnish");
    ASSERT_TRUE(a.window.saveProjectAs(file)) << a.messages.join("\n").toStdString();
    EXPECT_FALSE(a.window.isModified());
    const auto text = readFile(file.toStdString());
    ASSERT_TRUE(text);
    const auto json = nlohmann::json::parse(*text);
    EXPECT_EQ(json["format"], "burnish-project");
    EXPECT_EQ(json["version"], 1);
    EXPECT_EQ(json["maps"]["gloss"], "../gloss.png") << "paths relative to the project file";
    EXPECT_FALSE(json.contains("layers")) << "layers are written only when painted layers exist";
    EXPECT_EQ(json["environment"]["source"], "file");
    EXPECT_EQ(json["environment"]["file"], "../sky.exr") << "relative to the project file";
    EXPECT_EQ(json["environment"]["lobe"], "phong");
    EXPECT_EQ(json["environment"]["background"], false);
    EXPECT_EQ(json["lobes"], 2);

    TestWindow b;
    ASSERT_TRUE(b.window.openProject(file)) << b.messages.join("\n").toStdString();
    EXPECT_EQ(b.window.document()->settings(), saved);
    EXPECT_EQ(b.window.document()->maps().gloss->width, 512);
    EXPECT_FALSE(b.window.isModified());
    EXPECT_EQ(b.window.recentProjects().value(0), file);

    // Each source kind comes back as saved (the studio and off keep the last file's path too).
    for (const EnvironmentChoice choice : {EnvironmentChoice::Off, EnvironmentChoice::ProceduralStudio}) {
        MaterialSettings other = saved;
        other.environment.choice = choice;
        const auto parsed = parseProject(projectToJson(other, file), file);
        ASSERT_TRUE(parsed) << parsed.error();
        EXPECT_EQ(parsed->settings.environment, other.environment);
    }
    // Projects written before the environment was saved open with the default environment.
    auto old = nlohmann::json::parse(*text);
    old.erase("environment");
    const auto parsed = parseProject(old.dump(), file);
    ASSERT_TRUE(parsed) << parsed.error();
    EXPECT_EQ(parsed->settings.environment, EnvironmentSettings{});
    // ... and those written before the lobe count was saved with the default mixture.
    old.erase("lobes");
    const auto noLobes = parseProject(old.dump(), file);
    ASSERT_TRUE(noLobes) << noLobes.error();
    EXPECT_EQ(noLobes->settings.mixtureLobes, kDefaultMixtureLobes);
}

// The mesh and camera were not saved (issue 48, point 7): a project reopened on the sphere.
TEST(Project, TheMeshAndCameraAreSavedAndReopened) {
    test::TempDir dir;
    const QString quad = QString(BURNISH_SOURCE_DIR) + "/tests/fuzz/corpus/obj/quad.obj";
    fs::copy_file(quad.toStdString(), dir / "quad.obj");
    TestWindow a;
    auto* panelA = a.window.findChild<ViewportPanel*>("viewportPanel");
    ASSERT_TRUE(panelA->loadMesh(render::MeshKind::Obj, q(dir / "quad.obj")));
    panelA->viewport()->orbit(50.0f, -12.5f);
    panelA->viewport()->setDistance(4.25f);
    ViewSettings panned = panelA->viewport()->viewSettings();
    panned.target = glm::vec3(0.25f, -0.5f, 0.125f);
    panelA->viewport()->setViewSettings(panned);
    const ViewSettings saved = panelA->viewport()->viewSettings();
    ASSERT_TRUE(a.window.saveProjectAs(q(dir / "scene.burnish")));
    const auto json = nlohmann::json::parse(burnish::readFile(dir / "scene.burnish").value());
    EXPECT_EQ(json["view"]["mesh"], "obj");
    EXPECT_EQ(json["view"]["obj"], "quad.obj") << "relative to the project, as the maps";

    TestWindow b;
    ASSERT_TRUE(b.window.openProject(q(dir / "scene.burnish")));
    const ViewSettings opened =
        b.window.findChild<ViewportPanel*>("viewportPanel")->viewport()->viewSettings();
    EXPECT_EQ(opened.mesh, render::MeshKind::Obj);
    EXPECT_EQ(opened.objPath, q(dir / "quad.obj"));
    EXPECT_FLOAT_EQ(opened.yawDegrees, saved.yawDegrees);
    EXPECT_FLOAT_EQ(opened.pitchDegrees, saved.pitchDegrees);
    EXPECT_FLOAT_EQ(opened.distance, 4.25f);
    EXPECT_EQ(opened.target, saved.target);
    EXPECT_TRUE(b.messages.isEmpty()) << b.messages.join("; ").toStdString();

    // A project saved before views were: the default sphere and camera.
    auto old = json;
    old.erase("view");
    ASSERT_TRUE(writeFileAtomic(dir / "old.burnish", old.dump(), Overwrite::Allow));
    ASSERT_TRUE(b.window.openProject(q(dir / "old.burnish")));
    const ViewSettings reset =
        b.window.findChild<ViewportPanel*>("viewportPanel")->viewport()->viewSettings();
    EXPECT_EQ(reset.mesh, render::MeshKind::Sphere);
    EXPECT_FLOAT_EQ(reset.yawDegrees, ViewSettings{}.yawDegrees);
    EXPECT_EQ(reset.target, glm::vec3(0.0f));

    // Its OBJ gone: the project opens on the sphere and says why.
    fs::remove(dir / "quad.obj");
    TestWindow c;
    ASSERT_TRUE(c.window.openProject(q(dir / "scene.burnish")));
    EXPECT_EQ(c.window.findChild<ViewportPanel*>("viewportPanel")->viewport()->viewSettings().mesh,
              render::MeshKind::Sphere);
    ASSERT_EQ(c.messages.size(), 1);
    EXPECT_TRUE(c.messages[0].contains("quad.obj")) << c.messages[0].toStdString();

    // A view that is not one is refused in one line naming the field, as every other field.
    for (const auto& [field, value, said] : std::vector<std::tuple<const char*, nlohmann::json, const char*>>{
             {"mesh", "cube", "view: 'mesh' must be \"sphere\", \"plane\", \"torus\" or \"obj\""},
             {"pitch", 120, "view: 'pitch' must be a number in [-90, 90]"},
             {"distance", 0, "view: 'distance' must be a number in [0.001, 10000]"},
             {"target", nlohmann::json::array({1, 2}), "view: 'target' must be an array of 3 numbers"}}) {
        auto bad = json;
        bad["view"][field] = value;
        const auto parsed = parseProject(bad.dump(), q(dir / "bad.burnish"));
        ASSERT_FALSE(parsed) << field;
        EXPECT_NE(parsed.error().find(said), std::string::npos) << parsed.error();
    }
}

TEST(Project, InvalidFilesLeaveTheDocumentUntouched) {
    test::TempDir dir;
    TestWindow w;
    MaterialDocument* doc = w.window.document();
    doc->setGloss(0.25);
    const MaterialSettings before = doc->settings();
    const int undoIndex = doc->undoStack()->index();

    const std::string valid = projectToJson(before, q(dir / "p.burnish"));
    auto withField = [&](const char* key, nlohmann::json value) {
        auto j = nlohmann::json::parse(valid);
        j[key] = std::move(value);
        return j.dump();
    };
    auto materialGloss = [&](nlohmann::json value) {
        auto j = nlohmann::json::parse(valid);
        j["material"]["gloss"] = std::move(value);
        return j.dump();
    };
    auto environmentField = [&](const char* key, nlohmann::json value) {
        auto j = nlohmann::json::parse(valid);
        j["environment"][key] = std::move(value);
        return j.dump();
    };
    const std::map<std::string, std::pair<std::string, std::string>> cases = {
        {"environment-source",
         {environmentField("source", "sun"),
          "environment: 'source' must be \"off\", \"studio\" or \"file\""}},
        {"environment-intensity",
         {environmentField("intensity", 5000), "'intensity' must be a number in [0, 1024]"}},
        {"environment-rotation",
         {environmentField("rotation", "left"), "'rotation' must be a number in [-180, 180]"}},
        {"environment-lobe",
         {environmentField("lobe", "ggx"), "'lobe' must be \"blinn-phong\" or \"phong\""}},
        {"environment-fis", {environmentField("fis", "yes"), "'fis' must be true or false"}},
        {"environment-background", {environmentField("background", 1), "'background' must be true or false"}},
        {"environment-samples", {environmentField("fisSamples", 0), "'fisSamples' must be a number in [1"}},
        {"environment-fractional-samples",
         {environmentField("fisSamples", 2.5), "'fisSamples' must be a whole"}},
        {"environment-unknown", {environmentField("exposure", 1), "environment: unknown field 'exposure'"}},
        {"environment-missing-file",
         {[&] {
              auto j = nlohmann::json::parse(valid);
              j["environment"]["source"] = "file";
              j["environment"]["file"] = "nowhere.hdr";
              return j.dump();
          }(),
          "nowhere.hdr' does not exist"}},
        {"environment-file-null",
         {[&] {
              auto j = nlohmann::json::parse(valid);
              j["environment"]["source"] = "file";
              j["environment"]["file"] = nullptr;
              return j.dump();
          }(),
          "'file' must be a path when the source is \"file\""}},
        {"corrupt", {valid.substr(0, valid.size() / 2), "not valid JSON"}},
        // A number beyond a double (found by fuzzing the readers): an error, not an escaping exception.
        {"number-out-of-range",
         {[&] {
              std::string text = materialGloss("HUGE");
              text.replace(text.find("\"HUGE\""), 6, "1e999");
              return text;
          }(),
          "a number out of range"}},
        // An image opened as a project (issue 44: the parser's own message showed): the artist's words.
        {"png-bytes",
         {std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16), "not a Burnish project: not valid JSON"}},
        {"wrong-type", {materialGloss("high"), "'gloss' must be a number in [0"}},
        {"newer", {withField("version", 2), "written by a newer Burnish (project version 2"}},
        {"unknown-preset", {withField("preset", "no-such-preset"), "preset 'no-such-preset' is not known"}},
        {"lobes-zero", {withField("lobes", 0), "'lobes' must be a number in [1"}},
        {"lobes-five", {withField("lobes", 5), "'lobes' must be a number in [1"}},
        {"lobes-fractional", {withField("lobes", 2.5), "'lobes' must be a whole number"}},
        {"lobes-text", {withField("lobes", "three"), "'lobes' must be a number in [1"}},
        {"missing-map",
         {[&] {
              auto j = nlohmann::json::parse(valid);
              j["maps"]["normal"] = "missing.png";
              return j.dump();
          }(),
          "missing.png"}},
        {"allow-implausible-not-a-list",
         {[&] {
              auto j = nlohmann::json::parse(valid);
              j["maps"]["allowImplausible"] = "normal";
              return j.dump();
          }(),
          "'allowImplausible' must be an array"}},
        {"allow-implausible-gloss",
         {[&] {
              auto j = nlohmann::json::parse(valid);
              j["maps"]["allowImplausible"] = {"gloss"};
              return j.dump();
          }(),
          "'allowImplausible' holds \"normal\" or \"detail\""}},
    };
    for (const auto& [name, c] : cases) {
        const fs::path file = dir / (name + ".burnish");
        ASSERT_TRUE(writeFileAtomic(file, c.first));
        w.messages.clear();
        EXPECT_FALSE(w.window.openProject(q(file))) << name;
        ASSERT_EQ(w.messages.size(), 1) << name;
        EXPECT_TRUE(w.messages[0].contains(QString::fromStdString(c.second)))
            << name << ": " << w.messages[0].toStdString();
        EXPECT_FALSE(w.messages[0].contains("json.exception")) << name << ": " << w.messages[0].toStdString();
        EXPECT_EQ(doc->settings(), before) << name;
        EXPECT_EQ(doc->undoStack()->index(), undoIndex) << name;
        EXPECT_TRUE(w.window.projectPath().isEmpty()) << name;
    }
}

// Loading a map decodes it off the GUI thread (an 8192² PNG froze the window for minutes): the call
// returns at once with the old map still shown, the new one arrives as one undo step, a newer
// request supersedes an older one, and a bad file is refused with nothing changed.
TEST(MaterialDocument, BackgroundLoadsKeepTheWindowLiveAndTheNewestWins) {
    test::TempDir dir;
    MaterialDocument doc;
    const auto before = doc.maps().normal;
    QSignalSpy started(&doc, &MaterialDocument::mapLoadStarted);
    QSignalSpy finished(&doc, &MaterialDocument::mapLoadFinished);
    const int steps = doc.undoStack()->count();
    doc.loadMapInBackground(MapSlot::Normal, kNormalMap);
    EXPECT_EQ(started.count(), 1);
    EXPECT_TRUE(doc.loading(MapSlot::Normal));
    EXPECT_EQ(doc.maps().normal, before) << "the old map stays until the new one is decoded";
    ASSERT_TRUE(finished.wait(kWorkerTimeoutMs));
    EXPECT_TRUE(finished.at(0).at(2).toBool()) << finished.at(0).at(3).toString().toStdString();
    EXPECT_FALSE(doc.loading(MapSlot::Normal));
    EXPECT_EQ(doc.settings().normalMapPath, kNormalMap);
    EXPECT_EQ(doc.undoStack()->count(), steps + 1);
    doc.undoStack()->undo();
    EXPECT_EQ(doc.maps().normal, before);

    // Two requests in a row: only the second is applied.
    QImage flat(64, 32, QImage::Format_RGB888);
    flat.fill(QColor(128, 128, 255));
    const QString second = q(dir / "flat.png");
    ASSERT_TRUE(flat.save(second));
    finished.clear();
    doc.loadMapInBackground(MapSlot::Normal, kNormalMap);
    doc.loadMapInBackground(MapSlot::Normal, second);
    ASSERT_TRUE(finished.wait(kWorkerTimeoutMs));
    QTest::qWait(200); // the first request's result, if it came later, would be dropped too
    ASSERT_EQ(finished.count(), 1) << "the superseded request reports nothing";
    EXPECT_EQ(doc.settings().normalMapPath, second);
    EXPECT_EQ(doc.maps().normal->width, 64);

    // A file that is not an image: refused, the document unchanged.
    std::ofstream(dir / "bad.png") << "not a png";
    finished.clear();
    doc.loadMapInBackground(MapSlot::Normal, q(dir / "bad.png"));
    ASSERT_TRUE(finished.wait(kWorkerTimeoutMs));
    EXPECT_FALSE(finished.at(0).at(2).toBool());
    EXPECT_TRUE(finished.at(0).at(3).toString().contains("bad.png"))
        << finished.at(0).at(3).toString().toStdString();
    EXPECT_EQ(doc.settings().normalMapPath, second);
}

// A map the plausibility check refuses (here every texel points below the surface) can be loaded
// anyway: the window asks once the load has ended, showing the measured reason; No leaves the document
// as it was, Yes takes the map in as one undo step that the project, its bake job and a reopened
// window keep; a later ordinary map clears the choice. A synchronous load still refuses it.
TEST(MainWindow, ARefusedNormalMapCanBeLoadedAnywayAndTheProjectRemembersIt) {
    test::TempDir dir;
    QImage below(64, 64, QImage::Format_RGB888);
    below.fill(QColor(128, 128, 20)); // z = 2·20/255 − 1 < 0
    const QString odd = q(dir / "odd.png");
    ASSERT_TRUE(below.save(odd));

    TestWindow w;
    MaterialDocument* doc = w.window.document();
    const MaterialSettings before = doc->settings();
    const int steps = doc->undoStack()->count();
    EXPECT_FALSE(doc->loadMap(MapSlot::Normal, odd).ok());
    EXPECT_FALSE(doc->holdsRefusedMap(MapSlot::Normal)) << "only a background load holds one";

    QSignalSpy finished(doc, &MaterialDocument::mapLoadFinished);
    auto load = [&](const QString& path) {
        finished.clear();
        doc->loadMapInBackground(MapSlot::Normal, path);
        EXPECT_TRUE(finished.wait(kWorkerTimeoutMs));
        QApplication::processEvents(); // the question comes after the load's signal
    };
    w.answer = QMessageBox::No;
    load(odd);
    ASSERT_EQ(w.questions.size(), 1);
    EXPECT_TRUE(w.questions[0].contains("point below the surface")) << w.questions[0].toStdString();
    EXPECT_TRUE(w.questions[0].contains("odd.png")) << w.questions[0].toStdString();
    EXPECT_TRUE(w.messages.isEmpty()) << "a question, not an error box";
    EXPECT_FALSE(doc->holdsRefusedMap(MapSlot::Normal));
    EXPECT_EQ(doc->settings(), before);
    EXPECT_EQ(doc->undoStack()->count(), steps);

    w.answer = QMessageBox::Yes;
    load(odd);
    ASSERT_EQ(w.questions.size(), 2);
    EXPECT_EQ(doc->settings().normalMapPath, odd);
    EXPECT_TRUE(doc->settings().allowImplausibleNormal);
    EXPECT_EQ(doc->maps().normal->width, 64);
    EXPECT_EQ(doc->undoStack()->count(), steps + 1);
    EXPECT_TRUE(doc->diagnostics(MapSlot::Normal).join("\n").contains("loaded anyway"))
        << doc->diagnostics(MapSlot::Normal).join("\n").toStdString();
    EXPECT_TRUE(bakeJobSpecFor(*doc).allowImplausible);
    doc->undoStack()->undo();
    EXPECT_EQ(doc->settings(), before);
    doc->undoStack()->redo();
    EXPECT_TRUE(doc->settings().allowImplausibleNormal);

    // Saved, and reopened without a question.
    const QString project = q(dir / "odd.burnish");
    ASSERT_TRUE(w.window.saveProjectAs(project)) << w.messages.join("\n").toStdString();
    QFile file(project);
    ASSERT_TRUE(file.open(QIODevice::ReadOnly));
    EXPECT_TRUE(QString::fromUtf8(file.readAll()).contains("\"allowImplausible\""));
    TestWindow again;
    ASSERT_TRUE(again.window.openProject(project)) << again.messages.join("\n").toStdString();
    EXPECT_EQ(again.window.document()->settings().normalMapPath, odd);
    EXPECT_TRUE(again.window.document()->settings().allowImplausibleNormal);
    EXPECT_TRUE(again.questions.isEmpty());

    // An ordinary map in its place clears the choice.
    load(kNormalMap);
    EXPECT_EQ(doc->settings().normalMapPath, kNormalMap);
    EXPECT_FALSE(doc->settings().allowImplausibleNormal);
    EXPECT_FALSE(bakeJobSpecFor(*doc).allowImplausible);
    EXPECT_EQ(w.questions.size(), 2);
}

// Drag and drop as a user does it: an image dropped on a map slot loads into that slot; one
// dropped anywhere else on the window becomes the normal map; what is not a local file is ignored.
TEST(MainWindow, DroppedImagesLoadIntoTheSlotTheyAreDroppedOn) {
    test::TempDir dir;
    TestWindow w;
    MaterialDocument* doc = w.window.document();
    auto drop = [](QWidget* target, const QList<QUrl>& urls) {
        QMimeData data;
        data.setUrls(urls);
        const QPoint at(target->width() / 2, target->height() / 2);
        QDragEnterEvent enter(at, Qt::CopyAction, &data, Qt::LeftButton, Qt::NoModifier);
        QApplication::sendEvent(target, &enter);
        QDropEvent dropEvent(QPointF(at), Qt::CopyAction, &data, Qt::LeftButton, Qt::NoModifier);
        QApplication::sendEvent(target, &dropEvent);
        QApplication::processEvents(); // the window acts once the drop has finished
        return enter.isAccepted();
    };
    // A gloss map of the normal map's (the sample's) size, dropped on the Gloss slot.
    const QString gloss = writeGlossMap(dir / "gloss.png", kSampleSize, 180);
    MapSlotWidget* glossSlot = w.window.materialPanel()->slotWidget(MapSlot::Gloss);
    ASSERT_NE(glossSlot, nullptr);
    EXPECT_TRUE(drop(glossSlot, {QUrl::fromLocalFile(gloss)}));
    EXPECT_EQ(doc->settings().glossMapPath, gloss);
    EXPECT_TRUE(doc->settings().normalMapPath.isEmpty()) << "the normal slot is untouched";

    // A normal map dropped on the window (not on a slot) goes to the normal slot. The gloss map
    // does not fit a map of another size, so that one is refused with the reason, nothing changed.
    QImage small(64, 32, QImage::Format_RGB888);
    small.fill(QColor(128, 128, 255));
    const QString smallMap = q(dir / "small.png");
    ASSERT_TRUE(small.save(smallMap));
    EXPECT_TRUE(drop(&w.window, {QUrl::fromLocalFile(smallMap)}));
    EXPECT_TRUE(doc->settings().normalMapPath.isEmpty());
    ASSERT_FALSE(w.messages.isEmpty());
    EXPECT_TRUE(w.messages.last().contains("gloss")) << w.messages.last().toStdString();
    doc->clearMap(MapSlot::Gloss);
    EXPECT_TRUE(drop(&w.window, {QUrl::fromLocalFile(kNormalMap)}));
    EXPECT_EQ(doc->settings().normalMapPath, kNormalMap);

    // A web address is not a file: the drop is not even accepted.
    const int steps = doc->undoStack()->count();
    EXPECT_FALSE(drop(glossSlot, {QUrl("https://example.com/normal.png")}));
    EXPECT_EQ(doc->undoStack()->count(), steps);
}

// Drops went to the wrong handler (issue 48, point 5): an OBJ dropped on the window was read as a
// normal map, a project dropped on a slot likewise, a normal map dropped on the Gloss slot was
// taken, and a project dropped on unsaved work asked inside the drop. Now each goes where it
// belongs, after the drop has finished.
TEST(MainWindow, DropsAreRoutedByWhatIsDropped) {
    test::TempDir dir;
    TestWindow w;
    MaterialDocument* doc = w.window.document();
    auto drop = [](QWidget* target, const QString& path) {
        QMimeData data;
        data.setUrls({QUrl::fromLocalFile(path)});
        const QPoint at(target->width() / 2, target->height() / 2);
        QDragEnterEvent enter(at, Qt::CopyAction, &data, Qt::LeftButton, Qt::NoModifier);
        QApplication::sendEvent(target, &enter);
        if (!enter.isAccepted()) return false;
        QDropEvent dropEvent(QPointF(at), Qt::CopyAction, &data, Qt::LeftButton, Qt::NoModifier);
        QApplication::sendEvent(target, &dropEvent);
        return dropEvent.isAccepted();
    };
    MapSlotWidget* glossSlot = w.window.materialPanel()->slotWidget(MapSlot::Gloss);
    // An OBJ becomes the mesh, once the drop has finished, wherever it is dropped: a slot does not
    // take it and it goes on to the window.
    const QString quad = QString(BURNISH_SOURCE_DIR) + "/tests/fuzz/corpus/obj/quad.obj";
    auto* viewport = w.window.findChild<ViewportPanel*>("viewportPanel")->viewport();
    EXPECT_TRUE(drop(glossSlot, quad));
    EXPECT_EQ(viewport->viewSettings().mesh, render::MeshKind::Sphere) << "nothing happens inside the drop";
    QApplication::processEvents();
    EXPECT_EQ(viewport->viewSettings().mesh, render::MeshKind::Obj);
    EXPECT_TRUE(doc->settings().normalMapPath.isEmpty()) << "not read as a normal map";
    EXPECT_TRUE(doc->settings().glossMapPath.isEmpty()) << "nor as a gloss map";
    EXPECT_TRUE(w.messages.isEmpty()) << w.messages.join("; ").toStdString();

    // A file of no kind the studio reads is refused in a message naming it.
    std::ofstream(dir / "notes.txt") << "hello\n";
    EXPECT_TRUE(drop(&w.window, q(dir / "notes.txt")));
    QApplication::processEvents();
    ASSERT_EQ(w.messages.size(), 1);
    EXPECT_TRUE(w.messages[0].contains("notes.txt") && w.messages[0].contains("not an image"))
        << w.messages[0].toStdString();

    // A normal map dropped on the Gloss slot is refused with the reason; the slot stays empty.
    EXPECT_TRUE(drop(glossSlot, kNormalMap));
    EXPECT_TRUE(doc->settings().glossMapPath.isEmpty());
    ASSERT_EQ(w.messages.size(), 2);
    EXPECT_TRUE(w.messages[1].contains("looks like a tangent-space normal map"))
        << w.messages[1].toStdString();

    // A project dropped on unsaved work: the question comes after the drop, then the project opens.
    TestWindow saver;
    saver.window.document()->setGloss(0.3125);
    ASSERT_TRUE(saver.window.saveProjectAs(q(dir / "scene.burnish")));
    doc->setGloss(0.75); // unsaved work
    w.answer = QMessageBox::Discard;
    EXPECT_TRUE(drop(glossSlot, q(dir / "scene.burnish"))); // on a slot: still the window's to open
    EXPECT_TRUE(w.questions.isEmpty()) << "no question inside the drop";
    QApplication::processEvents();
    EXPECT_EQ(w.questions.size(), 1);
    EXPECT_DOUBLE_EQ(doc->settings().gloss, 0.3125);
    EXPECT_EQ(w.window.projectPath(), QFileInfo(q(dir / "scene.burnish")).absoluteFilePath());
}

TEST(MainWindow, OpenFileTakesAProjectOrAnImageAsTheNormalMap) {
    // What `burnish-studio FILE` and a drop on the window do: an image becomes the normal map of
    // the current document, a .burnish file replaces the document, and a bad file changes nothing.
    test::TempDir dir;
    TestWindow w;
    ASSERT_TRUE(w.window.openFile(kNormalMap)) << w.messages.join("\n").toStdString();
    EXPECT_EQ(w.window.document()->settings().normalMapPath, QFileInfo(kNormalMap).absoluteFilePath());
    EXPECT_EQ(w.window.document()->maps().normal->width, 512);
    EXPECT_TRUE(w.messages.isEmpty());

    const QString broken = q(dir / "broken.png");
    ASSERT_TRUE(writeFileAtomic(broken.toStdString(), std::string("\x89PNG\r\n\x1a\n not a png")));
    const MaterialSettings before = w.window.document()->settings();
    EXPECT_FALSE(w.window.openFile(broken));
    ASSERT_EQ(w.messages.size(), 1);
    EXPECT_TRUE(w.messages[0].contains("broken.png")) << w.messages[0].toStdString();
    EXPECT_EQ(w.window.document()->settings(), before);

    const QString project = q(dir / "m.burnish");
    ASSERT_TRUE(w.window.saveProjectAs(project)) << w.messages.join("\n").toStdString();
    TestWindow other;
    ASSERT_TRUE(other.window.openFile(project)) << other.messages.join("\n").toStdString();
    EXPECT_EQ(other.window.document()->settings(), before);
}

TEST(MainWindow, ProcessGltfAssetWritesWhatBurnishGltfWritesAndAsksBeforeReplacing) {
    // File ▸ Process glTF Asset…: the test plane with a real normal map, baked with the document's
    // method, on a worker thread; the same asset bytes as `burnish gltf --method <that method>`.
    test::TempDir dir;
    fs::create_directories(dir / "in");
    fs::copy_file(fs::path(BURNISH_TEST_DATA_DIR) / "gltf" / "plane.gltf", dir / "in" / "plane.gltf");
    fs::copy_file(kNormalMap.toStdString(), dir / "in" / "normal.png");
    TestWindow w;
    EXPECT_EQ(gltfMethodFor(*w.window.document()), std::nullopt); // another preset: gltf's own default
    ASSERT_TRUE(w.window.document()->setPreset("gltf"));
    ASSERT_TRUE(w.window.document()->setMethod(Method::Vmf));
    EXPECT_EQ(gltfMethodFor(*w.window.document()), "vmf");
    // The mixture the viewport shows goes out as BURNISH_lobe_mixture beside the fitted lobe, its lobe count
    // too.
    ASSERT_TRUE(w.window.document()->setPreset("mixture"));
    ASSERT_TRUE(w.window.document()->setMethod(Method::Mixture));
    w.window.document()->setMixtureLobes(2);
    GltfOptions mixture;
    setGltfMethod(*w.window.document(), mixture);
    EXPECT_EQ(mixture.method, "mixture");
    EXPECT_EQ(mixture.mixtureLobes, 2);
    ASSERT_TRUE(w.window.document()->setPreset("gltf"));
    ASSERT_TRUE(w.window.document()->setMethod(Method::Vmf));
    QSignalSpy finished(&w.window, &MainWindow::gltfFinished);
    QSignalSpy progress(w.window.gltfRunner(), &GltfRunner::progress);
    w.window.processGltfAsset(q(dir / "in" / "plane.gltf"), q(dir / "studio"));
    ASSERT_TRUE(finished.wait(kWorkerTimeoutMs));
    ASSERT_TRUE(finished.at(0).at(0).toBool()) << finished.at(0).at(1).toString().toStdString();
    EXPECT_TRUE(finished.at(0).at(1).toString().contains("Material 0 'metal'"))
        << finished.at(0).at(1).toString().toStdString();
    EXPECT_GT(progress.count(), 2);
    EXPECT_TRUE(w.messages.isEmpty());
    ASSERT_EQ(w.results.size(), 1);
    GltfOptions cli;
    cli.method = "vmf";
    auto expected = processGltf(dir / "in" / "plane.gltf", dir / "cli", cli);
    ASSERT_TRUE(expected) << expected.error();
    for (const std::string& name : expected->written)
        EXPECT_EQ(*readFile(dir / "studio" / name), *readFile(dir / "cli" / name)) << name;

    // Again into the same folder: asked first; "Cancel" leaves everything as it was.
    const auto before = fs::last_write_time(dir / "studio" / "plane.gltf");
    w.answer = QMessageBox::Cancel;
    w.window.processGltfAsset(q(dir / "in" / "plane.gltf"), q(dir / "studio"));
    EXPECT_FALSE(w.window.gltfRunner()->running());
    EXPECT_EQ(fs::last_write_time(dir / "studio" / "plane.gltf"), before);
    // "Yes" replaces it; a broken asset reports its one-line error.
    w.answer = QMessageBox::Yes;
    w.window.processGltfAsset(q(dir / "in" / "plane.gltf"), q(dir / "studio"));
    ASSERT_TRUE(finished.wait(kWorkerTimeoutMs));
    EXPECT_TRUE(finished.at(1).at(0).toBool());
    ASSERT_TRUE(
        writeFileAtomic(dir / "in" / "broken.gltf", std::string("{\"asset\": {\"version\": \"1.0\"}}")));
    w.window.processGltfAsset(q(dir / "in" / "broken.gltf"), q(dir / "studio"));
    ASSERT_TRUE(finished.wait(kWorkerTimeoutMs));
    EXPECT_FALSE(finished.at(2).at(0).toBool());
    EXPECT_TRUE(w.messages.last().contains("glTF version 1.0")) << w.messages.last().toStdString();
}

TEST(MainWindow, ExportGltfWritesTheMaterialWithItsSpecularColour) {
    // File ▸ Export glTF…: the document's normal map, gloss and specular colour as a glTF material, the
    // same bytes as core's exportMaterialGltf of gltfMaterialSourceFor(document).
    test::TempDir dir;
    TestWindow w;
    MaterialDocument& doc = *w.window.document();
    ASSERT_TRUE(doc.setSpecularMaterial("gold"));
    doc.setGloss(0.5);
    QSignalSpy finished(&w.window, &MainWindow::gltfFinished);
    w.window.exportGltf(q(dir / "studio"));
    ASSERT_TRUE(finished.wait(kWorkerTimeoutMs));
    ASSERT_TRUE(finished.at(0).at(0).toBool()) << finished.at(0).at(1).toString().toStdString();
    auto text = readFile(dir / "studio" / "material.gltf");
    ASSERT_TRUE(text);
    const auto asset = nlohmann::json::parse(*text);
    const auto& color = asset["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"];
    EXPECT_EQ(color[0].get<double>(), doc.settings().specular.r); // a metal: F0 is the base colour
    EXPECT_EQ(color[2].get<double>(), doc.settings().specular.b);
    const GltfMaterialSource source = gltfMaterialSourceFor(doc, "material");
    EXPECT_NEAR(source.roughness, GlossEncoding::ggxRoughness().value(doc.power()), 1e-12);
    auto expected = exportMaterialGltf(source, dir / "core");
    ASSERT_TRUE(expected) << expected.error();
    for (const std::string& name : expected->written)
        EXPECT_EQ(*readFile(dir / "studio" / name), *readFile(dir / "core" / name)) << name;
}

TEST(Project, AutosaveIsWrittenAndOfferedForRecovery) {
    test::TempDir dir;
    const QString file = q(dir / "a.burnish");
    {
        TestWindow w;
        ASSERT_TRUE(w.window.saveProjectAs(file));
        EXPECT_FALSE(w.window.autosave()) << "nothing to autosave in a clean document";
        w.window.document()->setGloss(0.125);
        ASSERT_TRUE(w.window.autosave());
        ASSERT_TRUE(w.window.waitForAutosave());
        const QString copy = autosavePathFor(file);
        ASSERT_TRUE(QFile::exists(copy));
        const auto parsed = loadProject(copy);
        ASSERT_TRUE(parsed) << parsed.error();
        EXPECT_EQ(parsed->autosaveOf, file);
        EXPECT_EQ(parsed->settings.gloss, 0.125);
        // Make the project clearly older than its copy (file times may share a clock tick).
        QFile project(file);
        ASSERT_TRUE(project.open(QIODevice::ReadWrite));
        ASSERT_TRUE(project.setFileTime(QDateTime::currentDateTime().addSecs(-60),
                                        QFileDevice::FileModificationTime));
        project.close();
        ASSERT_TRUE(recoverableAutosave(file).has_value());
        // The window "crashes" here: its destructor runs no close event, so the copy stays.
    }
    auto again = std::make_unique<TestWindow>();
    // Opening the project offers its newer autosave: No keeps the copy for later.
    again->answer = QMessageBox::No;
    ASSERT_TRUE(again->window.openProject(file));
    EXPECT_NE(again->window.document()->settings().gloss, 0.125) << "the saved project has the old gloss";
    EXPECT_TRUE(recoverableAutosave(file).has_value()) << "No keeps the autosave";
    again->answer = QMessageBox::Yes;
    again->window.offerRecovery();
    EXPECT_EQ(again->window.document()->settings().gloss, 0.125);
    EXPECT_TRUE(again->window.isModified()) << "recovered changes are not saved yet";
    ASSERT_TRUE(again->window.saveProjectAs(file));
    EXPECT_FALSE(QFile::exists(autosavePathFor(file))) << "saving removes the autosave copy";
    EXPECT_FALSE(recoverableAutosave(file).has_value());

    // Only an explicit Discard deletes an autosave the artist was offered.
    again->window.document()->setGloss(0.25);
    ASSERT_TRUE(again->window.autosave());
    ASSERT_TRUE(again->window.waitForAutosave());
    QFile project(file);
    ASSERT_TRUE(project.open(QIODevice::ReadWrite));
    ASSERT_TRUE(
        project.setFileTime(QDateTime::currentDateTime().addSecs(-60), QFileDevice::FileModificationTime));
    project.close();
    {
        // While the window that wrote it lives, the copy is its work in progress: not offered.
        TestWindow other;
        other.answer = QMessageBox::Discard;
        ASSERT_TRUE(other.window.openProject(file));
        EXPECT_TRUE(other.questions.isEmpty()) << other.questions.join('\n').toStdString();
        EXPECT_TRUE(QFile::exists(autosavePathFor(file)));
    }
    again.reset(); // "crashes"
    TestWindow third;
    third.answer = QMessageBox::Discard;
    ASSERT_TRUE(third.window.openProject(file));
    EXPECT_FALSE(QFile::exists(autosavePathFor(file)));
    EXPECT_NE(third.window.document()->settings().gloss, 0.25);
}

/// Points the user's data (autosave copies, settings) at a folder of its own for one test: other test
/// processes running beside it leave copies of their own in the shared test location.
class PrivateUserData {
public:
    PrivateUserData()
        : m_home(qgetenv("HOME")) {
        qputenv("HOME", QByteArray::fromStdString(m_dir.path().string()));
    }
    ~PrivateUserData() { qputenv("HOME", m_home); }
    PrivateUserData(const PrivateUserData&) = delete;
    PrivateUserData& operator=(const PrivateUserData&) = delete;

private:
    test::TempDir m_dir;
    QByteArray m_home;
};

/// Sets a file's modification time `secondsAgo` before now.
void age(const QString& path, int secondsAgo) {
    QFile file(path);
    ASSERT_TRUE(file.open(QIODevice::ReadWrite)) << path.toStdString();
    ASSERT_TRUE(file.setFileTime(QDateTime::currentDateTime().addSecs(-secondsAgo),
                                 QFileDevice::FileModificationTime));
}

TEST(Project, AStartWithNothingNamedOffersWhatEveryCrashedWindowLeft) {
    PrivateUserData data;
    ASSERT_TRUE(autosaveFolder().startsWith(qEnvironmentVariable("HOME")));
    test::TempDir dir;
    const QString file = q(dir / "saved.burnish");
    QString savedCopy, untitledCopy;
    {
        // A saved project edited, and an untitled document edited, in two windows that crash.
        TestWindow saved, untitled;
        ASSERT_TRUE(saved.window.saveProjectAs(file));
        saved.window.document()->setGloss(0.125);
        ASSERT_TRUE(saved.window.autosave());
        ASSERT_TRUE(saved.window.waitForAutosave());
        savedCopy = saved.window.autosaveCopy();
        untitled.window.document()->setGloss(0.375);
        ASSERT_TRUE(untitled.window.autosave());
        ASSERT_TRUE(untitled.window.waitForAutosave());
        untitledCopy = untitled.window.autosaveCopy();
        EXPECT_NE(untitledCopy, autosavePathFor({})) << "each window's untitled work has a copy of its own";
    }
    age(file, 300);
    age(savedCopy, 120);
    age(untitledCopy, 60); // the newest
    {
        // A third window stays open with unsaved work: its copy is not a crash's.
        TestWindow live;
        live.window.document()->setGloss(0.625);
        ASSERT_TRUE(live.window.autosave());
        ASSERT_TRUE(live.window.waitForAutosave());
        TestWindow start;
        start.answer = QMessageBox::No;
        start.window.offerRecoveryAtLaunch();
        ASSERT_EQ(start.questions.size(), 2) << start.questions.join('\n').toStdString();
        EXPECT_TRUE(start.questions[0].contains("unsaved work")) << start.questions[0].toStdString();
        EXPECT_TRUE(start.questions[1].contains("saved.burnish")) << start.questions[1].toStdString();
    }
    // Before: a start with no arguments offered the untitled copy only, and only "untitled.burnish".
    TestWindow start;
    start.answer = QMessageBox::No;
    start.window.offerRecoveryAtLaunch();
    ASSERT_EQ(start.questions.size(), 3)
        << "the live window has gone too: " << start.questions.join('\n').toStdString();
    EXPECT_TRUE(QFile::exists(savedCopy) && QFile::exists(untitledCopy)) << "No keeps every copy";

    // Yes on the saved project's copy: the project opens with the recovered state, unsaved.
    TestWindow again;
    again.window.setAutosaveDelay(0);
    int asked = 0;
    again.window.ask = [&](const QString&, const QString& text, QMessageBox::StandardButtons) {
        ++asked;
        return text.contains("saved.burnish") ? QMessageBox::Yes : QMessageBox::No;
    };
    again.window.offerRecoveryAtLaunch();
    EXPECT_EQ(again.window.projectPath(), QFileInfo(file).absoluteFilePath());
    EXPECT_EQ(again.window.document()->settings().gloss, 0.125);
    EXPECT_TRUE(again.window.isModified());
    EXPECT_EQ(again.window.autosaveCopy(), savedCopy) << "the recovered copy is the window's own now";
    ASSERT_TRUE(again.window.saveProjectAs(file));
    EXPECT_FALSE(QFile::exists(savedCopy));
    EXPECT_TRUE(QFile::exists(untitledCopy)) << "the untitled work waits for the next start";
}

TEST(Project, DiscardedWorkIsNotOfferedAgain) {
    PrivateUserData data;
    QString copy;
    {
        TestWindow w;
        w.window.document()->setGloss(0.125);
        ASSERT_TRUE(w.window.autosave());
        ASSERT_TRUE(w.window.waitForAutosave());
        copy = w.window.autosaveCopy();
        ASSERT_TRUE(QFile::exists(copy));
        // New ▸ Discard: the changes are gone, and so is their copy. (Before: the copy stayed and the
        // next start offered it again.)
        w.answer = QMessageBox::Discard;
        ASSERT_TRUE(w.window.newDocument());
        EXPECT_FALSE(QFile::exists(copy));
        // Edited again, then closed with Discard.
        w.window.document()->setGloss(0.25);
        ASSERT_TRUE(w.window.autosave());
        ASSERT_TRUE(w.window.waitForAutosave());
        ASSERT_TRUE(QFile::exists(w.window.autosaveCopy()));
        EXPECT_TRUE(w.window.close());
        EXPECT_FALSE(QFile::exists(w.window.autosaveCopy()));
    }
    TestWindow start;
    start.window.offerRecoveryAtLaunch();
    EXPECT_TRUE(start.questions.isEmpty()) << start.questions.join('\n').toStdString();
}

TEST(Project, AutosaveFollowsAnEditWithinItsDelay) {
    PrivateUserData data;
    TestWindow w;
    w.window.setAutosaveDelay(100);
    const QString copy = w.window.autosaveCopy();
    QTest::qWait(300);
    EXPECT_FALSE(QFile::exists(copy)) << "nothing edited, nothing written";
    w.window.document()->setGloss(0.125);
    w.window.document()->setGloss(0.25); // a burst of edits: one autosave
    // Before: the first autosave came on a two-minute clock, whenever the edit was.
    EXPECT_TRUE(QTest::qWaitFor([&] { return QFile::exists(copy); }, kWorkerTimeoutMs));
    ASSERT_TRUE(w.window.waitForAutosave());
    auto parsed = loadProject(copy);
    ASSERT_TRUE(parsed) << parsed.error();
    EXPECT_EQ(parsed->settings.gloss, 0.25);
    // A later edit is written too.
    w.window.document()->setGloss(0.5);
    EXPECT_TRUE(QTest::qWaitFor(
        [&] {
            auto p = loadProject(copy);
            return p && p->settings.gloss == 0.5;
        },
        kWorkerTimeoutMs));
}

TEST(Project, RecoveryNeverSilentlyReplacesAnImageNamedAtStart) {
    PrivateUserData data;
    {
        TestWindow crashed;
        crashed.window.document()->setGloss(0.125);
        ASSERT_TRUE(crashed.window.autosave());
        ASSERT_TRUE(crashed.window.waitForAutosave());
    }
    // burnish-studio IMAGE: the map opens; the offer says recovering would replace it, and No keeps it.
    TestWindow w;
    ASSERT_TRUE(w.window.openFile(kNormalMap));
    w.answer = QMessageBox::No;
    w.window.offerRecoveryAtLaunch(kNormalMap);
    ASSERT_EQ(w.questions.size(), 1);
    EXPECT_TRUE(w.questions[0].contains("replaces trak-rust1_nm.png")) << w.questions[0].toStdString();
    EXPECT_EQ(w.window.document()->settings().normalMapPath, kNormalMap);
    EXPECT_EQ(w.window.document()->undoStack()->count(), 1) << "History keeps the map's load";
    // A project named at start: other copies wait for a start that names nothing.
    test::TempDir dir;
    const QString file = q(dir / "named.burnish");
    ASSERT_TRUE(w.window.saveProjectAs(file));
    TestWindow named;
    ASSERT_TRUE(named.window.openProject(file));
    named.window.offerRecoveryAtLaunch(file);
    EXPECT_TRUE(named.questions.isEmpty()) << named.questions.join('\n').toStdString();
}

std::map<std::string, std::string> folderBytes(const fs::path& folder) {
    std::map<std::string, std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(folder))
        if (e.is_regular_file()) {
            auto bytes = readFile(e.path());
            files[fs::relative(e.path(), folder).string()] = bytes ? *bytes : "<unreadable>";
        }
    return files;
}

// A second export into a folder that holds the set asks "Overwrite…?" in the studio's words (it
// used to fail with the command line's "use --force"): Cancel leaves the set as it was, Yes replaces
// it for this export only.
TEST(BakeDialog, ExportIntoAFilledFolderAsksBeforeOverwriting) {
    test::TempDir dir;
    MaterialDocument doc;
    BakeDialog dialog(&doc);
    QStringList questions;
    QMessageBox::StandardButton answer = QMessageBox::Cancel;
    dialog.ask = [&](const QString&, const QString& text, QMessageBox::StandardButtons) {
        questions << text;
        return answer;
    };
    dialog.outputEdit()->setText(q(dir / "out"));
    auto bake = [&] {
        QSignalSpy finished(&dialog, &BakeDialog::bakeFinished);
        dialog.startBake();
        EXPECT_TRUE(finished.count() > 0 || finished.wait(kWorkerTimeoutMs));
        return finished.isEmpty() ? false : finished.at(0).at(0).toBool();
    };
    ASSERT_TRUE(bake()) << dialog.resultLabel()->text().toStdString();
    EXPECT_TRUE(questions.isEmpty()) << "an empty folder needs no question";
    const auto first = folderBytes(dir / "out");

    doc.setGloss(0.3);
    EXPECT_FALSE(bake());
    ASSERT_EQ(questions.size(), 1);
    EXPECT_TRUE(questions[0].contains("Overwrite")) << questions[0].toStdString();
    EXPECT_TRUE(questions[0].contains("bake.json")) << questions[0].toStdString();
    EXPECT_FALSE(questions[0].contains("--force"));
    EXPECT_EQ(dialog.resultLabel()->text().toStdString(),
              "Not exported: the folder's set was left as it was.");
    EXPECT_EQ(folderBytes(dir / "out"), first) << "Cancel changes nothing";

    answer = QMessageBox::Yes;
    ASSERT_TRUE(bake()) << dialog.resultLabel()->text().toStdString();
    EXPECT_NE(folderBytes(dir / "out"), first) << "Yes replaces the set";
    EXPECT_FALSE(doc.settings().exportSettings.overwrite) << "the setting itself is not changed";
}

// A refused export says what to change in the dialog, never a command-line option: LEAN's moments
// into 8-bit PNG read "(choose png16, … or allow 8-bit storage with --allow-8bit)".
TEST(BakeDialog, ARefusedExportSpeaksOfTheDialogNotTheCommandLine) {
    test::TempDir dir;
    MaterialDocument doc;
    ASSERT_TRUE(doc.setPreset("lean"));
    BakeDialog dialog(&doc);
    ASSERT_GE(dialog.formatCombo()->findData(QString("png8")), 0);
    dialog.formatCombo()->setCurrentIndex(dialog.formatCombo()->findData(QString("png8")));
    dialog.outputEdit()->setText(q(dir / "out"));
    QSignalSpy finished(&dialog, &BakeDialog::bakeFinished);
    dialog.startBake();
    ASSERT_TRUE(finished.count() > 0 || finished.wait(kWorkerTimeoutMs));
    EXPECT_FALSE(finished.at(0).at(0).toBool());
    const QString shown = dialog.resultLabel()->text();
    EXPECT_TRUE(shown.contains("choose a 16-bit or float Format")) << shown.toStdString();
    EXPECT_FALSE(shown.contains("--")) << shown.toStdString();
    EXPECT_EQ(inStudioWords("refusing to overwrite x (use --force to replace the set)"),
              "refusing to overwrite x (tick \"Replace an existing set\")");
}

TEST(BakeDialog, ExportWritesTheBytesOfBurnishBake) {
    struct Case {
        const char* preset;
        const char* format;
        const char* compression;
        bool detail;
    };
    for (const Case c : {Case{"gltf", "png16", "", true}, Case{"blackops", "dds", "rgba8", false}}) {
        SCOPED_TRACE(c.preset);
        test::TempDir dir;
        MaterialDocument doc;
        ASSERT_TRUE(doc.setPreset(c.preset));
        ASSERT_TRUE(doc.loadMap(MapSlot::Normal, kNormalMap));
        if (c.detail) {
            ASSERT_TRUE(doc.loadMap(MapSlot::Detail, kNormalMap));
        }
        doc.setGloss(0.6);
        BakeDialog dialog(&doc);
        dialog.formatCombo()->setCurrentIndex(dialog.formatCombo()->findData(QString(c.format)));
        dialog.compressionCombo()->setCurrentIndex(
            std::max(0, dialog.compressionCombo()->findData(QString(c.compression))));
        dialog.outputEdit()->setText(q(dir / "studio"));
        QSignalSpy finished(&dialog, &BakeDialog::bakeFinished);
        dialog.startBake();
        ASSERT_TRUE(finished.count() > 0 || finished.wait(kWorkerTimeoutMs));
        ASSERT_TRUE(finished.at(0).at(0).toBool()) << finished.at(0).at(1).toString().toStdString();
        EXPECT_TRUE(dialog.resultLabel()->text().startsWith("Wrote"));

        char power[64];
        std::snprintf(power, sizeof power, "%.17g", doc.power());
        std::string args = "bake " + test::shellQuote(kNormalMap.toStdString()) + " --preset " + c.preset +
                           " --method " + std::string(methodName(doc.settings().method)) + " --power " +
                           power + " --format " + c.format + " --out " +
                           test::shellQuote((dir / "cli").string());
        if (c.detail) args += " --detail " + test::shellQuote(kNormalMap.toStdString());
        if (*c.compression) args += std::string(" --compression ") + c.compression;
        if (doc.preset().findParameter("metallic")) args += " --metallic 1";
        // The picked colour (the default document's iron, a metal) as the studio passes it.
        const LinearRgb f0 = doc.settings().specular;
        char specular[128];
        std::snprintf(specular, sizeof specular, "%.17g,%.17g,%.17g", f0.r, f0.g, f0.b);
        args += std::string(" --specular ") + specular + " --material-class metal";
        const auto cli = test::runBurnish(args);
        ASSERT_EQ(cli.exitCode, 0) << cli.err;

        const auto studio = folderBytes(dir / "studio");
        const auto reference = folderBytes(dir / "cli");
        ASSERT_FALSE(reference.empty());
        ASSERT_EQ(studio.size(), reference.size());
        for (const auto& [name, bytes] : reference) {
            ASSERT_TRUE(studio.count(name)) << name;
            if (name == "bake.json") {
                // bake.json names the output folder's files only; both record the same input path.
                EXPECT_EQ(studio.at(name), bytes) << name;
            } else {
                EXPECT_TRUE(studio.at(name) == bytes) << name << " differs";
            }
        }
    }
}

TEST(TexturePane, BakedGlossIsBakedInAWorkerPerMip) {
    MaterialDocument doc;
    TexturePane pane(&doc);
    QSignalSpy updated(&pane, &TexturePane::imageUpdated);
    pane.setMode(TextureMode::BakedGloss);
    ASSERT_TRUE(pane.baking()) << "the bake runs off the GUI thread";
    ASSERT_TRUE(updated.wait(kWorkerTimeoutMs));
    EXPECT_FALSE(pane.baking());
    EXPECT_EQ(pane.view()->image().width(), kSampleSize);
    constexpr int kMip = 3;
    pane.setMip(kMip);
    EXPECT_EQ(pane.view()->image().width(), kSampleSize >> kMip);
    EXPECT_TRUE(pane.view()->image().isGrayscale()) << "variance-to-gloss shows its gloss channel";
}

struct StudioRun {
    int exitCode = -1; // -1: did not exit normally (killed by a signal, e.g. an abort)
    std::string out;
    std::string err;
};

/// Runs the built burnish-studio with `args` and no display: DISPLAY, WAYLAND_DISPLAY and
/// QT_QPA_PLATFORM removed from its environment, as over ssh or on a CI machine.
StudioRun runStudioWithoutDisplay(const std::string& args) {
    test::TempDir dir;
    const fs::path errPath = dir / "stderr.txt";
    const std::string command = "env -u DISPLAY -u WAYLAND_DISPLAY -u QT_QPA_PLATFORM " +
                                test::shellQuote(BURNISH_STUDIO_EXE) + " " + args + " 2>" +
                                test::shellQuote(errPath.string());
    StudioRun run;
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) return run;
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0)
        run.out.append(buffer, n);
    const int status = ::pclose(pipe);
    run.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream err(errPath);
    std::stringstream ss;
    ss << err.rdbuf();
    run.err = ss.str();
    return run;
}

// Ctrl+Z in a number field undoes a committed edit of the document, as in Blender or Substance (the field
// used to swallow it for its own text history; only Edit > Undo worked), and Ctrl+Shift+Z redoes it;
// while typed text is not committed yet, the shortcut stays the field's.
TEST(StudioKeys, UndoFromANumberFieldUndoesTheDocument) {
    MainWindow window;
    window.setAutosaveDelay(0);
    window.show();
    window.activateWindow();
    ASSERT_TRUE(QTest::qWaitForWindowActive(&window));
    auto* spin = window.findChild<QDoubleSpinBox*>("materialGloss");
    ASSERT_NE(spin, nullptr);
    MaterialDocument* doc = window.document();
    const double before = doc->settings().gloss;
    spin->setFocus();
    typeInto(spin, "0.2");
    QTest::keyClick(spin, Qt::Key_Return);
    ASSERT_DOUBLE_EQ(doc->settings().gloss, 0.2);
    const int index = doc->undoStack()->index();
    QTest::keyClick(spin, Qt::Key_Z, Qt::ControlModifier);
    EXPECT_EQ(doc->undoStack()->index(), index - 1);
    EXPECT_DOUBLE_EQ(doc->settings().gloss, before);
    QTest::keyClick(spin, Qt::Key_Z, Qt::ControlModifier | Qt::ShiftModifier);
    EXPECT_EQ(doc->undoStack()->index(), index);
    EXPECT_DOUBLE_EQ(doc->settings().gloss, 0.2);
    // Mid-typing the field keeps Ctrl+Z for its text: the document is untouched.
    typeInto(spin, "0.33");
    QTest::keyClick(spin, Qt::Key_Z, Qt::ControlModifier);
    EXPECT_EQ(doc->undoStack()->index(), index);
    EXPECT_DOUBLE_EQ(doc->settings().gloss, 0.2);
}

TEST(StudioCommandLine, HelpAndVersionNeedNoDisplay) {
    const StudioRun help = runStudioWithoutDisplay("--help");
    EXPECT_EQ(help.exitCode, 0) << help.err;
    EXPECT_NE(help.out.find("Burnish Studio"), std::string::npos) << help.out;
    EXPECT_NE(help.out.find("--screenshot <FILE>"), std::string::npos) << help.out;
    EXPECT_NE(help.out.find("[PROJECT|IMAGE]"), std::string::npos) << help.out;

    const StudioRun shortHelp = runStudioWithoutDisplay("-h");
    EXPECT_EQ(shortHelp.exitCode, 0) << shortHelp.err;
    EXPECT_EQ(shortHelp.out, help.out);

    const StudioRun version = runStudioWithoutDisplay("--version");
    EXPECT_EQ(version.exitCode, 0) << version.err;
    EXPECT_EQ(version.out, std::string("burnish-studio ") + kStudioVersion + "\n");

    // A usage error is printed too, with a failing exit status, instead of a toolkit abort.
    const StudioRun unknown = runStudioWithoutDisplay("--no-such-option");
    EXPECT_GT(unknown.exitCode, 0) << unknown.err;
    EXPECT_NE(unknown.err.find("no-such-option"), std::string::npos) << unknown.err;
}

TEST(StudioCommandLine, OnlyPrintingCommandLinesAreRecognisedBeforeTheApplicationStarts) {
    auto onlyPrints = [](std::vector<const char*> args) {
        args.insert(args.begin(), "burnish-studio");
        return commandLineOnlyPrints(int(args.size()), args.data());
    };
    EXPECT_TRUE(onlyPrints({"--help"}));
    EXPECT_TRUE(onlyPrints({"project.burnish", "-v"}));
    EXPECT_TRUE(onlyPrints({"--bogus"}));
    EXPECT_FALSE(onlyPrints({}));
    EXPECT_FALSE(onlyPrints({"project.burnish"}));
    EXPECT_FALSE(onlyPrints({"--screenshot", "shot.png"}));
    EXPECT_FALSE(onlyPrints({"--", "--help"})) << "after --, a project that happens to be named so";
}

// The View menu lists every panel (a panel closed by its title bar's button can always be brought
// back), Save As has its shortcut, and Help holds the studio guide (the README's Studio section)
// and About.
TEST(MainWindow, MenusListEveryPanelSaveAsAndHelp) {
    TestWindow w;
    QMenu* view = nullptr;
    QMenu* file = nullptr;
    QMenu* help = nullptr;
    for (QAction* a : w.window.menuBar()->actions()) {
        if (a->text() == "&View") view = a->menu();
        if (a->text() == "&File") file = a->menu();
        if (a->text() == "&Help") help = a->menu();
    }
    ASSERT_TRUE(view && file && help);
    const QList<QDockWidget*> docks = w.window.findChildren<QDockWidget*>();
    EXPECT_GE(docks.size(), 5);
    for (QDockWidget* dock : docks)
        EXPECT_TRUE(view->actions().contains(dock->toggleViewAction())) << dock->windowTitle().toStdString();
    bool saveAs = false;
    for (QAction* a : file->actions())
        if (a->text().startsWith("Save &As"))
            saveAs = a->shortcut() == QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_S);
    EXPECT_TRUE(saveAs);
    QStringList helpItems;
    for (QAction* a : help->actions())
        helpItems << a->text();
    EXPECT_TRUE(helpItems.contains("Studio &Guide") && helpItems.contains("&About Burnish Studio"))
        << helpItems.join(", ").toStdString();
    // The guide is written for artists: how to open, choose, look, paint, export and recover, and
    // none of the developers' matters (environment variables, tests, build) the README's section held.
    const QString guide = studioGuideMarkdown();
    EXPECT_TRUE(guide.startsWith("# Burnish Studio Guide\n")) << guide.left(80).toStdString();
    for (const char* heading : {"\n## Your first ten minutes\n", "\n## Painting\n", "\n## Exporting\n",
                                "\n## Saving and crashes\n"})
        EXPECT_TRUE(guide.contains(heading)) << heading;
    for (const char* developers : {"BURNISH_", "ctest", "offscreen", "cmake", "test", "EGL"})
        EXPECT_FALSE(guide.contains(developers, Qt::CaseInsensitive)) << developers;
    // Every shortcut it names is one the menus have.
    QStringList shortcuts;
    for (QAction* a : w.window.findChildren<QAction*>())
        if (!a->shortcut().isEmpty()) shortcuts << a->shortcut().toString();
    for (const char* keys : {"Ctrl+O", "Ctrl+S", "Ctrl+Shift+S", "Ctrl+E", "Ctrl+Alt+G", "Ctrl+Shift+G",
                             "Ctrl+1", "Ctrl+6", "F"})
        EXPECT_TRUE(shortcuts.contains(keys)) << keys << " in the guide, not in the menus";
}

// Presets that store roughness or smoothness say so in the panel, the history and the status bar
// (the Unreal preset's panel read "Gloss"); every method has its own colour in the charts (naive
// and CLEAN were drawn alike).
TEST(MainWindow, WordsFollowThePresetsQuantity) {
    TestWindow w;
    MaterialDocument* doc = w.window.document();
    auto labelled = [&](const QString& text) {
        for (QLabel* l : w.window.materialPanel()->findChildren<QLabel*>())
            if (l->text() == text || l->text() == "<b>" + text + "</b>") return true;
        return false;
    };
    EXPECT_TRUE(labelled("Gloss"));
    for (const auto& [preset, word] : {std::pair{"unreal", "Roughness"}, std::pair{"unity", "Smoothness"},
                                       std::pair{"blackops", "Gloss"}}) {
        ASSERT_TRUE(doc->setPreset(preset));
        EXPECT_TRUE(labelled(word)) << preset;
        if (QString(word) != "Gloss") {
            EXPECT_FALSE(labelled("Gloss")) << preset << " still says gloss";
        }
        doc->setGloss(0.45);
        EXPECT_EQ(doc->undoStack()->text(doc->undoStack()->count() - 1), QString("%1 0.450").arg(word))
            << preset;
        QStringList status;
        for (QLabel* l : w.window.statusBar()->findChildren<QLabel*>())
            status << l->text();
        EXPECT_TRUE(status.join(" ").contains(QString(word).toLower() + " 0.450"))
            << status.join(" | ").toStdString();
        // The Paint panel, its History entries, the texture view and the View menu (they said
        // "Gloss", "Paint gloss", "Authored gloss" and "Baked gloss" under every preset).
        const QString lower = QString(word).toLower();
        PaintTool* tool = w.window.paintTool();
        auto* layer = tool->findChild<QComboBox*>();
        ASSERT_NE(layer, nullptr);
        EXPECT_EQ(layer->itemText(layer->findData(int(PaintLayerKind::Gloss))), QString(word)) << preset;
        tool->setPaintMode(true);
        tool->pressAt({100.0, 100.0});
        tool->moveTo({120.0, 110.0});
        tool->release();
        tool->setPaintMode(false);
        EXPECT_EQ(doc->undoStack()->text(doc->undoStack()->count() - 1), "Paint " + lower) << preset;
        QStringList modes;
        auto* modeCombo = w.window.texturePane()->findChild<QComboBox*>();
        for (int i = 0; i < modeCombo->count(); ++i)
            modes << modeCombo->itemText(i);
        EXPECT_TRUE(modes.contains("Authored " + lower) && modes.contains("Baked " + lower + " (method)"))
            << modes.join(", ").toStdString();
        QStringList viewItems;
        for (QAction* a : w.window.menuBar()->actions())
            if (a->menu() && a->text() == "&View")
                for (QAction* item : a->menu()->actions())
                    viewItems << item->text();
        EXPECT_TRUE(viewItems.contains(QString("Authored ") + word) &&
                    viewItems.contains(QString("Baked ") + word))
            << viewItems.join(", ").toStdString();
        w.window.texturePane()->setMode(TextureMode::Gloss);
        EXPECT_TRUE(w.window.texturePane()->infoText().startsWith("authored " + lower))
            << w.window.texturePane()->infoText().toStdString();
        if (lower != "gloss") {
            EXPECT_FALSE(w.window.texturePane()->infoText().contains("gloss"))
                << w.window.texturePane()->infoText().toStdString();
        }
    }
    QSet<QRgb> colours;
    for (Method m : allMethods())
        colours.insert(methodColour(m).rgb());
    EXPECT_EQ(colours.size(), qsizetype(allMethods().size()));
}

// F0 is typed as numbers, linear or 8-bit sRGB, beside the colour dialog (there was only an 8-bit
// dialog: 0.04 could not be typed). With "grey" one number sets all three channels; without it, one.
TEST(MainWindow, SpecularColourIsTypedAsNumbers) {
    TestWindow w;
    MaterialDocument* doc = w.window.document();
    MaterialPanel* panel = w.window.materialPanel();
    panel->specularGreyCheck()->setChecked(true);
    panel->specularLinearSpin(0)->setValue(0.04);
    EXPECT_EQ(doc->settings().specular, LinearRgb::grey(0.04));
    EXPECT_TRUE(doc->settings().specularName.isEmpty()) << "a typed colour is a custom one";
    EXPECT_EQ(panel->specularSrgbSpin(1)->value(), int(toSrgb8(LinearRgb::grey(0.04)).g)) << "sRGB follows";
    EXPECT_EQ(panel->specularLinearSpin(2)->value(), 0.04);

    panel->specularGreyCheck()->setChecked(false);
    panel->specularSrgbSpin(0)->setValue(255);
    EXPECT_EQ(doc->settings().specular, (LinearRgb{1.0, 0.04, 0.04}));
    panel->specularLinearSpin(2)->setValue(0.0123);
    EXPECT_DOUBLE_EQ(doc->settings().specular.b, 0.0123) << "four places kept";
    EXPECT_DOUBLE_EQ(doc->settings().specular.g, 0.04);

    // A tinted material turns "grey" off, so typing a channel never flattens it.
    ASSERT_TRUE(doc->setSpecularMaterial("gold"));
    EXPECT_FALSE(panel->specularGreyCheck()->isChecked());
    const LinearRgb gold = doc->settings().specular;
    panel->specularLinearSpin(0)->setValue(0.9);
    EXPECT_EQ(doc->settings().specular, (LinearRgb{0.9, gold.g, gold.b}));
    doc->undoStack()->undo();
    EXPECT_EQ(doc->settings().specular, gold);
    EXPECT_EQ(doc->settings().specularName, "gold");
    EXPECT_EQ(panel->specularLinearSpin(0)->value(), std::round(gold.r * 1e4) / 1e4) << "fields follow undo";
}

// A window state saved by another arrangement of the docks is not restored (one from before the
// texture view was a dock covered the viewport: no frame was ever drawn); the first layout is made
// instead. A state of this arrangement is restored.
TEST(MainWindow, AStateSavedForAnotherLayoutIsNotRestored) {
    QSettings settings;
    {
        TestWindow old;
        old.window.textureDock()->setFloating(true);
        settings.setValue("window/state", old.window.saveState()); // the old version number: 0
    }
    {
        TestWindow w;
        w.window.show();
        QApplication::processEvents();
        EXPECT_FALSE(w.window.textureDock()->isFloating()) << "the old state was restored";
        w.window.textureDock()->setFloating(true);
        w.window.close(); // saves this layout's state
    }
    {
        TestWindow w;
        EXPECT_TRUE(w.window.textureDock()->isFloating()) << "this layout's state is restored";
    }
    settings.remove("window/state");
    settings.remove("window/geometry");
}

// View ▸ Reset Layout brings every panel back, docked, where the first layout puts it (there was
// no way back from a closed or floated panel but one by one); Ctrl+Y redoes as Ctrl+Shift+Z does.
TEST(MainWindow, ResetLayoutAndCtrlYRedo) {
    TestWindow w;
    w.window.resize(1200, 700);
    w.window.show();
    QApplication::processEvents();
    const QList<QDockWidget*> docks = w.window.findChildren<QDockWidget*>();
    for (QDockWidget* dock : docks)
        dock->setFloating(true);
    w.window.textureDock()->close();
    QAction* reset = nullptr;
    for (QAction* a : w.window.menuBar()->actions())
        if (a->menu() && a->text() == "&View")
            for (QAction* item : a->menu()->actions())
                if (item->text() == "Reset &Layout") reset = item;
    ASSERT_NE(reset, nullptr);
    reset->trigger();
    QApplication::processEvents();
    for (QDockWidget* dock : docks) {
        EXPECT_FALSE(dock->isFloating()) << dock->objectName().toStdString();
        EXPECT_FALSE(dock->isHidden()) << dock->objectName().toStdString();
    }
    EXPECT_TRUE(w.window.tabifiedDockWidgets(w.window.textureDock())
                    .contains(w.window.findChild<QDockWidget*>("historyDock")))
        << "a 1200 px window's compact layout: Texture over History";

    w.window.activateWindow();
    ASSERT_TRUE(QTest::qWaitForWindowActive(&w.window));
    MaterialDocument* doc = w.window.document();
    doc->setGloss(0.25);
    doc->undoStack()->undo();
    ASSERT_NE(doc->settings().gloss, 0.25);
    QAction* redo = nullptr;
    for (QAction* a : w.window.findChildren<QAction*>())
        if (a->text().startsWith("&Redo")) redo = a;
    ASSERT_NE(redo, nullptr);
    EXPECT_TRUE(redo->shortcuts().contains(QKeySequence(Qt::CTRL | Qt::Key_Y)));
    EXPECT_TRUE(redo->shortcuts().contains(QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_Z)));
    // From a number field (the field's own Ctrl+Y would otherwise take it).
    auto* spin = w.window.findChild<QDoubleSpinBox*>("materialGloss");
    spin->setFocus();
    QTest::keyClick(spin, Qt::Key_Y, Qt::ControlModifier);
    EXPECT_EQ(doc->settings().gloss, 0.25) << "Ctrl+Y redoes from a number field";
}

TEST(MainWindow, ScreenshotIsNotBlank) {
    TestWindow w;
    w.window.resize(1200, 800);
    w.window.show();
    QApplication::processEvents();
    const QImage shot = w.window.grab().toImage();
    ASSERT_FALSE(shot.isNull());
    QSet<QRgb> colours;
    for (int y = 0; y < shot.height(); y += 4)
        for (int x = 0; x < shot.width(); x += 4)
            colours.insert(shot.pixel(x, y));
    // Panels, text and the normal map give hundreds of colours; a blank or failed grab gives one.
    constexpr int kMinDistinctColours = 50;
    EXPECT_GE(colours.size(), kMinDistinctColours);
}

} // namespace
} // namespace burnish::studio

int main(int argc, char** argv) {
    if (qEnvironmentVariableIsEmpty("QT_QPA_PLATFORM")) qputenv("QT_QPA_PLATFORM", "offscreen");
    QApplication app(argc, argv);
    burnish::studio::setUpApplication(app);
    // Settings and autosave copies go to test locations, never the user's.
    QStandardPaths::setTestModeEnabled(true);
    QSettings().clear();
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
