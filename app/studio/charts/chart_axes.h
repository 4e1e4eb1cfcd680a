// Helpers shared by the studio's Qt Charts.
#pragma once

#include <QAbstractAxis>
#include <QAbstractSeries>
#include <QChart>
#include <QCursor>
#include <QScatterSeries>
#include <QToolTip>
#include <QXYSeries>

#include <array>
#include <cstddef>

namespace burnish::studio {

/// What the pointer over a point of a series reads: the series, then each axis's title and value
/// ("vMF (current)\nbytes per texel: 12\nrelative L1 error: 0.0312").
inline QString hoverReadout(const QString& series, const QString& xTitle, double x, const QString& yTitle,
                            double y) {
    return QString("%1\n%2: %3\n%4: %5")
        .arg(series, xTitle, QString::number(x, 'g', 4), yTitle, QString::number(y, 'g', 4));
}

/// The property of a series holding the read-out its last hover showed (empty when the pointer left).
inline constexpr const char* kHoverReadoutProperty = "hoverReadout";

/// Adds x at the bottom and y at the left of the chart and attaches every series to both. Every line
/// and scatter series then says its value under the pointer (hoverReadout, as a tool tip): no plot
/// left a number to be read off its gridlines only.
inline void attachAxes(QChart* chart, QAbstractAxis* x, QAbstractAxis* y) {
    chart->addAxis(x, Qt::AlignBottom);
    chart->addAxis(y, Qt::AlignLeft);
    for (QAbstractSeries* s : chart->series()) {
        s->attachAxis(x);
        s->attachAxis(y);
        auto* xy = qobject_cast<QXYSeries*>(s);
        if (!xy) continue;
        QObject::connect(xy, &QXYSeries::hovered, xy,
                         [xy, xTitle = x->titleText(), yTitle = y->titleText()](const QPointF& p, bool on) {
                             const QString text =
                                 on ? hoverReadout(xy->name(), xTitle, p.x(), yTitle, p.y()) : QString();
                             xy->setProperty(kHoverReadoutProperty, text);
                             if (on)
                                 QToolTip::showText(QCursor::pos(), text);
                             else
                                 QToolTip::hideText();
                         });
    }
}

/// Group i's colour and marker among many (a qualitative palette, Tableau 10, and the six marker
/// shapes): up to 30 groups look different even where they overlap, where the chart theme's
/// palette repeats after five.
inline QColor groupColour(std::size_t i) {
    static const std::array<QColor, 10> kPalette = {QColor(0x4e, 0x79, 0xa7), QColor(0xf2, 0x8e, 0x2b),
                                                    QColor(0xe1, 0x57, 0x59), QColor(0x76, 0xb7, 0xb2),
                                                    QColor(0x59, 0xa1, 0x4f), QColor(0xed, 0xc9, 0x48),
                                                    QColor(0xb0, 0x7a, 0xa1), QColor(0xff, 0x9d, 0xa7),
                                                    QColor(0x9c, 0x75, 0x5f), QColor(0xba, 0xb0, 0xac)};
    return kPalette[i % kPalette.size()];
}
inline QScatterSeries::MarkerShape groupMarker(std::size_t i) {
    static const std::array<QScatterSeries::MarkerShape, 6> kShapes = {
        QScatterSeries::MarkerShapeCircle,   QScatterSeries::MarkerShapeRectangle,
        QScatterSeries::MarkerShapeTriangle, QScatterSeries::MarkerShapeRotatedRectangle,
        QScatterSeries::MarkerShapeStar,     QScatterSeries::MarkerShapePentagon};
    return kShapes[i % kShapes.size()];
}

} // namespace burnish::studio
