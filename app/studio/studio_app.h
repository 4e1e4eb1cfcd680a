// Application-wide set-up shared by burnish-studio's main() and the studio tests.
#pragma once

#include <QString>

class QApplication;

namespace burnish::studio {

inline constexpr const char* kStudioVersion = "0.1.0";

/// Organisation/application names (QSettings, QStandardPaths) and the dark Fusion look.
void setUpApplication(QApplication& app);

} // namespace burnish::studio
