// burnish_studio_latency MAP [--repeats N] [--width W --height H]: how long the studio makes an
// artist wait, measured as the artist sees it. The whole main window runs as the studio runs it
// (background loads and bakes, the texture pane beside the viewport), on the platform Qt is given
// (offscreen for a figure without a display). For one map it prints, in milliseconds:
//   - load: from asking for the map (Load…, a drop) to the first frame that draws its bake;
//   - method: from a method change to the first frame that draws the new method;
//   - gloss: from a base-gloss change to the first frame that draws it (median of N changes);
//   - landing frame: the viewport frame that takes a bake in (its upload included);
//   - Paint switched on: how long the GUI thread is held, and until the paint tool's live bake (built on a
//     worker) is ready;
//   - a stroke painted on the texture view (a gloss stroke of 24 dabs across the map, one dab
//     per 16 ms as a mouse sends them): to 2D, from the first dab to the texture view's first paint
//     after it; to 3D, from the first dab to the first viewport frame drawing the stroke with no bake
//     pending; after release, from the stroke's end to the frame that draws all of it; and the longest
//     the GUI thread did not answer (gap between 1 ms timer ticks) from the first dab to that frame;
// and the peak resident memory of the process (after the stroke). Figures, not a pass/fail test:
// core/bench/studio_latency.sh runs it on a real map at several sizes.
#include "main_window.h"
#include "material_document.h"
#include "paint_tool.h"
#include "texture_pane.h"
#include "texture_view.h"
#include "viewport.h"

#include <QApplication>
#include <QCommandLineParser>
#include <QElapsedTimer>
#include <QSurfaceFormat>
#include <QTimer>

#include <algorithm>
#include <cstdio>
#include <sys/resource.h>
#include <vector>

namespace {

using burnish::Method;
using burnish::studio::MainWindow;
using burnish::studio::MapSlot;
using burnish::studio::MaterialDocument;
using burnish::studio::Viewport;

constexpr qint64 kTimeoutMs = 600000;

struct Landing {
    double ms = -1.0;     // request to the first frame without a bake pending; < 0: timed out
    double frameMs = 0.0; // that frame's own time
};

// Runs the event loop from `request` (false: it was refused) until the viewport draws a frame with no bake
// pending once `applied` holds (the frame that takes the requested bake in, or one drawn at once when nothing
// had to be baked).
template <typename Request, typename Applied>
Landing timeUntilDrawn(Viewport& view, Request request, Applied applied) {
    bool landed = false;
    Landing result;
    QElapsedTimer clock;
    const auto connection = QObject::connect(&view, &Viewport::frameRendered, [&](double frameMs) {
        if (landed || view.bakingShown() || !applied()) return;
        landed = true;
        result.ms = double(clock.nsecsElapsed()) / 1e6;
        result.frameMs = frameMs;
    });
    clock.start();
    const bool asked = request();
    while (asked && !landed && clock.elapsed() < kTimeoutMs)
        QCoreApplication::processEvents(QEventLoop::AllEvents, 5);
    QObject::disconnect(connection);
    return result;
}

template <typename Request> Landing timeUntilDrawn(Viewport& view, Request request) {
    return timeUntilDrawn(view, request, [] { return true; });
}

// Asks the viewport for a frame: its picture is drawn by a child surface, which the view's own
// update() does not repaint.
void redraw(Viewport& view) {
    view.update();
    for (QWidget* w : view.findChildren<QWidget*>())
        w->update();
}

struct StrokeFigures {
    double paintOnMs = 0.0, liveReadyMs = 0.0, to2d = -1.0, to3d = -1.0, afterRelease = -1.0,
           longestStall = 0.0;
};

// Records when a widget starts painting.
class PaintSpy : public QObject {
public:
    QElapsedTimer* clock = nullptr;
    double firstPaintMs = -1.0;
    bool armed = false;

protected:
    bool eventFilter(QObject* watched, QEvent* event) override {
        if (armed && event->type() == QEvent::Paint && firstPaintMs < 0.0)
            firstPaintMs = double(clock->nsecsElapsed()) / 1e6;
        return QObject::eventFilter(watched, event);
    }
};

// Paints one gloss stroke across the middle of the map as a mouse would (a dab every 16 ms) and times
// what the artist sees.
StrokeFigures timeStroke(MainWindow& window, Viewport& view, int width, int height) {
    StrokeFigures f;
    constexpr int kDabs = 24;
    constexpr int kDabIntervalMs = 16;
    burnish::studio::PaintTool& tool = *window.paintTool();
    QElapsedTimer paintOn;
    paintOn.start();
    tool.setPaintMode(true); // the live bake starts building, on a worker
    f.paintOnMs = double(paintOn.nsecsElapsed()) / 1e6;
    while (tool.liveBuilding() && paintOn.elapsed() < kTimeoutMs)
        QCoreApplication::processEvents(QEventLoop::AllEvents, 5);
    f.liveReadyMs = double(paintOn.nsecsElapsed()) / 1e6;
    burnish::Brush brush = tool.brush();
    brush.radius = std::max(16.0, width / 128.0);
    brush.value = 0.95f;
    tool.setBrush(brush);
    // Settle: paint mode's live bake and a frame drawn before the clock starts.
    (void)timeUntilDrawn(view, [&] {
        redraw(view);
        return true;
    });
    QWidget* canvas = window.texturePane()->view();
    QElapsedTimer clock;
    PaintSpy spy;
    spy.clock = &clock;
    canvas->installEventFilter(&spy);
    double lastTick = 0.0;
    QTimer ticker;
    ticker.setInterval(1);
    QObject::connect(&ticker, &QTimer::timeout, [&] {
        const double now = double(clock.nsecsElapsed()) / 1e6;
        f.longestStall = std::max(f.longestStall, now - lastTick);
        lastTick = now;
    });
    bool released = false;
    double releaseMs = 0.0;
    const auto frame = QObject::connect(&view, &Viewport::frameRendered, [&](double) {
        if (view.bakingShown()) return;
        const double now = double(clock.nsecsElapsed()) / 1e6;
        if (f.to3d < 0.0) f.to3d = now;
        if (released && f.afterRelease < 0.0) f.afterRelease = now - releaseMs;
    });
    auto runFor = [&](double ms) {
        const double until = double(clock.nsecsElapsed()) / 1e6 + ms;
        while (double(clock.nsecsElapsed()) / 1e6 < until)
            QCoreApplication::processEvents(QEventLoop::AllEvents, 1);
    };
    clock.start();
    ticker.start();
    spy.armed = true;
    const double y = height * 0.5;
    tool.pressAt(QPointF(width * 0.25, y));
    for (int i = 1; i <= kDabs; ++i) {
        runFor(kDabIntervalMs);
        tool.moveTo(QPointF(width * (0.25 + 0.5 * i / kDabs), y));
    }
    runFor(kDabIntervalMs);
    tool.release();
    releaseMs = double(clock.nsecsElapsed()) / 1e6;
    released = true;
    while (f.afterRelease < 0.0 && clock.elapsed() < kTimeoutMs)
        QCoreApplication::processEvents(QEventLoop::AllEvents, 1);
    runFor(50.0); // the ticker's next tick: the landing frame's own time counts as a stall too
    QObject::disconnect(frame);
    f.to2d = spy.firstPaintMs;
    canvas->removeEventFilter(&spy);
    return f;
}

double peakResidentMb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0;
}

} // namespace

int main(int argc, char** argv) {
    QSurfaceFormat format = QSurfaceFormat::defaultFormat();
    format.setVersion(3, 3);
    format.setProfile(QSurfaceFormat::CoreProfile);
    QSurfaceFormat::setDefaultFormat(format);
    QApplication app(argc, argv);
    QCommandLineParser parser;
    parser.setApplicationDescription("The studio's latencies for one normal map.");
    parser.addHelpOption();
    parser.addPositionalArgument("map", "the normal map to load");
    const QCommandLineOption repeatsOption("repeats", "gloss changes timed (median)", "N", "5");
    const QCommandLineOption widthOption("width", "window width", "W", "1920");
    const QCommandLineOption heightOption("height", "window height", "H", "1080");
    const QCommandLineOption presetOption("preset", "the material's preset (its default method paints)", "P",
                                          "blackops");
    parser.addOptions({repeatsOption, widthOption, heightOption, presetOption});
    parser.process(app);
    if (parser.positionalArguments().size() != 1) parser.showHelp(2);
    const QString map = parser.positionalArguments().first();
    const int repeats = std::max(1, parser.value(repeatsOption).toInt());

    MainWindow window;
    window.showMessage = [](const QString&, const QString& text) {
        std::fprintf(stderr, "burnish_studio_latency: %s\n", qPrintable(text));
    };
    window.ask = [](const QString&, const QString&, QMessageBox::StandardButtons) {
        return QMessageBox::Discard;
    };
    window.setBackgroundLoads(true);
    window.resize(parser.value(widthOption).toInt(), parser.value(heightOption).toInt());
    window.show();
    auto* view = window.findChild<Viewport*>();
    if (!view) {
        std::fprintf(stderr, "burnish_studio_latency: the window has no viewport\n");
        return 1;
    }
    MaterialDocument& doc = *window.document();
    // The sample's first frame, so the load below starts from a settled window.
    if (timeUntilDrawn(*view, [&] {
            redraw(*view);
            return true;
        }).ms < 0.0)
        return 1;

    if (const auto set = doc.setPreset(parser.value(presetOption)); !set) {
        std::fprintf(stderr, "burnish_studio_latency: %s\n", set.error().c_str());
        return 2;
    }
    const Landing load = timeUntilDrawn(
        *view, [&] { return window.openFile(map); }, [&] { return doc.settings().normalMapPath == map; });
    if (load.ms < 0.0 || doc.settings().normalMapPath != map) {
        std::fprintf(stderr, "burnish_studio_latency: %s was not drawn\n", qPrintable(map));
        return 1;
    }
    const auto& normal = *doc.maps().normal;

    // A method change: to LEAN, or to the preset's default when it is already LEAN.
    const std::vector<Method> methods = doc.availableMethods();
    // A change to a method that bakes from the moments (LEAN where the preset stores it): the fitted lobe
    // and the mixture fit per texel, which is the bake's time, not the studio's.
    Method other = doc.settings().method;
    for (const Method m : methods)
        if (m != doc.settings().method && m != Method::Fitted && m != Method::Mixture &&
            (other == doc.settings().method || m == Method::Lean))
            other = m;
    const Landing method = timeUntilDrawn(*view, [&] { return bool(doc.setMethod(other)); });
    std::fprintf(stderr, "burnish_studio_latency: method %s -> %s, preset %s\n",
                 std::string(burnish::methodName(doc.preset().method)).c_str(),
                 std::string(burnish::methodName(other)).c_str(), qPrintable(doc.settings().preset));

    std::vector<Landing> gloss;
    for (int i = 0; i < repeats; ++i) {
        const double value = 0.3 + 0.5 * double(i % 2); // alternates, so each is a change
        gloss.push_back(timeUntilDrawn(*view, [&] {
            doc.setGloss(value);
            return true;
        }));
    }
    std::sort(gloss.begin(), gloss.end(), [](const Landing& a, const Landing& b) { return a.ms < b.ms; });
    const Landing median = gloss[gloss.size() / 2];
    if (method.ms < 0.0 || median.ms < 0.0) {
        std::fprintf(stderr, "burnish_studio_latency: a change was not drawn in %lld s\n",
                     static_cast<long long>(kTimeoutMs / 1000));
        return 1;
    }
    const double peakBeforeStroke = peakResidentMb();
    // The stroke under the preset's own method (the method change above may have left a slow one).
    if (doc.settings().method != doc.preset().method &&
        timeUntilDrawn(*view, [&] { return bool(doc.setMethod(doc.preset().method)); }).ms < 0.0)
        return 1;
    const StrokeFigures stroke = timeStroke(window, *view, normal.width, normal.height);
    if (stroke.afterRelease < 0.0) {
        std::fprintf(stderr, "burnish_studio_latency: the stroke was not drawn in %lld s\n",
                     static_cast<long long>(kTimeoutMs / 1000));
        return 1;
    }
    std::printf("| %d×%d | %.0f | %.0f | %.0f (%.0f–%.0f) | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | "
                "%.0f | %.0f |\n",
                normal.width, normal.height, load.ms, method.ms, median.ms, gloss.front().ms, gloss.back().ms,
                median.frameMs, peakBeforeStroke, stroke.paintOnMs, stroke.liveReadyMs, stroke.to2d,
                stroke.to3d, stroke.afterRelease, stroke.longestStall, peakResidentMb());
    return 0;
}
