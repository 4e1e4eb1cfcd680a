// The main window fits every screen from 1280×720 up: at 1280×720, 1366×768 and 1920×1080 the
// window lies inside the screen (a geometry saved on a larger screen included), no widget is outside
// the window or squeezed below the size its text needs, and laid-out siblings do not overlap. Each
// size runs in a child process whose offscreen screen has that size (the platform's configfile);
// the screenshots are left beside the test binary as layout-WxH.png for a person to look at.
#include "elided_label.h"
#include "flow_layout.h"
#include "main_window.h"
#include "viewport.h"
#include "viewport_panel.h"

#include "temp_dir.h"

#include <gtest/gtest.h>

#include <QAbstractButton>
#include <QAbstractScrollArea>
#include <QApplication>
#include <QComboBox>
#include <QDockWidget>
#include <QFile>
#include <QLabel>
#include <QLayout>
#include <QProcess>
#include <QPushButton>
#include <QScreen>
#include <QSet>
#include <QSettings>
#include <QSplitter>
#include <QTest>
#include <QVBoxLayout>

#include <string>

namespace burnish::studio {
namespace {

// The child's instructions: "W H SHOT" (screen size and where to save the screenshot).
constexpr const char* kLayoutEnv = "BURNISH_LAYOUT_SCREEN";

// Widgets not on show by design: inside a scroll area's viewport (scrolled into view on demand), or
// in a dock that is a tab behind another (Qt moves it out of the window).
bool outOfViewByDesign(const QWidget* w, const QMainWindow& window) {
    for (const QWidget* p = w; p && p != &window; p = p->parentWidget()) {
        if (auto* area = qobject_cast<const QAbstractScrollArea*>(p->parentWidget());
            area && area->viewport() == p)
            return true;
        if (auto* dock = qobject_cast<const QDockWidget*>(p);
            dock && !window.tabifiedDockWidgets(const_cast<QDockWidget*>(dock)).isEmpty() &&
            !dock->geometry().intersects(window.rect()))
            return true;
    }
    return false;
}

/// The visible widgets a layout places, through its nested layouts.
void collectPlaced(QLayout* layout, QList<QWidget*>& placed) {
    for (int i = 0; i < layout->count(); ++i) {
        QLayoutItem* item = layout->itemAt(i);
        if (QWidget* c = item->widget(); c && c->isVisible()) placed << c;
        if (QLayout* nested = item->layout()) collectPlaced(nested, placed);
    }
}

/// What is wrong with the window's layout, one line each (empty when it fits).
QStringList layoutProblems(QMainWindow& window, const QRect& screen) {
    QStringList problems;
    if (!screen.contains(window.frameGeometry()))
        problems << QString("window %1,%2 %3x%4 is not inside the screen %5x%6")
                        .arg(window.frameGeometry().x())
                        .arg(window.frameGeometry().y())
                        .arg(window.frameGeometry().width())
                        .arg(window.frameGeometry().height())
                        .arg(screen.width())
                        .arg(screen.height());
    const QRect inside = window.rect();
    for (QWidget* w : window.findChildren<QWidget*>()) {
        if (!w->isVisible() || w->isWindow() || outOfViewByDesign(w, window)) continue;
        const QString name =
            QString("%1 '%2' (%3)")
                .arg(w->metaObject()->className(), w->objectName(),
                     qobject_cast<QLabel*>(w)            ? qobject_cast<QLabel*>(w)->text()
                     : qobject_cast<QAbstractButton*>(w) ? qobject_cast<QAbstractButton*>(w)->text()
                                                         : QString());
        const QRect r(w->mapTo(&window, QPoint(0, 0)), w->size());
        if (!inside.contains(r))
            problems << QString("%1 at %2,%3 %4x%5 is outside the window")
                            .arg(name)
                            .arg(r.x())
                            .arg(r.y())
                            .arg(r.width())
                            .arg(r.height());
        // Text cut short: a label, button or combo narrower or lower than its own minimum.
        // (Qt's own dock title buttons are drawn smaller than their hint by Qt itself.)
        const bool qtTitleButton = w->objectName().startsWith("qt_dockwidget_");
        if (!qtTitleButton &&
            (qobject_cast<QLabel*>(w) || qobject_cast<QAbstractButton*>(w) || qobject_cast<QComboBox*>(w))) {
            const QSize least = w->minimumSizeHint();
            const bool wraps = qobject_cast<QLabel*>(w) && qobject_cast<QLabel*>(w)->wordWrap();
            if ((!wraps && w->width() < least.width()) || w->height() < least.height())
                problems << QString("%1 is %2x%3, below its minimum %4x%5")
                                .arg(name)
                                .arg(w->width())
                                .arg(w->height())
                                .arg(least.width())
                                .arg(least.height());
        }
        // Siblings one layout places, its nested layouts included, must not overlap (the viewport
        // over its control rows, which a nested flow layout places, did).
        if (QLayout* layout = w->layout()) {
            QList<QWidget*> placed;
            collectPlaced(layout, placed);
            for (int i = 0; i < placed.size(); ++i)
                for (int j = i + 1; j < placed.size(); ++j)
                    if (placed[i]->geometry().intersects(placed[j]->geometry()))
                        problems << QString("%1 and %2 overlap in %3")
                                        .arg(placed[i]->metaObject()->className(),
                                             placed[j]->metaObject()->className(), name);
        }
    }
    return problems;
}

/// Shows the window and lets the first layout (and the default dock sizes after it) settle.
void settle(QMainWindow& window) {
    window.show();
    for (int i = 0; i < 5; ++i) {
        QApplication::processEvents();
        QTest::qWait(20);
    }
}

// The child's test: registered only in a child process started with kLayoutEnv set, so ctest lists
// it once, as the parent Layout.FitsEveryScreenFrom1280x720Up.
class LayoutOnScreen : public ::testing::Test {
public:
    void TestBody() override {
        const QStringList args = qEnvironmentVariable(kLayoutEnv).split(' ');
        ASSERT_EQ(args.size(), 3) << kLayoutEnv << ": want 'WIDTH HEIGHT SHOT'";
        const QSize size(args[0].toInt(), args[1].toInt());
        const QScreen* screen = QGuiApplication::primaryScreen();
        ASSERT_EQ(screen->geometry().size(), size) << "the offscreen platform's configfile was not applied";
        const QRect available = screen->availableGeometry();

        {
            // First launch: no saved geometry.
            MainWindow window;
            window.setAutosaveDelay(0);
            settle(window);
            const QStringList problems = layoutProblems(window, available);
            EXPECT_TRUE(problems.isEmpty()) << problems.join("\n").toStdString();
            const QImage shot = window.grab().toImage();
            QSet<QRgb> colours;
            for (int y = 0; y < shot.height(); y += 4)
                for (int x = 0; x < shot.width(); x += 4)
                    colours.insert(shot.pixel(x, y));
            EXPECT_GE(colours.size(), 50) << "the window drew nothing";
            EXPECT_TRUE(shot.save(args[2]));
            // On a small screen the 3D picture (not its control rows) gets at least half the window
            // by default; at 1280×720 it had 550×210 pixels under the charts' half.
            if (size.height() <= 768) {
                auto* panel = window.findChild<ViewportPanel*>();
                ASSERT_NE(panel, nullptr);
                const QSize picture = panel->viewport()->size();
                const double share =
                    double(picture.width()) * picture.height() / (double(window.width()) * window.height());
                EXPECT_GE(share, 0.5) << "the 3D view is " << picture.width() << "x" << picture.height()
                                      << " of a " << window.width() << "x" << window.height() << " window";
            }
        }
        {
            // A geometry saved on a 2560×1440 screen by a window wider than this screen (the old
            // layout's 1995 px) is clamped to this one on the next launch.
            MainWindow wide;
            wide.setAutosaveDelay(0);
            wide.setGeometry(400, 200, 1995, 1300);
            QSettings().setValue("window/geometry", wide.saveGeometry());
        }
        MainWindow window;
        window.setAutosaveDelay(0);
        settle(window);
        const QStringList problems = layoutProblems(window, available);
        EXPECT_TRUE(problems.isEmpty()) << problems.join("\n").toStdString();
        QSettings().remove("window/geometry");
    }
};

[[maybe_unused]] const bool kLayoutChildRegistered = [] {
    if (qEnvironmentVariableIsEmpty(kLayoutEnv)) return false;
    ::testing::RegisterTest("LayoutOnScreen", "WindowAndEveryWidgetFit", nullptr, nullptr, __FILE__, __LINE__,
                            []() -> ::testing::Test* { return new LayoutOnScreen; });
    return true;
}();

TEST(Layout, FitsEveryScreenFrom1280x720Up) {
    test::TempDir dir;
    for (const QSize size : {QSize(1280, 720), QSize(1366, 768), QSize(1920, 1080)}) {
        const QString tag = QString("%1x%2").arg(size.width()).arg(size.height());
        const QString config =
            QString::fromStdString((dir / ("screen-" + tag.toStdString() + ".json")).string());
        QFile file(config);
        ASSERT_TRUE(file.open(QIODevice::WriteOnly));
        file.write(QString(R"({"screens": [{"name": "screen", "x": 0, "y": 0, "width": %1, "height": %2,
                              "logicalDpiX": 96, "logicalDpiY": 96, "dpr": 1}]})")
                       .arg(size.width())
                       .arg(size.height())
                       .toUtf8());
        file.close();
        const QString shot = QString("layout-%1.png").arg(tag);
        QFile::remove(shot);
        QProcess child;
        QProcessEnvironment env = QProcessEnvironment::systemEnvironment();
        env.insert("QT_QPA_PLATFORM", "offscreen:configfile=" + config);
        // Its own settings (the saved geometry it plants), not those of tests running beside it.
        env.insert("HOME", QString::fromStdString(dir.path().string()));
        env.insert(kLayoutEnv, QString("%1 %2 %3").arg(size.width()).arg(size.height()).arg(shot));
        child.setProcessEnvironment(env);
        child.setProcessChannelMode(QProcess::MergedChannels);
        child.start(QCoreApplication::applicationFilePath(),
                    {"--gtest_filter=LayoutOnScreen.WindowAndEveryWidgetFit"});
        ASSERT_TRUE(child.waitForFinished(120000)) << tag.toStdString();
        const QString output = QString::fromUtf8(child.readAll());
        EXPECT_EQ(child.exitCode(), 0) << tag.toStdString() << "\n" << output.toStdString();
        EXPECT_TRUE(output.contains("[  PASSED  ] 1 test")) << output.toStdString();
        EXPECT_TRUE(QImage(shot).size().isValid()) << "no screenshot at " << shot.toStdString();
    }
}

// The layout check catches what it was written for: a flow layout's rows squeezed into less
// height than they need, under the widget laid out after them.
TEST(Layout, TheCheckFindsControlRowsUnderTheView) {
    QMainWindow window;
    auto* central = new QWidget;
    auto* column = new QVBoxLayout(central);
    auto* flow = new FlowLayout;
    for (int i = 0; i < 8; ++i)
        flow->addWidget(new QPushButton(QString("control %1").arg(i)));
    column->addLayout(flow);
    auto* view = new QWidget;
    view->setMinimumSize(40, 40);
    column->addWidget(view, 1);
    window.setCentralWidget(central);
    window.show();
    window.resize(140, 140); // eight rows of buttons need more than this
    QApplication::processEvents();
    const QStringList problems = layoutProblems(window, QRect(-10000, -10000, 20000, 20000));
    EXPECT_TRUE(problems.join("\n").contains("overlap")) << problems.join("\n").toStdString();
}

// The viewport panel's control rows keep their height when a neighbour takes the room: in a
// vertical splitter under a tall panel, narrowed so its controls wrap onto several rows, the panel's
// minimum height follows its width and nothing overlaps the view.
TEST(Layout, ViewportControlRowsAreNeverSqueezedUnderTheView) {
    MaterialDocument doc;
    QMainWindow window;
    auto* splitter = new QSplitter(Qt::Vertical);
    auto* panel = new ViewportPanel(&doc);
    splitter->addWidget(panel);
    auto* tall = new QWidget;
    tall->setMinimumHeight(100);
    splitter->addWidget(tall);
    window.setCentralWidget(splitter);
    window.show();
    window.resize(360, 700);
    splitter->setSizes({10, 690}); // the user drags the neighbour as tall as it goes
    QApplication::processEvents();
    const int rows = panel->controlsHeightForWidth(panel->width());
    EXPECT_GT(rows, 3 * 20) << "at 360 px the controls wrap onto several rows";
    EXPECT_GE(panel->height(), rows + panel->viewport()->minimumHeight());
    const QStringList problems = layoutProblems(window, QRect(-10000, -10000, 20000, 20000));
    EXPECT_FALSE(problems.join("\n").contains("overlap")) << problems.join("\n").toStdString();
}

TEST(Layout, FitInsideMovesAndShrinksAsLittleAsItTakes) {
    const QRect screen(0, 0, 1280, 720);
    EXPECT_EQ(fitInside(QRect(100, 50, 800, 600), screen), QRect(100, 50, 800, 600)) << "inside: unchanged";
    EXPECT_EQ(fitInside(QRect(900, 50, 800, 600), screen), QRect(480, 50, 800, 600)) << "moved left";
    EXPECT_EQ(fitInside(QRect(-40, -10, 800, 600), screen), QRect(0, 0, 800, 600)) << "moved on screen";
    EXPECT_EQ(fitInside(QRect(400, 200, 1995, 1300), screen), screen) << "shrunk to the screen";
    const QRect second(1280, 0, 1920, 1080); // a second screen to the right
    EXPECT_EQ(fitInside(QRect(1300, 100, 2500, 900), second), QRect(1280, 100, 1920, 900));
}

TEST(FlowLayout, WrapsItemsOntoRowsAndReportsTheHeight) {
    QWidget box;
    auto* flow = new FlowLayout(&box, 6, 2);
    flow->setContentsMargins(0, 0, 0, 0);
    QList<QWidget*> items;
    for (int i = 0; i < 4; ++i) {
        auto* w = new QWidget;
        w->setFixedSize(100, 20);
        flow->addWidget(w);
        items << w;
    }
    EXPECT_EQ(flow->heightForWidth(430), 20) << "4 × 100 + 3 × 6 = 418: one row";
    EXPECT_EQ(flow->heightForWidth(300), 42) << "two rows of two";
    EXPECT_EQ(flow->heightForWidth(100), 4 * 20 + 3 * 2) << "one item a row";
    EXPECT_EQ(flow->minimumSize(), QSize(100, 20)) << "as narrow as the widest item";
    flow->setGeometry(QRect(0, 0, 300, 42));
    EXPECT_EQ(items[0]->geometry(), QRect(0, 0, 100, 20));
    EXPECT_EQ(items[1]->geometry(), QRect(106, 0, 100, 20));
    EXPECT_EQ(items[2]->geometry(), QRect(0, 22, 100, 20));
    EXPECT_EQ(items[3]->geometry(), QRect(106, 22, 100, 20));
}

TEST(ElidedLabel, CutsLongTextWithAnEllipsisAndKeepsItInTheTooltip) {
    ElidedLabel label;
    const QString text = "normal map 8192×8192 · 16-bit PNG · tangent space, OpenGL (+Y) green";
    label.setText(text);
    EXPECT_EQ(label.toolTip(), text);
    EXPECT_LT(label.minimumSizeHint().width(), label.sizeHint().width()) << "it never widens its window";
    label.resize(label.sizeHint());
    EXPECT_EQ(label.shownText().toStdString(), text.toStdString());
    label.resize(80, label.sizeHint().height());
    EXPECT_TRUE(label.shownText().endsWith(QChar(0x2026))) << label.shownText().toStdString();
    EXPECT_LT(label.shownText().size(), text.size());
}

} // namespace
} // namespace burnish::studio
