// Painting in the studio: strokes on the texture view, undo/redo, the eyedropper, and the layers
// saved beside a project and loaded back. main() is test_studio.cpp's (one QApplication).
#include "main_window.h"
#include "material_document.h"
#include "paint_tool.h"
#include "project.h"
#include "texture_pane.h"
#include "texture_view.h"

#include "temp_dir.h"

#include <gtest/gtest.h>

#include <QApplication>
#include <QTest>

#include <cstring>

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

} // namespace

TEST(StudioPaint, StrokeOnTheViewChangesTheLayerAndUndoRestoresIt) {
    MainWindow window;
    window.setAutosaveInterval(0);
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

    doc->undoStack()->undo();
    EXPECT_TRUE(sameBits(doc->paintLayer(PaintLayerKind::Gloss).value, before.value));
    EXPECT_TRUE(sameBits(doc->paintLayer(PaintLayerKind::Gloss).coverage, before.coverage));
    EXPECT_FALSE(doc->authoredGloss()); // nothing painted, no gloss map: the base power again
    doc->undoStack()->redo();
    EXPECT_TRUE(sameBits(doc->paintLayer(PaintLayerKind::Gloss).value, painted.value));
    EXPECT_TRUE(sameBits(doc->paintLayer(PaintLayerKind::Gloss).coverage, painted.coverage));

    // The eyedropper reads the painted gloss under the stroke's middle.
    const QPointF middle = view->texelAt(QPointF(view->width() / 2.0, view->height() / 2.0));
    tool->setEyedropper(true);
    tool->pressAt(middle);
    EXPECT_FALSE(tool->eyedropper()); // one pick, then back to the brush
    EXPECT_NEAR(tool->brush().value, 0.95f, kGlossTol);
    EXPECT_NEAR(tool->pickAt(middle), 0.95f, kGlossTol);
    tool->setPaintMode(false);
}

TEST(StudioPaint, LayersSurviveASaveAndLoad) {
    test::TempDir dir;
    const QString file = QString::fromStdString((dir.path() / "painted.burnish").string());
    MainWindow window;
    window.setAutosaveInterval(0);
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
    EXPECT_TRUE(QFileInfo::exists(layerPathFor(file, PaintLayerKind::Gloss)));
    EXPECT_TRUE(QFileInfo::exists(layerPathFor(file, PaintLayerKind::VarianceOffset)));

    MainWindow other;
    other.setAutosaveInterval(0);
    other.showMessage = [](const QString&, const QString& text) { ADD_FAILURE() << text.toStdString(); };
    ASSERT_TRUE(other.openProject(file));
    const MaterialDocument* loaded = other.document();
    EXPECT_TRUE(sameBits(loaded->paintLayer(PaintLayerKind::Gloss).value, gloss.value));
    EXPECT_TRUE(sameBits(loaded->paintLayer(PaintLayerKind::Gloss).coverage, gloss.coverage));
    EXPECT_TRUE(sameBits(loaded->paintLayer(PaintLayerKind::VarianceOffset).value, offset.value));
    EXPECT_TRUE(sameBits(loaded->paintLayer(PaintLayerKind::VarianceOffset).coverage, offset.coverage));
    ASSERT_TRUE(loaded->authoredGloss());
    EXPECT_TRUE(sameBits(*loaded->authoredGloss(), authored));

    // A project naming a missing layer file loads nothing half-way.
    QFile::remove(layerPathFor(file, PaintLayerKind::Gloss));
    MainWindow third;
    third.setAutosaveInterval(0);
    QString message;
    third.showMessage = [&](const QString&, const QString& text) { message = text; };
    EXPECT_FALSE(third.openProject(file));
    EXPECT_TRUE(message.contains("gloss.exr")) << message.toStdString();
    EXPECT_FALSE(third.document()->paintLayer(PaintLayerKind::VarianceOffset).painted());
}
