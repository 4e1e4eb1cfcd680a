#include "charts/error_cost_chart.h"
#include "charts/chart_axes.h"

#include <burnish/core/prefilter/gloss.h>

#include <QChart>
#include <QChartView>
#include <QComboBox>
#include <QCoreApplication>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLegend>
#include <QLogValueAxis>
#include <QPointer>
#include <QProgressBar>
#include <QPushButton>
#include <QScatterSeries>
#include <QSpinBox>
#include <QTableWidget>
#include <QThread>
#include <QTimer>
#include <QVBoxLayout>
#include <QValueAxis>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace burnish::studio {

namespace {

// Wait this long after the last edit before evaluating again: a slider drag is one evaluation.
constexpr int kDebounceMs = 400;
// Bake timings are not plotted (the cost axis is shading time or storage): one run is enough.
constexpr int kBakeRuns = 1;
// Progress reaches the status line at most this often (in fractions of the whole run).
constexpr double kProgressStep = 0.02;

QString qs(std::string_view s) {
    return QString::fromUtf8(s.data(), int(s.size()));
}

QChart* newChart(const QString& title) {
    auto* chart = new QChart;
    chart->setTheme(QChart::ChartThemeDark);
    chart->setBackgroundRoundness(0);
    chart->setTitle(title);
    chart->legend()->setAlignment(Qt::AlignRight);
    // The legend shows each series' own marker (its colour and shape), not a square for all.
    chart->legend()->setMarkerShape(QLegend::MarkerShapeFromSeries);
    return chart;
}

void setChart(QChartView* view, QChart* chart) {
    QChart* old = view->chart();
    view->setChart(chart);
    delete old;
}

} // namespace

QAbstractAxis* errorCostAxis(const QString& title, double lo, double hi) {
    if (!(lo > 0.0) || !(hi >= lo) || !std::isfinite(hi)) {
        lo = 0.1;
        hi = 1.0;
    }
    double a0 = std::pow(10.0, std::floor(std::log10(lo)));
    double a1 = std::pow(10.0, std::ceil(std::log10(hi)));
    if (a1 <= a0) a1 = a0 * 10.0;
    if (a1 / a0 <= 10.0 * (1.0 + 1e-9)) {
        auto* a = new QValueAxis;
        a->setTitleText(title);
        a->setRange(0.0, hi * 1.1);
        a->setTickCount(6);
        a->applyNiceNumbers();
        a->setLabelFormat("%.3g");
        return a;
    }
    auto* a = new QLogValueAxis;
    a->setTitleText(title);
    a->setBase(10.0);
    a->setLabelFormat("%.6g"); // decades: 1000, not 1e+03
    a->setMinorTickCount(-1);
    a->setRange(a0, a1);
    return a;
}

ErrorCostChart::ErrorCostChart(MaterialDocument* doc, QWidget* parent)
    : QTabWidget(parent)
    , m_doc(doc) {
    setObjectName("errorCostChart");

    auto* methods = new QWidget(this);
    auto* controls = new QHBoxLayout;
    m_mipSpin = new QSpinBox(methods);
    m_mipSpin->setObjectName("errorCostMip");
    m_mipSpin->setPrefix("mip ");
    m_mipSpin->setRange(1, 4); // the evaluation's default mips; set from the result
    m_mipSpin->setValue(2);
    m_mipSpin->setKeyboardTracking(false);
    m_costCombo = new QComboBox(methods);
    m_costCombo->setObjectName("errorCostAxis");
    m_costCombo->addItem("cost: ns per lobe evaluation (CPU, double)");
    m_costCombo->addItem("cost: bytes per texel stored");
    auto* rerun = new QPushButton("Evaluate now", methods);
    controls->addWidget(m_mipSpin);
    controls->addWidget(m_costCombo);
    controls->addStretch(1);
    controls->addWidget(rerun);
    m_methodsView = new QChartView(methods);
    m_methodsView->setRenderHint(QPainter::Antialiasing);
    m_methodsView->setMinimumSize(420, 280);
    m_status = new QLabel(methods);
    m_status->setWordWrap(true);
    m_progress = new QProgressBar(methods);
    m_progress->setObjectName("errorCostProgress");
    m_progress->setRange(0, 100);
    m_progress->hide();
    m_cancelButton = new QPushButton("Cancel", methods);
    m_cancelButton->setObjectName("errorCostCancel");
    m_cancelButton->hide();
    auto* progressRow = new QHBoxLayout;
    progressRow->addWidget(m_progress, 1);
    progressRow->addWidget(m_cancelButton);
    auto* methodsLayout = new QVBoxLayout(methods);
    methodsLayout->addLayout(controls);
    methodsLayout->addWidget(m_methodsView, 1);
    methodsLayout->addLayout(progressRow);
    methodsLayout->addWidget(m_status);
    addTab(methods, "Methods vs ground truth");

    // Where the energy goes: evaluate's energy split of LEAN beside the mixture, per mip.
    auto* energy = new QWidget(this);
    m_energyStatus = new QLabel(energy);
    m_energyStatus->setWordWrap(true);
    m_energyTable = new QTableWidget(0, 6, energy);
    m_energyTable->setObjectName("energyTable");
    m_energyTable->setHorizontalHeaderLabels(
        {"mip", "LEAN keeps", "one cosine", "one Gaussian", "steep normals", "mixture keeps"});
    const QStringList tips{
        "The mip level: its texels' footprints are 2^mip × 2^mip finest texels.",
        "The share of the truth's highlight energy (at the evaluation's light/view pairs) LEAN keeps: "
        "the product of the next three columns.",
        "The truth with LEAN's one cosine max(0, n̄·l) for the footprint instead of each normal's own.",
        "One slope-space Gaussian for the footprint's normals that are not steep, against the normals' own "
        "lobes: its tails and its peak (below 1: clusters of normals smeared into one broad lobe).",
        "LEAN against that Gaussian: the steep normals' pull on the slope moments (their slopes widen the "
        "Gaussian and move its mean; their own light rarely reaches the sampled directions).",
        "The share the lobe mixture keeps, at the document's lobe count."};
    for (int c = 0; c < tips.size(); ++c)
        m_energyTable->horizontalHeaderItem(c)->setToolTip(tips[c]);
    m_energyTable->verticalHeader()->hide();
    m_energyTable->setEditTriggers(QAbstractItemView::NoEditTriggers);
    m_energyTable->setSelectionMode(QAbstractItemView::NoSelection);
    m_energyTable->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
    m_energyTable->setMinimumHeight(140);
    auto* energyLayout = new QVBoxLayout(energy);
    energyLayout->addWidget(m_energyStatus);
    energyLayout->addWidget(m_energyTable, 1);
    addTab(energy, "Energy kept");

    auto* approx = new QWidget(this);
    m_approxView = new QChartView(approx);
    m_approxView->setRenderHint(QPainter::Antialiasing);
    m_approxView->setMinimumSize(420, 280);
    m_approxStatus =
        new QLabel("Measures every approximation of core against its exact form (quick mode).", approx);
    m_approxStatus->setWordWrap(true);
    m_measureButton = new QPushButton("Measure", approx);
    // measureApproximations reports no fraction done: a busy bar while it runs.
    m_approxProgress = new QProgressBar(approx);
    m_approxProgress->setObjectName("approximationsProgress");
    m_approxProgress->setRange(0, 0);
    m_approxProgress->hide();
    m_approxCancelButton = new QPushButton("Cancel", approx);
    m_approxCancelButton->setObjectName("approximationsCancel");
    m_approxCancelButton->hide();
    auto* approxControls = new QHBoxLayout;
    approxControls->addWidget(m_approxStatus, 1);
    approxControls->addWidget(m_approxProgress);
    approxControls->addWidget(m_approxCancelButton);
    approxControls->addWidget(m_measureButton);
    auto* approxLayout = new QVBoxLayout(approx);
    approxLayout->addWidget(m_approxView, 1);
    approxLayout->addLayout(approxControls);
    addTab(approx, "Approximations");

    m_debounce = new QTimer(this);
    m_debounce->setSingleShot(true);
    m_debounce->setInterval(kDebounceMs);
    connect(m_debounce, &QTimer::timeout, this, [this] {
        if (!isVisible() || evaluationKey() == m_evaluatedKey) return;
        if (evaluatesByItself()) {
            evaluateNow();
            return;
        }
        // A big map is evaluated only when asked: its ground truth visits every finest texel for
        // every direction (an 8192² map took minutes and 17 GB when it started by itself).
        const NormalMap& map = *m_doc->maps().normal;
        if (!m_evaluating)
            m_status->setText(QString("The %1×%2 map is evaluated only when asked (it visits every texel for "
                                      "each of 48 light/view pairs, at every mip): press Evaluate now.")
                                  .arg(map.width)
                                  .arg(map.height));
    });
    connect(m_doc, &MaterialDocument::changed, this, &ErrorCostChart::onDocumentChanged);
    connect(m_doc, &MaterialDocument::mapChanged, this, &ErrorCostChart::onDocumentChanged);
    connect(m_mipSpin, qOverload<int>(&QSpinBox::valueChanged), this, [this] { showMethods(); });
    connect(m_costCombo, qOverload<int>(&QComboBox::currentIndexChanged), this, [this](int i) {
        m_costAxis = i == 0 ? CostAxis::NsPerLobe : CostAxis::BytesPerTexel;
        showMethods();
    });
    connect(rerun, &QPushButton::clicked, this, &ErrorCostChart::evaluateNow);
    connect(m_cancelButton, &QPushButton::clicked, this, &ErrorCostChart::cancelEvaluation);
    connect(m_approxCancelButton, &QPushButton::clicked, this, &ErrorCostChart::cancelApproximations);
    // No worker may outlive the event loop: a window closed while one runs would leave it running
    // at exit if the chart were not destroyed before the application object.
    connect(QCoreApplication::instance(), &QCoreApplication::aboutToQuit, this,
            &ErrorCostChart::cancelAndJoinWorkers);
    connect(m_measureButton, &QPushButton::clicked, this, &ErrorCostChart::measureApproximationsNow);
    connect(this, &QTabWidget::currentChanged, this, [this, approx](int tab) {
        if (widget(tab) == approx && !m_approximations && !m_measuring) measureApproximationsNow();
    });
    showMethods();
    showApproximations();
}

ErrorCostChart::~ErrorCostChart() {
    cancelAndJoinWorkers();
}

void ErrorCostChart::cancelAndJoinWorkers() {
    for (const Worker& w : m_workers)
        w.cancel->store(true);
    // Each worker stops at its next check (one direction pair of the evaluation, one approximation
    // entry); its queued result finds the chart gone or a newer generation and is dropped.
    for (const Worker& w : m_workers)
        if (w.thread) w.thread->wait();
    m_workers.clear();
}

bool ErrorCostChart::evaluatesByItself() const {
    return m_doc->maps().normal->texelCount() <= kAutoEvaluateTexels;
}

QString ErrorCostChart::evaluationKey() const {
    // The mixture is evaluated with the document's lobe count: another K is another evaluation; and
    // under the BRDF the preset's engine shades (GGX for the roughness presets).
    return QString("%1 %2 %3 %4")
        .arg(quintptr(m_doc->maps().normal.get()))
        .arg(m_doc->power(), 0, 'g', 17)
        .arg(m_doc->settings().mixtureLobes)
        .arg(qs(brdfName(glossBrdf(m_doc->preset().encoding))));
}

void ErrorCostChart::onDocumentChanged() {
    if (evaluationKey() != m_evaluatedKey) m_debounce->start();
    showMethods(); // the current method's point is highlighted
}

void ErrorCostChart::showEvent(QShowEvent* event) {
    QTabWidget::showEvent(event);
    if (evaluationKey() != m_evaluatedKey) m_debounce->start();
}

void ErrorCostChart::evaluateNow() {
    m_debounce->stop();
    // A newer evaluation replaces a running one: the old stops at its next step, its result is
    // dropped (older generation).
    if (m_evaluation.cancel) m_evaluation.cancel->store(true);
    m_evaluating = true;
    const quint64 generation = ++m_evaluationGeneration;
    m_runningKey = evaluationKey();
    std::shared_ptr<const NormalMap> map = m_doc->maps().normal;
    EvaluationReportOptions options;
    options.evaluate.basePowers = {m_doc->power()};
    // The truth the preset's engine shades: GGX for the roughness presets, whose methods are those with
    // a GGX form; LEAN's energy split (the "Energy kept" tab) is a Blinn-Phong measure.
    options.evaluate.brdf = glossBrdf(m_doc->preset().encoding);
    options.evaluate.methods = methodsUnder(options.evaluate.brdf);
    options.evaluate.mixtureLobes = {m_doc->settings().mixtureLobes};
    options.evaluate.energySplit = options.evaluate.brdf == Brdf::BlinnPhong;
    options.bakeRuns = kBakeRuns;
    options.inputName = m_doc->settings().normalMapPath.isEmpty()
                            ? std::string(kSampleName)
                            : m_doc->settings().normalMapPath.toStdString();
    m_status->setText(QString("evaluating %1 methods on the %2×%3 normal map at power %4…")
                          .arg(options.evaluate.methods.size())
                          .arg(map->width)
                          .arg(map->height)
                          .arg(m_doc->power(), 0, 'g', 4));
    m_progress->setValue(0);
    m_progress->show();
    m_cancelButton->setEnabled(true);
    m_cancelButton->show();
    QPointer<ErrorCostChart> self(this);
    const QString key = m_runningKey;
    auto cancel = std::make_shared<std::atomic<bool>>(false);
    QThread* worker = QThread::create([self, map, options, key, generation, cancel] {
        double lastShown = -1.0;
        auto progress = [&](double f) {
            if (f - lastShown < kProgressStep && f < 1.0) return;
            lastShown = f;
            QMetaObject::invokeMethod(
                QCoreApplication::instance(),
                [self, f, generation] {
                    if (!self || self->m_evaluationGeneration != generation || !self->m_evaluating) return;
                    const int percent = int(std::lround(100.0 * f));
                    self->m_progress->setValue(std::max(self->m_progress->value(), percent));
                    self->m_status->setText(QString("evaluating… %1%").arg(percent));
                },
                Qt::QueuedConnection);
        };
        auto built = buildEvaluationReport(*map, options, progress, cancel.get());
        std::shared_ptr<const EvaluationReport> report;
        QString error;
        bool cancelled = false;
        if (built) {
            report = std::make_shared<const EvaluationReport>(std::move(built.value()));
        } else {
            error = QString::fromStdString(built.error());
            cancelled = isCancelled(Error{built.error()});
        }
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, report, error, key, generation, cancelled] {
                // Gone, or replaced by a newer evaluation: that one reports.
                if (!self || self->m_evaluationGeneration != generation) return;
                self->m_evaluating = false;
                self->m_evaluation = {};
                self->m_report = report;
                self->m_evaluatedKey = key;
                self->m_cancelButton->hide();
                if (report) self->m_progress->setValue(100);
                self->m_progress->hide();
                if (cancelled)
                    self->m_status->setText("evaluation cancelled: press Evaluate now to run it again");
                else if (!report)
                    self->m_status->setText("evaluation failed: " + error);
                self->showMethods();
                if (!cancelled && self->isVisible() && self->evaluationKey() != key) self->evaluateNow();
                emit self->methodsUpdated();
            },
            Qt::QueuedConnection);
    });
    worker->setParent(this);
    m_evaluation = {worker, cancel};
    m_workers.append(m_evaluation);
    connect(worker, &QThread::finished, this, [this, worker] {
        m_workers.removeIf([worker](const Worker& w) { return w.thread == worker; });
        worker->deleteLater();
    });
    worker->start();
}

void ErrorCostChart::cancelEvaluation() {
    if (!m_evaluating || !m_evaluation.cancel) return;
    m_evaluation.cancel->store(true);
    m_cancelButton->setEnabled(false);
    m_status->setText("cancelling…");
}

void ErrorCostChart::measureApproximationsNow() {
    if (m_measuring) return;
    m_measuring = true;
    m_measureButton->setEnabled(false);
    m_approxProgress->show();
    m_approxCancelButton->setEnabled(true);
    m_approxCancelButton->show();
    m_approxStatus->setText("measuring every approximation (quick mode, a few seconds)…");
    QPointer<ErrorCostChart> self(this);
    auto cancel = std::make_shared<std::atomic<bool>>(false);
    QThread* worker = QThread::create([self, cancel] {
        ApproximationOptions options;
        options.quick = true;
        auto measured = measureApproximations(options, cancel.get());
        std::shared_ptr<const ApproximationReport> report;
        QString error;
        bool cancelled = false;
        if (measured) {
            report = std::make_shared<const ApproximationReport>(std::move(measured.value()));
        } else {
            error = QString::fromStdString(measured.error());
            cancelled = isCancelled(Error{measured.error()});
        }
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, report, error, cancelled] {
                if (!self) return;
                self->m_measuring = false;
                self->m_approximation = {};
                self->m_measureButton->setEnabled(true);
                self->m_approxProgress->hide();
                self->m_approxCancelButton->hide();
                self->m_approximations = report;
                if (cancelled)
                    self->m_approxStatus->setText("measurement cancelled: press Measure to run it again");
                else if (!report)
                    self->m_approxStatus->setText("measurement failed: " + error);
                self->showApproximations();
                emit self->approximationsUpdated();
            },
            Qt::QueuedConnection);
    });
    worker->setParent(this);
    m_approximation = {worker, cancel};
    m_workers.append(m_approximation);
    connect(worker, &QThread::finished, this, [this, worker] {
        m_workers.removeIf([worker](const Worker& w) { return w.thread == worker; });
        worker->deleteLater();
    });
    worker->start();
}

void ErrorCostChart::cancelApproximations() {
    if (!m_measuring || !m_approximation.cancel) return;
    m_approximation.cancel->store(true);
    m_approxCancelButton->setEnabled(false);
    m_approxStatus->setText("cancelling…");
}

void ErrorCostChart::setMip(int mip) {
    m_mipSpin->setValue(mip);
    showMethods();
}

int ErrorCostChart::mip() const {
    return m_mipSpin->value();
}

void ErrorCostChart::setCostAxis(CostAxis axis) {
    m_costCombo->setCurrentIndex(axis == CostAxis::NsPerLobe ? 0 : 1);
}

QString ErrorCostChart::statusText() const {
    return m_status->text();
}

namespace {

// The method's place in the method table.
size_t methodIndex(Method method) {
    const auto methods = allMethods();
    const auto at = std::find(methods.begin(), methods.end(), method);
    return at == methods.end() ? 0 : size_t(at - methods.begin());
}

} // namespace

QColor methodColour(Method method) {
    // Every method its own colour (and marker: methodMarker), the same in every chart, in the method
    // table's order (the chart theme's palette repeats after five series, so naive and CLEAN were
    // drawn alike).
    return groupColour(methodIndex(method));
}

QScatterSeries::MarkerShape methodMarker(Method method) {
    return groupMarker(methodIndex(method));
}

QScatterSeries* ErrorCostChart::methodSeries(Method method) const {
    if (!m_methodsView->chart()) return nullptr;
    for (QAbstractSeries* s : m_methodsView->chart()->series())
        if (s->objectName() == qs(methodName(method))) return qobject_cast<QScatterSeries*>(s);
    return nullptr;
}

QList<QScatterSeries*> ErrorCostChart::approximationSeries() const {
    QList<QScatterSeries*> out;
    if (!m_approxView->chart()) return out;
    for (QAbstractSeries* s : m_approxView->chart()->series())
        if (auto* scatter = qobject_cast<QScatterSeries*>(s)) out << scatter;
    return out;
}

void ErrorCostChart::showMethods() {
    const bool ns = m_costAxis == CostAxis::NsPerLobe;
    QChart* chart = newChart(
        m_report ? QString("Relative L1 error vs ground truth at mip %1 against cost, power %2")
                       .arg(mip())
                       .arg(m_report->result.basePowers.empty() ? 0.0 : m_report->result.basePowers.front(),
                            0, 'g', 4)
                 : QString("Relative L1 error vs ground truth against cost"));
    double xLo = std::numeric_limits<double>::infinity(), xHi = 0.0;
    double yLo = std::numeric_limits<double>::infinity(), yHi = 0.0;
    if (m_report) {
        m_mipSpin->blockSignals(true);
        m_mipSpin->setRange(m_report->result.firstMip, m_report->result.lastMip);
        m_mipSpin->blockSignals(false);
        std::map<Method, double> cost;
        for (const MethodCost& c : m_report->costs)
            cost[c.method] = ns ? c.nsPerLobe : c.storage.bytesPerTexel;
        int shown = 0;
        for (const MipError& e : m_report->result.errors) {
            if (e.mip != mip() || e.kernel != FilterKernel::Box || !cost.count(e.method)) continue;
            const double x = cost[e.method];
            const double y = e.relativeL1;
            // A log chart cannot place 0 or a non-finite value; core's values are finite, an exact
            // zero error is not expected from any method but would be left out, not faked.
            if (!(x > 0.0) || !(y > 0.0) || !std::isfinite(x) || !std::isfinite(y)) continue;
            auto* s = new QScatterSeries;
            s->setObjectName(qs(methodName(e.method)));
            const bool current = e.method == m_doc->settings().method;
            s->setName(QString::fromStdString(variantLabel(variantOf(e))) + (current ? " (current)" : ""));
            s->setMarkerSize(current ? 16.0 : 11.0);
            s->setColor(methodColour(e.method));
            // Shapes as well as colours: methods of nearly equal cost and error (naive and Toksvig)
            // stay told apart where their markers overlap.
            s->setMarkerShape(methodMarker(e.method));
            s->setBorderColor(current ? QColor(Qt::white) : methodColour(e.method).darker(140));
            s->append(x, y);
            chart->addSeries(s);
            xLo = std::min(xLo, x);
            xHi = std::max(xHi, x);
            yLo = std::min(yLo, y);
            yHi = std::max(yHi, y);
            ++shown;
        }
        if (!m_evaluating)
            m_status->setText(
                QString("%1 methods on the %2×%3 map \"%4\", base power %5, mip %6 (%7×%8 texels), "
                        "%9 directions, %12 truth; evaluated in %10 s. Cost: %11.")
                    .arg(shown)
                    .arg(m_report->width)
                    .arg(m_report->height)
                    .arg(QString::fromStdString(m_report->input))
                    .arg(m_report->result.basePowers.empty() ? 0.0 : m_report->result.basePowers.front(), 0,
                         'g', 4)
                    .arg(mip())
                    .arg(std::max(1, m_report->width >> mip()))
                    .arg(std::max(1, m_report->height >> mip()))
                    .arg(m_report->result.directions.size())
                    .arg(m_report->result.seconds, 0, 'f', 2)
                    .arg(ns ? "median ns per lobe evaluation on one CPU core"
                            : "bytes per texel at mip 0 in the recommended storage")
                    .arg(m_report->options.brdf == Brdf::Ggx ? "GGX (as this preset's engine shades)"
                                                             : "Blinn-Phong"));
    } else if (!m_evaluating && m_status->text().isEmpty()) {
        m_status->setText("not evaluated yet: shows when the panel is visible, or press Evaluate now");
    }
    attachAxes(chart, errorCostAxis(ns ? "ns per lobe evaluation" : "bytes per texel", xLo, xHi),
               errorCostAxis("relative L1 error", yLo, yHi));
    setChart(m_methodsView, chart);
    showEnergy();
}

void ErrorCostChart::showEnergy() {
    m_energyTable->setRowCount(0);
    if (m_report && m_report->options.brdf == Brdf::Ggx) {
        m_energyStatus->setText(
            "Where LEAN's energy goes is measured under the Blinn-Phong truth; this preset's "
            "engine shades GGX, where LEAN and the mixture have no form. Choose a "
            "Blinn-Phong preset (blackops, exp2) to see it.");
        return;
    }
    if (!m_report || m_report->result.energySplits.empty()) {
        m_energyStatus->setText(
            m_evaluating ? "evaluating…"
                         : QString("Shows with the methods' evaluation, which starts by itself for maps up "
                                   "to %1×%1 texels; "
                                   "a larger map waits for Evaluate now on Methods vs ground truth.")
                               .arg(std::lround(std::sqrt(double(kAutoEvaluateTexels)))));
        return;
    }
    const std::vector<LeanEnergySplit>& rows = m_report->result.energySplits;
    const int lobes = m_report->options.mixtureLobes.empty() ? kDefaultMixtureLobes
                                                             : m_report->options.mixtureLobes.front();
    m_energyTable->horizontalHeaderItem(5)->setText(
        QString::fromStdString(variantLabel({Method::Mixture, FilterKernel::Box, lobes}) + " keeps"));
    m_energyStatus->setText(
        QString(
            "How much of the ground truth's highlight energy each method keeps at the evaluated light/view "
            "pairs, base power %1 (1 keeps all of it; a cell more than 3 % away is marked). LEAN's share is "
            "the product of three steps from the truth: one cosine for the footprint, one Gaussian for its "
            "normals, and the steep normals' pull on that Gaussian (%2 % of this map's normals tilt more "
            "than %3°). Hover a column's title for more.")
            .arg(rows.front().basePower, 0, 'g', 4)
            .arg(100.0 * rows.front().steepNormals, 0, 'f', 1)
            .arg(m_report->options.steepDeg, 0, 'g', 3));
    auto cell = [](double v) {
        auto* item = new QTableWidgetItem(QString::number(v, 'f', 3));
        item->setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
        if (!(v >= 0.97 && v <= 1.03)) item->setBackground(QColor(120, 60, 30));
        return item;
    };
    for (const LeanEnergySplit& e : rows) {
        const int r = m_energyTable->rowCount();
        m_energyTable->insertRow(r);
        auto* mip = new QTableWidgetItem(QString::number(e.mip));
        mip->setTextAlignment(Qt::AlignCenter);
        m_energyTable->setItem(r, 0, mip);
        m_energyTable->setItem(r, 1, cell(e.energy));
        m_energyTable->setItem(r, 2, cell(e.cosine));
        m_energyTable->setItem(r, 3, cell(e.shape));
        m_energyTable->setItem(r, 4, cell(e.steep));
        for (const MipError& x : m_report->result.errors)
            if (x.method == Method::Mixture && x.lobes == lobes && !x.betweenTexels && x.mip == e.mip &&
                x.basePower == e.basePower)
                m_energyTable->setItem(r, 5, cell(x.energyRatio));
    }
}

void ErrorCostChart::showApproximations() {
    QChart* chart = newChart("Approximations: headline error against ns per evaluation (quick mode)");
    double xLo = std::numeric_limits<double>::infinity(), xHi = 0.0;
    double yLo = std::numeric_limits<double>::infinity(), yHi = 0.0;
    int shown = 0, left = 0;
    if (m_approximations) {
        std::map<std::string, QScatterSeries*> groups;
        for (size_t i = 0; i < m_approximations->groups.size(); ++i) {
            const std::string& g = m_approximations->groups[i];
            auto* s = new QScatterSeries;
            s->setObjectName(QString::fromStdString(g));
            s->setName(QString::fromStdString(g));
            s->setMarkerSize(10.0);
            // Nine groups shared the theme's five colours: each its own colour and marker.
            s->setColor(groupColour(i));
            s->setBorderColor(groupColour(i).darker(140));
            s->setMarkerShape(groupMarker(i));
            groups[g] = s;
        }
        for (const ApproximationEntry& e : m_approximations->entries) {
            const double x = e.approxNs;
            const double y = e.headlineError();
            auto it = groups.find(e.group);
            // Exact reformulations (error 0) and unmeasurable timings have no place on log axes.
            if (it == groups.end() || !(x > 0.0) || !(y > 0.0) || !std::isfinite(x) || !std::isfinite(y)) {
                ++left;
                continue;
            }
            it->second->append(x, y);
            xLo = std::min(xLo, x);
            xHi = std::max(xHi, x);
            yLo = std::min(yLo, y);
            yHi = std::max(yHi, y);
            ++shown;
        }
        for (const std::string& g : m_approximations->groups) {
            QScatterSeries* s = groups[g];
            if (s->count() > 0)
                chart->addSeries(s);
            else
                delete s;
        }
        m_approxStatus->setText(
            QString("%1 approximations shown%2; measured in %3 s on %4 (%5). Headline error: the largest "
                    "absolute or relative error of each approximation over its domain.")
                .arg(shown)
                .arg(left > 0 ? QString(", %1 with zero error or no timing left out").arg(left) : QString())
                .arg(m_approximations->seconds, 0, 'f', 1)
                .arg(QString::fromStdString(m_approximations->cpuModel))
                .arg(QString::fromStdString(m_approximations->compiler)));
    }
    attachAxes(chart, errorCostAxis("ns per evaluation (float kernel)", xLo, xHi),
               errorCostAxis("headline error", yLo, yHi)); // max abs or max rel: the status line says
    setChart(m_approxView, chart);
}

} // namespace burnish::studio
