#include "charts/brdf_plots.h"
#include "charts/chart_axes.h"

#include <burnish/core/prefilter/gloss.h>
#include <burnish/core/prefilter/methods.h>
#include <burnish/core/shading/color.h>
#include <burnish/core/shading/fresnel.h>
#include <burnish/core/shading/ndf.h>
#include <burnish/core/shading/spherical_gaussian.h>
#include <burnish/core/shading/visibility.h>

#include <QChart>
#include <QChartView>
#include <QLineSeries>
#include <QLogValueAxis>
#include <QPolarChart>
#include <QScatterSeries>
#include <QValueAxis>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>

namespace burnish::studio {

namespace {

constexpr double kDegrees = 180.0 / kPi<double>;
// The NDF plots span four decades below the peak: the tails that tell GGX from Beckmann show,
// the underflowing far tail does not flatten the rest.
constexpr double kNdfDecades = 4.0;
// The visibility plot starts at n·v = 0.02 (88.9°): every term but "none" has a pole at 0.
constexpr double kMinNoV = 0.02;

QChart* newChart(const QString& title) {
    auto* chart = new QChart;
    chart->setTheme(QChart::ChartThemeDark);
    chart->setBackgroundRoundness(0);
    chart->setTitle(title);
    chart->legend()->setAlignment(Qt::AlignRight);
    return chart;
}

QChartView* newView(QWidget* parent, const QString& name) {
    auto* view = new QChartView(parent);
    view->setObjectName(name);
    view->setRenderHint(QPainter::Antialiasing);
    view->setMinimumSize(420, 280);
    return view;
}

/// Replaces a view's chart (the old one is deleted with its series and axes).
void setChart(QChartView* view, QChart* chart) {
    QChart* old = view->chart();
    view->setChart(chart);
    delete old;
}

/// The pen of the i-th curve of a chart: six colours told apart on the dark theme, and dashes so
/// curves that coincide (the Blinn-Phong-like lobes at high powers) still show each other.
QPen curvePen(int i) {
    static const QColor colours[] = {QColor(90, 200, 120),  QColor(80, 160, 255), QColor(255, 150, 60),
                                     QColor(220, 220, 220), QColor(230, 90, 90),  QColor(200, 120, 230)};
    static const Qt::PenStyle styles[] = {Qt::SolidLine, Qt::DashLine,    Qt::SolidLine,
                                          Qt::DotLine,   Qt::DashDotLine, Qt::SolidLine};
    constexpr int kCount = int(std::size(colours));
    return QPen(colours[i % kCount], 2.0, styles[i % kCount]);
}

QLineSeries* addCurve(QChart* chart, const QString& id, const QString& label,
                      const std::function<double(double)>& f, double x0, double x1, bool positiveOnly) {
    auto* s = new QLineSeries;
    s->setObjectName(id);
    s->setName(label);
    s->setPen(curvePen(int(chart->series().size())));
    for (int i = 0; i < BrdfPlots::kSamples; ++i) {
        const double x = x0 + (x1 - x0) * double(i) / double(BrdfPlots::kSamples - 1);
        const double y = f(x);
        // Log axes cannot show 0 (an NDF's underflowed far tail): such samples are left out.
        if (positiveOnly && !(y > 0.0)) continue;
        s->append(x, y);
    }
    chart->addSeries(s);
    return s;
}

QLogValueAxis* logAxis(const QString& title, double lo, double hi) {
    auto* a = new QLogValueAxis;
    a->setTitleText(title);
    a->setBase(10.0);
    a->setLabelFormat("%.6g"); // decades: 1000, not 1e+03
    // Whole decades: a log axis labels lo·10^k, so a range from 0.37 labelled 0.37, 3.7, 37 and left
    // the top decade without a label.
    if (lo > 0.0 && hi > lo && std::isfinite(hi)) {
        lo = std::pow(10.0, std::floor(std::log10(lo)));
        hi = std::pow(10.0, std::ceil(std::log10(hi)));
    }
    a->setRange(lo, hi);
    a->setMinorTickCount(-1); // a minor tick per integer multiple: the decades read at a glance
    return a;
}

QValueAxis* valueAxis(const QString& title, double lo, double hi, const QString& format = "%.3g") {
    auto* a = new QValueAxis;
    a->setTitleText(title);
    a->setRange(lo, hi);
    a->setLabelFormat(format);
    return a;
}

/// The lobes of the NDF plots as functions of the signed half-vector angle θh in radians.
struct Lobes {
    double n, m, alpha, sigma2;
    explicit Lobes(double power)
        : n(clampPower(power))
        , m(beckmannRoughnessFromPower(power))
        , alpha(ggxAlphaFromPower(power))
        // LEAN for a flat footprint: Σ = I/s (Olano & Baker 2010), the smallest covariance it stores.
        , sigma2(varianceFromPower(power, VarianceConvention::InversePower)) {}
    double blinnPhong(double t) const { return blinnPhongNdf(std::cos(t), n); }
    double beckmann(double t) const { return beckmannNdf(std::cos(t), m); }
    double ggx(double t) const { return ggxNdf(std::cos(t), alpha); }
    // Lagarde 2012: c^n ≈ exp((n + 0.775)(c − 1)), with the Blinn-Phong NDF's normalization.
    double sg(double t) const { return blinnPhongNdfNorm(n) * sgLobe(std::cos(t), n, kSgOffsetLagarde); }
    // Olano & Baker 2010: the slope-space Gaussian along x (h in the xz plane).
    double lean(double t) const {
        return slopeGaussianNdf(glm::dvec3(std::sin(t), 0.0, std::cos(t)), glm::dvec2(0.0),
                                {sigma2, sigma2, 0.0});
    }
};

struct LobeCurve {
    const char* id;
    const char* label;
    double (Lobes::*f)(double) const;
};
const LobeCurve kLobeCurves[] = {
    {"blinn-phong", "Blinn-Phong", &Lobes::blinnPhong},
    {"beckmann", "Beckmann", &Lobes::beckmann},
    {"ggx", "GGX", &Lobes::ggx},
    {"sg", "spherical Gaussian", &Lobes::sg},
    {"lean", "LEAN slice, Σ = I/s", &Lobes::lean},
};

} // namespace

BrdfPlots::BrdfPlots(MaterialDocument* doc, QWidget* parent)
    : QTabWidget(parent)
    , m_doc(doc) {
    setObjectName("brdfPlots");
    m_ndf = newView(this, "ndfView");
    m_polar = newView(this, "polarView");
    m_fresnel = newView(this, "fresnelView");
    m_visibility = newView(this, "visibilityView");
    m_gloss = newView(this, "glossView");
    addTab(m_ndf, "NDF");
    addTab(m_polar, "NDF polar");
    addTab(m_fresnel, "Fresnel");
    addTab(m_visibility, "Visibility");
    addTab(m_gloss, "Gloss → power");
    connect(m_doc, &MaterialDocument::changed, this, &BrdfPlots::refresh);
    refresh();
}

QChartView* BrdfPlots::view(int tab) const {
    return qobject_cast<QChartView*>(widget(tab));
}

QXYSeries* BrdfPlots::findSeries(const QString& name) const {
    const QString plot = name.section('/', 0, 0);
    const QString curve = name.section('/', 1);
    for (QChartView* v : {m_ndf, m_polar, m_fresnel, m_visibility, m_gloss}) {
        if (v->objectName() != plot + "View") continue;
        for (QAbstractSeries* s : v->chart()->series())
            if (s->objectName() == curve) return qobject_cast<QXYSeries*>(s);
    }
    return nullptr;
}

double BrdfPlots::ndfAngleRangeDegrees(double n) {
    n = clampPower(n);
    // cos(θ)^n = 1e-3 → θ = acos(1e-3^(1/n)); n = 0 (a flat lobe) gives acos(0) = 90°.
    const double theta = n > 0.0 ? std::acos(std::exp(std::log(1e-3) / n)) : kPi<double> / 2.0;
    return std::clamp(2.0 * theta * kDegrees, 0.05, 90.0);
}

double BrdfPlots::plottedF0() const {
    return saturate(luminance(m_doc->settings().specular));
}

void BrdfPlots::refresh() {
    buildNdf();
    buildPolar();
    buildFresnel();
    buildVisibility();
    buildGloss();
}

void BrdfPlots::buildNdf() {
    const double n = m_doc->power();
    const Lobes lobes(n);
    const double thetaMax = ndfAngleRangeDegrees(n);
    QChart* chart = newChart(QString("NDF at power n = %1 (Beckmann m = GGX α = √(2/(n+2)) = %2)")
                                 .arg(n, 0, 'g', 4)
                                 .arg(lobes.m, 0, 'g', 3));
    for (const LobeCurve& c : kLobeCurves)
        addCurve(
            chart, c.id, c.label, [&](double deg) { return (lobes.*c.f)(deg / kDegrees); }, 0.0, thetaMax,
            true);
    const double peak = blinnPhongNdfNorm(n);
    auto* x = valueAxis("half-vector angle θh (degrees)", 0.0, thetaMax);
    x->applyNiceNumbers(); // round tick values; the range only grows
    attachAxes(chart, x, logAxis("D (1/sr)", peak * std::pow(10.0, -kNdfDecades), peak * 2.0));
    setChart(m_ndf, chart);
}

void BrdfPlots::buildPolar() {
    const double n = m_doc->power();
    const Lobes lobes(n);
    auto* chart = new QPolarChart;
    chart->setTheme(QChart::ChartThemeDark);
    chart->setBackgroundRoundness(0);
    chart->setTitle(QString("NDF lobes, polar: angle θh from the normal (up), radius D (1/sr), n = %1")
                        .arg(n, 0, 'g', 4));
    chart->legend()->setAlignment(Qt::AlignRight);
    // The whole upper hemisphere, θh in [−90°, 90°]; the polar chart's angles run clockwise from the
    // top over [0, 360), so negative angles are stored as 360 + θh. Dense near the normal, where
    // the narrow lobes of high powers live.
    const double thetaMax = ndfAngleRangeDegrees(n);
    double peak = 0.0;
    for (const LobeCurve& c : kLobeCurves) {
        auto* s = new QLineSeries;
        s->setObjectName(c.id);
        s->setName(c.label);
        s->setPen(curvePen(int(chart->series().size())));
        for (int i = 0; i < kSamples; ++i) {
            const double deg = -thetaMax + 2.0 * thetaMax * double(i) / double(kSamples - 1);
            const double d = (lobes.*c.f)(deg / kDegrees);
            peak = std::max(peak, d);
            s->append(deg < 0.0 ? 360.0 + deg : deg, d);
        }
        chart->addSeries(s);
    }
    auto* angular = valueAxis("", 0.0, 360.0, "%.0f");
    angular->setTickCount(13); // every 30°
    auto* radial = valueAxis("", 0.0, peak * 1.05, "%.3g");
    chart->addAxis(angular, QPolarChart::PolarOrientationAngular);
    chart->addAxis(radial, QPolarChart::PolarOrientationRadial);
    for (QAbstractSeries* s : chart->series()) {
        s->attachAxis(angular);
        s->attachAxis(radial);
    }
    setChart(m_polar, chart);
}

void BrdfPlots::buildFresnel() {
    const double c = plottedF0();
    const double g = m_doc->settings().gloss;
    QChart* chart = newChart(
        QString("Fresnel for F0 = %1 (luminance of the specular colour), x = cos θ").arg(c, 0, 'f', 4));
    auto cosOf = [](double deg) { return std::cos(deg / kDegrees); };
    addCurve(
        chart, "schlick", "Schlick", [&](double deg) { return fresnelSchlick(c, cosOf(deg)); }, 0.0, 90.0,
        false);
    addCurve(
        chart, "glossy", QString("glossy form, g = %1").arg(g, 0, 'f', 2),
        [&](double deg) { return fresnelGlossy(c, cosOf(deg), g); }, 0.0, 90.0, false);
    addCurve(
        chart, "sg", "SG, exp2(−8.35x)", [&](double deg) { return fresnelSchlickSg(c, cosOf(deg)); }, 0.0,
        90.0, false);
    addCurve(
        chart, "sg-quadratic", "SG quadratic",
        [&](double deg) { return fresnelSchlickSgQuadratic(c, cosOf(deg)); }, 0.0, 90.0, false);
    addCurve(
        chart, "dielectric", "exact dielectric", [&](double deg) { return fresnelDielectric(c, cosOf(deg)); },
        0.0, 90.0, false);
    auto* x = valueAxis("angle of incidence θ (degrees)", 0.0, 90.0, "%.0f");
    x->setTickCount(10);
    attachAxes(chart, x, valueAxis("F", 0.0, 1.0, "%.2f"));
    setChart(m_fresnel, chart);
}

void BrdfPlots::buildVisibility() {
    const double n = m_doc->power();
    const double m = beckmannRoughnessFromPower(n);
    const double alpha = ggxAlphaFromPower(n);
    QChart* chart =
        newChart(QString("Visibility V = G/((n·l)(n·v)) at the highlight peak (l mirrors v, h = n), n = %1")
                     .arg(n, 0, 'g', 4));
    // At the peak configuration n·l = n·v and v·h = n·v, n·h = 1.
    addCurve(
        chart, "none", "none", [](double) { return visibilityNone<double>(); }, kMinNoV, 1.0, true);
    addCurve(
        chart, "kelemen", "Kelemen–Szirmay-Kalos", [](double v) { return visibilityKelemen(v); }, kMinNoV,
        1.0, true);
    addCurve(
        chart, "schlick-smith", "Schlick–Smith", [&](double v) { return visibilitySchlickSmith(v, v, n); },
        kMinNoV, 1.0, true);
    addCurve(
        chart, "cook-torrance", "Cook–Torrance",
        [](double v) { return visibilityCookTorrance(v, v, 1.0, v); }, kMinNoV, 1.0, true);
    addCurve(
        chart, "smith-beckmann", "Smith Beckmann", [&](double v) { return visibilitySmithBeckmann(v, v, m); },
        kMinNoV, 1.0, true);
    addCurve(
        chart, "smith-ggx", "Smith GGX correlated",
        [&](double v) { return visibilitySmithGgxCorrelated(v, v, alpha); }, kMinNoV, 1.0, true);
    double hi = 1.0;
    for (QAbstractSeries* s : chart->series())
        for (const QPointF& p : static_cast<QXYSeries*>(s)->points())
            hi = std::max(hi, p.y());
    // Schlick–Smith and Smith fall below 1 at grazing angles for rough lobes: half a decade of room.
    auto* x = valueAxis("n·v", 0.0, 1.0, "%.1f");
    x->setTickCount(11); // every 0.1
    attachAxes(chart, x, logAxis("V", 0.3, hi * 1.5));
    setChart(m_visibility, chart);
}

void BrdfPlots::buildGloss() {
    const Preset& preset = m_doc->preset();
    const GlossEncoding& enc = preset.encoding;
    // In the preset's own word: roughness for gltf, unreal, …, gloss for the log-power presets.
    const QString term = glossQuantity(enc), lower = glossQuantity(enc, false);
    setTabText(indexOf(m_gloss), term + " → power");
    QChart* chart =
        newChart(QString("%1 encoding of preset %2: %3")
                     .arg(term, QString::fromStdString(preset.name), QString::fromStdString(enc.formula())));
    QLineSeries* curve = addCurve(
        chart, "power", "power n(g)", [&](double g) { return enc.power(g); }, 0.0, 1.0, true);
    auto* current = new QScatterSeries;
    current->setObjectName("current");
    current->setName(QString("current: g = %1, n = %2")
                         .arg(m_doc->settings().gloss, 0, 'f', 3)
                         .arg(m_doc->power(), 0, 'g', 4));
    current->setMarkerSize(11.0);
    current->setColor(QColor(255, 230, 120));
    if (m_doc->power() > 0.0) current->append(m_doc->settings().gloss, m_doc->power());
    chart->addSeries(current);
    double lo = kMaxPower, hi = 1.0;
    for (const QPointF& p : curve->points()) {
        lo = std::min(lo, p.y());
        hi = std::max(hi, p.y());
    }
    // A tick every 0.1, so each label stands at its value (five ticks put "0.3" at 0.25).
    QValueAxis* storedAxis = valueAxis(QString("stored %1 g").arg(lower), 0.0, 1.0, "%.1f");
    storedAxis->setTickCount(11);
    attachAxes(chart, storedAxis, logAxis("Blinn-Phong power n", lo / 2.0, hi * 2.0));
    setChart(m_gloss, chart);
}

} // namespace burnish::studio
