#include "charts/specular_chart.h"

#include <burnish/core/shading/color.h>
#include <burnish/core/shading/materials.h>

#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <QUndoStack>

#include <algorithm>
#include <cmath>

namespace burnish::studio {

namespace {

// Layout in pixels: wide enough side margins for the end labels, a strip tall enough to judge the
// greys by, and lanes one text line high.
constexpr double kSideMargin = 18.0;
constexpr double kTitleHeight = 20.0;
constexpr double kLinearAxisHeight = 22.0;
constexpr double kStripHeight = 30.0;
constexpr double kSrgbAxisHeight = 22.0;
constexpr double kLaneHeight = 18.0;
constexpr double kSwatch = 11.0;
constexpr double kLabelGap = 6.0; // between neighbouring labels in one lane
constexpr double kReadoutHeight = 22.0;

// Linear values worth a tick: the range ends of the table and round numbers in between.
constexpr double kLinearTicks[] = {0.005, 0.02, 0.04, 0.1, 0.2, 0.33, 0.5, 0.7, 1.0};
// 8-bit sRGB codes worth a tick: the chart's gradient ends (40, 75, 155, 255) and mid grey 187.
constexpr int kSrgbTicks[] = {0, 40, 75, 100, 155, 187, 255};

QString qs(const std::string& s) {
    return QString::fromStdString(s);
}

QColor swatchColor(const LinearRgb& c) {
    const Srgb8 s = toSrgb8(c);
    return QColor(s.r, s.g, s.b);
}

QString rgbText(const LinearRgb& c) {
    const Srgb8 s = toSrgb8(c);
    if (s.r == s.g && s.g == s.b) return QString("sRGB %1 · linear %2").arg(s.r).arg(c.r, 0, 'f', 4);
    return QString("sRGB (%1, %2, %3) · linear (%4, %5, %6)")
        .arg(s.r)
        .arg(s.g)
        .arg(s.b)
        .arg(c.r, 0, 'f', 3)
        .arg(c.g, 0, 'f', 3)
        .arg(c.b, 0, 'f', 3);
}

} // namespace

SpecularChart::SpecularChart(MaterialDocument* doc, QWidget* parent)
    : QWidget(parent)
    , m_doc(doc) {
    setObjectName("specularChart");
    setMouseTracking(true);
    setSizePolicy(QSizePolicy::Expanding, QSizePolicy::Fixed);
    connect(m_doc, &MaterialDocument::changed, this, qOverload<>(&QWidget::update));
    layoutMarkers();
}

QSize SpecularChart::sizeHint() const {
    return {900, minimumSizeHint().height()};
}

QSize SpecularChart::minimumSizeHint() const {
    double bottom = stripRect().bottom() + kSrgbAxisHeight;
    for (const Marker& m : m_markers)
        bottom = std::max(bottom, m.label.bottom());
    return {480, int(std::ceil(bottom + kReadoutHeight + 4.0))};
}

QRectF SpecularChart::stripRect() const {
    const double top = kTitleHeight + kLinearAxisHeight;
    return {kSideMargin, top, std::max(1.0, width() - 2.0 * kSideMargin), kStripHeight};
}

double SpecularChart::xForF0(double f0) const {
    const QRectF strip = stripRect();
    return strip.left() + linearToSrgb(f0) * strip.width();
}

double SpecularChart::f0ForX(double x) const {
    const QRectF strip = stripRect();
    return srgbToLinear((x - strip.left()) / strip.width());
}

void SpecularChart::resizeEvent(QResizeEvent* event) {
    QWidget::resizeEvent(event);
    layoutMarkers();
    setFixedHeight(minimumSizeHint().height());
}

void SpecularChart::layoutMarkers() {
    const MaterialTable& table = builtinMaterialTable();
    const QFontMetricsF fm(font());
    const double lanesTop = stripRect().bottom() + kSrgbAxisHeight;
    // Markers in order of position; each goes to the first lane whose last label ends before it.
    std::vector<int> order(table.materials.size());
    for (size_t i = 0; i < order.size(); ++i)
        order[i] = int(i);
    auto lumOf = [&](int i) { return luminance(table.materials[size_t(i)].f0Min); };
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return lumOf(a) < lumOf(b); });
    std::vector<double> laneEnd;
    m_markers.clear();
    for (int i : order) {
        const Material& mat = table.materials[size_t(i)];
        const double x0 = xForF0(luminance(mat.f0Min));
        const double x1 = std::max(xForF0(luminance(mat.f0Max)), x0 + 2.0); // a single value: a 2 px tick
        const double labelWidth = kSwatch + 4.0 + fm.horizontalAdvance(qs(mat.name));
        // Labels start at their value, or end at the strip's right end where they would not fit.
        const double labelLeft = std::min(x0, width() - kSideMargin - labelWidth);
        const double left = std::min(x0, labelLeft);
        const double right = std::max(x1, labelLeft + labelWidth);
        size_t lane = 0;
        while (lane < laneEnd.size() && laneEnd[lane] + kLabelGap > left)
            ++lane;
        if (lane == laneEnd.size()) laneEnd.push_back(0.0);
        laneEnd[lane] = right;
        const double y = lanesTop + double(lane) * kLaneHeight;
        Marker m;
        m.material = i;
        m.tick = QRectF(x0, y, x1 - x0, 3.0);
        m.label = QRectF(labelLeft, y + 4.0, labelWidth, kLaneHeight - 5.0);
        m_markers.push_back(m);
    }
}

QRectF SpecularChart::markerRect(const QString& materialName) const {
    const MaterialTable& table = builtinMaterialTable();
    for (const Marker& m : m_markers)
        if (QString::fromStdString(table.materials[size_t(m.material)].name)
                .compare(materialName, Qt::CaseInsensitive) == 0)
            return m.label;
    return {};
}

int SpecularChart::markerAt(const QPointF& p) const {
    for (size_t i = 0; i < m_markers.size(); ++i)
        if (m_markers[i].label.adjusted(0, -4, 0, 0).contains(p)) return int(i);
    return -1;
}

QString SpecularChart::describeF0(double f0) const {
    const MaterialTable& table = builtinMaterialTable();
    const F0Classification c = classifyF0(table, LinearRgb::grey(f0));
    QString where = "between the ranges: no common material is here";
    if (c.f0Class == F0Class::Dielectric)
        where = c.insideChart ? "dielectric (inside the chart's gradient)" : "dielectric (plausible)";
    else if (c.f0Class == F0Class::Metal)
        where = "metal";
    else if (f0 < table.dielectricPlausible.bounds().min)
        where = "below every dielectric";
    return QString("%1 — %2").arg(rgbText(LinearRgb::grey(f0)), where);
}

void SpecularChart::mouseMoveEvent(QMouseEvent* event) {
    const QPointF p = event->position();
    const int hovered = markerAt(p);
    if (hovered >= 0) {
        const Material& mat = builtinMaterialTable().materials[size_t(m_markers[size_t(hovered)].material)];
        m_readout = QString("%1 (%2): %3").arg(qs(mat.name), toString(mat.materialClass), rgbText(mat.f0Min));
        if (mat.isRange()) m_readout += QString(" to %1").arg(rgbText(mat.f0Max));
        m_readout += " — click to pick";
    } else if (stripRect().adjusted(0, -kLinearAxisHeight, 0, kSrgbAxisHeight).contains(p)) {
        m_readout = describeF0(f0ForX(p.x())) + " — click to pick this grey";
    } else {
        m_readout.clear();
    }
    m_hovered = hovered;
    setToolTip(m_readout);
    update();
}

void SpecularChart::leaveEvent(QEvent* event) {
    QWidget::leaveEvent(event);
    m_hovered = -1;
    m_readout.clear();
    update();
}

void SpecularChart::mousePressEvent(QMouseEvent* event) {
    if (event->button() != Qt::LeftButton) return;
    const QPointF p = event->position();
    const int hit = markerAt(p);
    if (hit >= 0) {
        const Material& mat = builtinMaterialTable().materials[size_t(m_markers[size_t(hit)].material)];
        // The name comes from the table itself, so this cannot fail; a failure would be a table defect.
        (void)m_doc->setSpecularMaterial(QString::fromStdString(mat.name));
        return;
    }
    if (!stripRect().adjusted(0, -kLinearAxisHeight, 0, kSrgbAxisHeight).contains(p)) return;
    // A grey picked off the strip, snapped to its 8-bit sRGB code (what a texture can store), and
    // the material class that goes with it: one undo step for both.
    const double f0 = srgb8ToLinear(linearToSrgb8(f0ForX(p.x())));
    const F0Class cls = classifyF0(builtinMaterialTable(), LinearRgb::grey(f0)).f0Class;
    QUndoStack* undo = m_doc->undoStack();
    undo->beginMacro(QString("Specular: grey %1").arg(f0, 0, 'f', 4));
    if (cls != F0Class::Implausible)
        m_doc->setMaterialClass(cls == F0Class::Metal ? MaterialClass::Metal : MaterialClass::Dielectric);
    m_doc->setCustomSpecular(LinearRgb::grey(f0));
    undo->endMacro();
}

void SpecularChart::paintEvent(QPaintEvent*) {
    QPainter p(this);
    p.setRenderHint(QPainter::Antialiasing);
    const QPalette& pal = palette();
    const QColor text = pal.color(QPalette::WindowText);
    const QColor dim = pal.color(QPalette::Mid);
    const MaterialTable& table = builtinMaterialTable();
    const QRectF strip = stripRect();
    const QFontMetricsF fm(font());

    p.setPen(text);
    p.drawText(QRectF(kSideMargin, 0, width() - 2 * kSideMargin, kTitleHeight),
               Qt::AlignLeft | Qt::AlignVCenter,
               "Specular colour F0 — positions by sRGB encoding; linear F0 above, 8-bit sRGB below");

    // The gradient: each column painted with its own sRGB grey.
    const int columns = std::max(1, int(strip.width()));
    for (int i = 0; i < columns; ++i) {
        const int code = std::clamp(int(std::lround(255.0 * (i + 0.5) / columns)), 0, 255);
        p.fillRect(QRectF(strip.left() + i, strip.top(), 1.0, strip.height()), QColor(code, code, code));
    }

    // Ranges: translucent bands over the strip with their names on top.
    auto band = [&](const LinearInterval& r, QColor colour, const QString& name, double inset,
                    Qt::Alignment align) {
        const QRectF rect(xForF0(r.min), strip.top() + inset, xForF0(r.max) - xForF0(r.min),
                          strip.height() - 2 * inset);
        QColor fill = colour;
        fill.setAlpha(70);
        p.fillRect(rect, fill);
        p.setPen(QPen(colour, 2.0));
        p.drawRect(rect);
        p.setPen(Qt::white);
        QFont f = font();
        f.setPointSizeF(f.pointSizeF() * 0.85);
        p.setFont(f);
        p.drawText(rect.adjusted(6, 0, -6, 0), align | Qt::AlignVCenter, name);
        p.setFont(font());
    };
    band(table.dielectricPlausible.bounds(), QColor(90, 160, 255), "plausible dielectrics", 0.0,
         Qt::AlignRight);
    band(table.dielectricChart.bounds(), QColor(60, 120, 230), "dielectric chart", 4.0, Qt::AlignLeft);
    band(table.metalChart.bounds(), QColor(230, 150, 50), "metal (coloured, brightest channel)", 4.0,
         Qt::AlignLeft);

    // Linear axis above, sRGB axis below.
    p.setPen(text);
    for (double v : kLinearTicks) {
        const double x = xForF0(v);
        p.drawLine(QPointF(x, strip.top() - 4), QPointF(x, strip.top()));
        const QString label = QString::number(v, 'g', 3);
        const double w = fm.horizontalAdvance(label);
        p.drawText(QPointF(std::clamp(x - w / 2, 0.0, width() - w), strip.top() - 7), label);
    }
    for (int code : kSrgbTicks) {
        const double x = xForF0(srgb8ToLinear(std::uint8_t(code)));
        p.drawLine(QPointF(x, strip.bottom()), QPointF(x, strip.bottom() + 4));
        const QString label = QString::number(code);
        const double w = fm.horizontalAdvance(label);
        p.drawText(QPointF(std::clamp(x - w / 2, 0.0, width() - w), strip.bottom() + 4 + fm.ascent()), label);
    }

    // Materials: a bar (range) or tick on the lane, swatch and name beneath.
    for (size_t i = 0; i < m_markers.size(); ++i) {
        const Marker& m = m_markers[i];
        const Material& mat = table.materials[size_t(m.material)];
        const bool current = m_doc->settings().specularName.compare(qs(mat.name), Qt::CaseInsensitive) == 0;
        const bool hovered = int(i) == m_hovered;
        const QColor accent =
            mat.materialClass == MaterialClass::Metal ? QColor(230, 150, 50) : QColor(90, 160, 255);
        p.fillRect(m.tick, accent);
        const QRectF sw(m.label.left(), m.label.top() + 1, kSwatch, kSwatch);
        p.fillRect(sw, swatchColor(mat.f0()));
        p.setPen(QPen(dim, 1.0));
        p.drawRect(sw);
        QFont f = font();
        f.setBold(current);
        f.setUnderline(hovered);
        p.setFont(f);
        p.setPen(current ? QColor(255, 230, 120) : text);
        p.drawText(QPointF(sw.right() + 4, sw.bottom()), qs(mat.name));
        p.setFont(font());
    }

    // The current colour: a marker through the strip at its luminance.
    const LinearRgb& f0 = m_doc->settings().specular;
    const double xc = xForF0(luminance(f0));
    p.setPen(QPen(QColor(255, 230, 120), 2.0));
    p.drawLine(QPointF(xc, strip.top()), QPointF(xc, strip.bottom()));
    QPainterPath tri;
    tri.moveTo(xc, strip.bottom() + 1);
    tri.lineTo(xc - 6, strip.bottom() + 9);
    tri.lineTo(xc + 6, strip.bottom() + 9);
    tri.closeSubpath();
    p.fillPath(tri, QColor(255, 230, 120));
    p.fillRect(QRectF(xc - 7, strip.top() + 8, 14, strip.height() - 16), swatchColor(f0));

    // Readout: what is under the mouse, else the current colour.
    const QString line =
        m_readout.isEmpty()
            ? QString("current: %1%2")
                  .arg(m_doc->settings().specularName.isEmpty() ? "custom" : m_doc->settings().specularName)
                  .arg(" — " + rgbText(f0))
            : m_readout;
    p.setPen(text);
    p.drawText(QRectF(kSideMargin, height() - kReadoutHeight, width() - 2 * kSideMargin, kReadoutHeight),
               Qt::AlignLeft | Qt::AlignVCenter, line);
}

} // namespace burnish::studio
