// BRDF plots (Qt Charts) for the current material, each series sampled from core's functions:
// NDF lobes at the current power (Blinn-Phong, Beckmann and GGX at the equivalent roughness, the
// spherical Gaussian, a LEAN slice) in Cartesian and polar form; Fresnel curves for the current
// F0; visibility terms against n·v; the preset's gloss → power curve with the current gloss marked.
#pragma once

#include "material_document.h"

#include <QTabWidget>

class QChartView;
class QXYSeries;

namespace burnish::studio {

class BrdfPlots : public QTabWidget {
    Q_OBJECT
public:
    /// Samples per curve.
    static constexpr int kSamples = 181;

    explicit BrdfPlots(MaterialDocument* doc, QWidget* parent = nullptr);

    /// Series by object name, "<plot>/<curve>": plots "ndf", "polar", "fresnel", "visibility",
    /// "gloss"; curves e.g. "blinn-phong", "beckmann", "ggx", "sg", "lean" (ndf and polar),
    /// "schlick", "glossy", "sg", "sg-quadratic", "dielectric" (fresnel), "none", "kelemen",
    /// "schlick-smith", "cook-torrance", "smith-beckmann", "smith-ggx" (visibility), "power" and
    /// "current" (gloss). Null when there is none.
    QXYSeries* findSeries(const QString& name) const;
    QChartView* view(int tab) const;

    /// The widest half-vector angle the NDF plots show for power n, in degrees: where the
    /// Blinn-Phong lobe has fallen to 1e-3 of its peak, times two (to show GGX's longer tail),
    /// at most 90.
    static double ndfAngleRangeDegrees(double n);
    /// The F0 the Fresnel plot uses: the luminance of the specular colour.
    double plottedF0() const;

public slots:
    /// Re-samples every curve from the document (connected to changed()).
    void refresh();

private:
    void buildNdf();
    void buildPolar();
    void buildFresnel();
    void buildVisibility();
    void buildGloss();

    MaterialDocument* m_doc;
    QChartView* m_ndf;
    QChartView* m_polar;
    QChartView* m_fresnel;
    QChartView* m_visibility;
    QChartView* m_gloss;
};

} // namespace burnish::studio
