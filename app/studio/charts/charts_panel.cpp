#include "charts/charts_panel.h"

#include "charts/brdf_plots.h"
#include "charts/error_cost_chart.h"
#include "charts/gloss_chart.h"
#include "charts/specular_chart.h"

#include <QScrollArea>
#include <QTabWidget>
#include <QVBoxLayout>

namespace burnish::studio {

ChartsPanel::ChartsPanel(MaterialDocument* doc, QWidget* parent)
    : QDockWidget("Charts", parent) {
    setObjectName("chartsDock");
    m_tabs = new QTabWidget(this);
    m_tabs->setObjectName("chartsTabs");

    // The two artist charts share a page: pick a colour, then a gloss, without switching tabs.
    auto* page = new QWidget;
    m_specular = new SpecularChart(doc, page);
    m_gloss = new GlossChart(doc, page);
    auto* layout = new QVBoxLayout(page);
    layout->addWidget(m_specular);
    layout->addWidget(m_gloss);
    layout->addStretch(1);
    auto* scroll = new QScrollArea(m_tabs);
    scroll->setWidget(page);
    scroll->setWidgetResizable(true);
    scroll->setFrameShape(QFrame::NoFrame);
    m_tabs->addTab(scroll, "Specular && gloss");

    m_brdf = new BrdfPlots(doc, m_tabs);
    m_tabs->addTab(m_brdf, "BRDF plots");
    m_errorCost = new ErrorCostChart(doc, m_tabs);
    m_tabs->addTab(m_errorCost, "Error vs cost");
    setWidget(m_tabs);
}

} // namespace burnish::studio
