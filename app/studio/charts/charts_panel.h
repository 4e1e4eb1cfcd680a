// The Charts dock: the specular colour and glossiness charts for artists, the BRDF plots, and error
// against cost, each following the material document.
#pragma once

#include "material_document.h"

#include <QDockWidget>

class QTabWidget;

namespace burnish::studio {

class BrdfPlots;
class ErrorCostChart;
class GlossChart;
class SpecularChart;

class ChartsPanel : public QDockWidget {
    Q_OBJECT
public:
    explicit ChartsPanel(MaterialDocument* doc, QWidget* parent = nullptr);

    SpecularChart* specularChart() const { return m_specular; }
    GlossChart* glossChart() const { return m_gloss; }
    BrdfPlots* brdfPlots() const { return m_brdf; }
    ErrorCostChart* errorCostChart() const { return m_errorCost; }
    QTabWidget* tabs() const { return m_tabs; }

private:
    QTabWidget* m_tabs;
    SpecularChart* m_specular;
    GlossChart* m_gloss;
    BrdfPlots* m_brdf;
    ErrorCostChart* m_errorCost;
};

} // namespace burnish::studio
