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
    // Every page scrolls when the dock is shorter or narrower than the charts, so the dock never
    // sets the window's minimum size (the window must fit 1280×720).
    auto scrolled = [this](QWidget* content) {
        auto* scroll = new QScrollArea(m_tabs);
        scroll->setWidget(content);
        scroll->setWidgetResizable(true);
        scroll->setFrameShape(QFrame::NoFrame);
        return scroll;
    };
    m_tabs->addTab(scrolled(page), "Specular && gloss");
    m_brdf = new BrdfPlots(doc);
    m_tabs->addTab(scrolled(m_brdf), "BRDF plots");
    m_errorCost = new ErrorCostChart(doc);
    m_tabs->addTab(scrolled(m_errorCost), "Error vs cost");
    setWidget(m_tabs);
}

} // namespace burnish::studio
