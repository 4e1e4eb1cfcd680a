// The specular colour chart (after Lagarde 2011's chart for artists): F0 along a strip spaced by its
// sRGB encoding (8-bit codes below, linear values above), the dielectric and metal ranges shaded,
// every material of core's calibrated table as a marker with its name and colour swatch, the current
// colour marked. Hover shows sRGB and linear values; a click picks (one undo step on the document).
#pragma once

#include "material_document.h"

#include <QRectF>
#include <QString>
#include <QWidget>

#include <vector>

namespace burnish::studio {

class SpecularChart : public QWidget {
    Q_OBJECT
public:
    explicit SpecularChart(MaterialDocument* doc, QWidget* parent = nullptr);

    /// Where a material's marker (swatch and name) is drawn, in widget coordinates; empty when the
    /// table has no such material. Valid after the widget has a size.
    QRectF markerRect(const QString& materialName) const;
    /// The horizontal position of a linear F0 on the strip (its sRGB encoding along the strip).
    double xForF0(double f0) const;
    /// The linear F0 at a horizontal position (inverse of xForF0, clamped to the strip).
    double f0ForX(double x) const;
    /// The strip's rectangle (the gradient the ranges are shaded on).
    QRectF stripRect() const;
    /// The text the hover readout shows now.
    QString readout() const { return m_readout; }

    QSize sizeHint() const override;
    QSize minimumSizeHint() const override;

protected:
    void paintEvent(QPaintEvent* event) override;
    void resizeEvent(QResizeEvent* event) override;
    void mouseMoveEvent(QMouseEvent* event) override;
    void mousePressEvent(QMouseEvent* event) override;
    void leaveEvent(QEvent* event) override;

private:
    struct Marker {
        int material = 0; // index into builtinMaterialTable().materials
        QRectF tick;      // the range bar or tick on the strip's lane
        QRectF label;     // swatch and name
    };
    void layoutMarkers();
    int markerAt(const QPointF& p) const;
    QString describeF0(double f0) const;

    MaterialDocument* m_doc;
    std::vector<Marker> m_markers;
    int m_hovered = -1;
    QString m_readout;
};

} // namespace burnish::studio
