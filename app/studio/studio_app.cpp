#include "studio_app.h"

#include <QApplication>
#include <QCommandLineParser>
#include <QPalette>
#include <QStringList>
#include <QStyleFactory>

namespace burnish::studio {

void setUpApplication(QApplication& app) {
    QApplication::setOrganizationName("Burnish");
    QApplication::setApplicationName("burnish-studio");
    QApplication::setApplicationVersion(kStudioVersion);
    app.setStyle(QStyleFactory::create("Fusion"));
    // A dark neutral palette, so colours and greys in the views are judged against grey, not white.
    QPalette p;
    const QColor window(45, 45, 48);
    const QColor base(30, 30, 32);
    const QColor text(220, 220, 220);
    const QColor highlight(74, 130, 200);
    p.setColor(QPalette::Window, window);
    p.setColor(QPalette::WindowText, text);
    p.setColor(QPalette::Base, base);
    p.setColor(QPalette::AlternateBase, window);
    p.setColor(QPalette::ToolTipBase, base);
    p.setColor(QPalette::ToolTipText, text);
    p.setColor(QPalette::Text, text);
    p.setColor(QPalette::Button, QColor(58, 58, 62));
    p.setColor(QPalette::ButtonText, text);
    p.setColor(QPalette::BrightText, Qt::white);
    p.setColor(QPalette::Highlight, highlight);
    p.setColor(QPalette::HighlightedText, Qt::white);
    p.setColor(QPalette::Link, highlight.lighter(130));
    p.setColor(QPalette::Mid, QColor(120, 120, 125));
    p.setColor(QPalette::Disabled, QPalette::Text, QColor(120, 120, 120));
    p.setColor(QPalette::Disabled, QPalette::ButtonText, QColor(120, 120, 120));
    p.setColor(QPalette::Disabled, QPalette::WindowText, QColor(120, 120, 120));
    app.setPalette(p);
}

void addStudioOptions(QCommandLineParser& parser) {
    parser.setApplicationDescription("Burnish Studio: specular colour and gloss authoring with normal-map "
                                     "prefiltering.");
    parser.addHelpOption();
    parser.addVersionOption();
    parser.addOption(
        QCommandLineOption(kScreenshotOption, "Save a picture of the main window to FILE and exit.", "FILE"));
    parser.addPositionalArgument("file",
                                 "A .burnish project to open, or an image to load as the normal map of "
                                 "the built-in sample (default: the built-in sample).",
                                 "[PROJECT|IMAGE]");
}

bool commandLineOnlyPrints(int argc, const char* const* argv) {
    QStringList arguments;
    for (int i = 0; i < argc; ++i)
        arguments << QString::fromLocal8Bit(argv[i]);
    QCommandLineParser parser;
    addStudioOptions(parser);
    // Not understood: QCommandLineParser::process prints the error and exits.
    if (!parser.parse(arguments)) return true;
    // The names as given on the command line, so the platform-specific help aliases count too.
    for (const QString& name : parser.optionNames())
        if (name == "h" || name == "?" || name == "help" || name == "help-all" || name == "v" ||
            name == "version")
            return true;
    return false;
}

} // namespace burnish::studio
