// Helpers shared by the studio's Qt Charts.
#pragma once

#include <QAbstractAxis>
#include <QAbstractSeries>
#include <QChart>

namespace burnish::studio {

/// Adds x at the bottom and y at the left of the chart and attaches every series to both.
inline void attachAxes(QChart* chart, QAbstractAxis* x, QAbstractAxis* y) {
    chart->addAxis(x, Qt::AlignBottom);
    chart->addAxis(y, Qt::AlignLeft);
    for (QAbstractSeries* s : chart->series()) {
        s->attachAxis(x);
        s->attachAxis(y);
    }
}

} // namespace burnish::studio
