// burnish-studio [PROJECT|IMAGE]: the material-authoring studio. Opens PROJECT, or the built-in
// sample with IMAGE as its normal map, or the built-in sample.
// --screenshot FILE renders the main window once the UI has settled, saves it and exits (CI).
// --help and --version print without a display.
#include "main_window.h"
#include "studio_app.h"
#include "texture_pane.h"

#include <QApplication>
#include <QCommandLineParser>
#include <QSurfaceFormat>
#include <QTimer>

#include <cstdio>

int main(int argc, char** argv) {
    // The window toolkit connects to the display when QApplication starts, before the command line
    // is parsed: a command line that only prints (help, version, a usage error) runs on the
    // offscreen platform, so it works over ssh and in CI.
    if (burnish::studio::commandLineOnlyPrints(argc, argv)) qputenv("QT_QPA_PLATFORM", "offscreen");
    // The 3D viewport's renderer needs OpenGL 3.3 core; every QOpenGLWidget of a window shares one
    // format, so it is set for the whole application before it starts.
    QSurfaceFormat format = QSurfaceFormat::defaultFormat();
    format.setVersion(3, 3);
    format.setProfile(QSurfaceFormat::CoreProfile);
    QSurfaceFormat::setDefaultFormat(format);
    QApplication app(argc, argv);
    burnish::studio::setUpApplication(app);

    QCommandLineParser parser;
    burnish::studio::addStudioOptions(parser);
    parser.process(app);
    if (parser.positionalArguments().size() > 1) {
        std::fprintf(stderr, "burnish-studio: give at most one project or image\n");
        return 2;
    }

    burnish::studio::MainWindow window;
    const bool shooting = parser.isSet(burnish::studio::kScreenshotOption);
    // A big map decodes off the GUI thread; a screenshot waits for its map instead.
    window.setBackgroundLoads(!shooting);
    if (!parser.positionalArguments().isEmpty()) {
        if (shooting) {
            window.showMessage = [](const QString&, const QString& text) {
                std::fprintf(stderr, "burnish-studio: %s\n", qPrintable(text));
            };
        }
        if (!window.openFile(parser.positionalArguments().first()) && shooting) return 1;
    }
    window.show();
    if (shooting) {
        const QString file = parser.value(burnish::studio::kScreenshotOption);
        // Let layouts, docks and the first paint settle before grabbing.
        QTimer::singleShot(500, &window, [&window, file] {
            const bool ok = window.grab().save(file);
            if (!ok)
                std::fprintf(stderr, "burnish-studio: cannot write the screenshot '%s'\n", qPrintable(file));
            QApplication::exit(ok ? 0 : 1);
        });
    } else {
        // Work a crashed or killed studio left behind (projects and untitled alike) is offered now.
        const QString opened = parser.positionalArguments().value(0);
        QTimer::singleShot(0, &window, [&window, opened] { window.offerRecoveryAtLaunch(opened); });
    }
    return app.exec();
}
