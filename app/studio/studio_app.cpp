#include "studio_app.h"

#include <QApplication>
#include <QPalette>
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

} // namespace burnish::studio
