// Application-wide set-up shared by burnish-studio's main() and the studio tests.
#pragma once

#include <QString>

class QApplication;
class QCommandLineParser;

namespace burnish::studio {

inline constexpr const char* kStudioVersion = "0.1.0";

/// Organisation/application names (QSettings, QStandardPaths) and the dark Fusion look.
void setUpApplication(QApplication& app);

/// burnish-studio's command line: --help, --version, --screenshot FILE and one optional PROJECT.
void addStudioOptions(QCommandLineParser& parser);
/// Name of the --screenshot option.
inline constexpr const char* kScreenshotOption = "screenshot";

/// True when the command line only prints and exits (--help, --version, or options it does not
/// understand): the window toolkit then needs no display. Read before QApplication exists.
bool commandLineOnlyPrints(int argc, const char* const* argv);

} // namespace burnish::studio
