#include "elided_label.h"

#include <QFontMetrics>
#include <QPainter>
#include <QStyle>

#include <algorithm>
#include <cmath>

namespace burnish::studio {

namespace {
// Room for a few characters and the ellipsis: below this the label is not worth reading.
constexpr int kMinimumCharacters = 6;
} // namespace

ElidedLabel::ElidedLabel(QWidget* parent)
    : ElidedLabel(QString(), parent) {}

ElidedLabel::ElidedLabel(const QString& text, QWidget* parent)
    : QFrame(parent) {
    setSizePolicy(QSizePolicy::Preferred, QSizePolicy::Fixed);
    setText(text);
}

void ElidedLabel::setText(const QString& text) {
    if (text == m_text) return;
    m_text = text;
    setToolTip(text);
    updateGeometry();
    update();
}

QString ElidedLabel::shownText() const {
    const QRect r = contentsRect();
    return fontMetrics().elidedText(m_text, Qt::ElideRight, r.width());
}

QSize ElidedLabel::sizeHint() const {
    const QFontMetrics fm = fontMetrics();
    const QMargins m = contentsMargins();
    // The advance rounded up, and one pixel more: elidedText cuts a text wider than its width by
    // a fraction of a pixel.
    const int advance = int(std::ceil(QFontMetricsF(font()).horizontalAdvance(m_text))) + 1;
    return {advance + m.left() + m.right() + 2 * frameWidth(),
            fm.height() + m.top() + m.bottom() + 2 * frameWidth()};
}

QSize ElidedLabel::minimumSizeHint() const {
    const QFontMetrics fm = fontMetrics();
    const QMargins m = contentsMargins();
    const int least = fm.averageCharWidth() * kMinimumCharacters;
    return {std::min(sizeHint().width(), least + m.left() + m.right() + 2 * frameWidth()),
            sizeHint().height()};
}

void ElidedLabel::paintEvent(QPaintEvent* event) {
    QFrame::paintEvent(event);
    QPainter painter(this);
    painter.setPen(
        palette().color(isEnabled() ? QPalette::Active : QPalette::Disabled, QPalette::WindowText));
    painter.drawText(contentsRect(), Qt::AlignLeft | Qt::AlignVCenter, shownText());
}

} // namespace burnish::studio
