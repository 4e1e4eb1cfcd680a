// Error against cost, measured by core in a worker thread so the UI never waits:
//  - "Methods": each prefiltering method's relative L1 error against the ground truth (evaluate.h)
//    for the current material's normal map and base power at a chosen mip, against its cost (ns per
//    lobe evaluation or bytes per texel stored, evaluate_report.h), one point per method;
//  - "Approximations": the approximations report in its quick mode (approximations.h), each
//    approximation's headline error against its ns per evaluation, one series per group.
#pragma once

#include "material_document.h"

#include <burnish/core/eval/approximations.h>
#include <burnish/core/eval/evaluate_report.h>

#include <QColor>
#include <QList>
#include <QPointer>
#include <QScatterSeries>
#include <QTabWidget>

#include <atomic>
#include <memory>
#include <optional>

class QAbstractAxis;
class QChartView;
class QComboBox;
class QLabel;
class QProgressBar;
class QPushButton;
class QSpinBox;
class QTableWidget;
class QThread;
class QTimer;

namespace burnish::studio {

/// Each method's colour in the charts: one of ten distinct colours, by the method's place in the
/// method table (groupColour).
QColor methodColour(Method method);
/// Each method's marker in the error-vs-cost chart (groupMarker), beside its colour.
QScatterSeries::MarkerShape methodMarker(Method method);

/// The axis the error-vs-cost charts draw values in [lo, hi] on: a log axis over whole decades when
/// they span more than one decade; within one, a linear axis with rounded ticks (a log axis there
/// labels only the decade's two ends, one of them often cut off, so it read as one label).
QAbstractAxis* errorCostAxis(const QString& title, double lo, double hi);

class ErrorCostChart : public QTabWidget {
    Q_OBJECT
public:
    /// Maps up to this many texels (1024²) are evaluated by themselves when the chart is shown or
    /// the map or power changes; larger ones only when Evaluate now is pressed.
    static constexpr size_t kAutoEvaluateTexels = size_t(1) << 20;
    bool evaluatesByItself() const;
    enum class CostAxis { NsPerLobe, BytesPerTexel };

    explicit ErrorCostChart(MaterialDocument* doc, QWidget* parent = nullptr);
    ~ErrorCostChart() override;

    /// Starts the method evaluation for the current document now (a running one is cancelled and
    /// its result dropped). The chart also does this by itself, debounced, while it is visible.
    /// While it runs, the tab shows a progress bar and a Cancel button.
    void evaluateNow();
    /// Cancels the running method evaluation: it stops at its next step, and the tab then shows
    /// "cancelled" and no points. Nothing happens when none runs.
    void cancelEvaluation();
    /// Starts the quick approximations report (the chart does this when its tab is first shown).
    void measureApproximationsNow();
    /// Cancels the running approximations measurement (it stops before its next entry).
    void cancelApproximations();
    bool evaluating() const { return m_evaluating; }
    bool measuring() const { return m_measuring; }

    void setMip(int mip);
    int mip() const;
    void setCostAxis(CostAxis axis);

    /// The scatter series of one method (one point when a result is shown), or null.
    QScatterSeries* methodSeries(Method method) const;
    /// Every series of the approximations scatter (one per group).
    QList<QScatterSeries*> approximationSeries() const;
    /// The last evaluation (null before the first finishes or when it failed).
    const EvaluationReport* report() const { return m_report.get(); }
    /// The "Energy kept" tab's table: per evaluated mip, how much of the truth's energy LEAN keeps, its
    /// three steps (evaluate's energy split: one cosine, one Gaussian's shape, the steep normals' pull)
    /// and the mixture's energy at the document's K. Empty before an evaluation.
    QTableWidget* energyTable() const { return m_energyTable; }
    /// The status line under the methods chart (progress, errors, what was measured).
    QString statusText() const;
    /// The methods tab's progress bar (0..100; shown while an evaluation runs) and Cancel button.
    QProgressBar* progressBar() const { return m_progress; }
    QPushButton* cancelButton() const { return m_cancelButton; }

signals:
    /// A method evaluation finished (successfully or not; statusText() says).
    void methodsUpdated();
    /// The approximations report finished.
    void approximationsUpdated();

protected:
    void showEvent(QShowEvent* event) override;

private:
    /// What the evaluation depends on: the normal map's identity, the base power.
    QString evaluationKey() const;
    void onDocumentChanged();
    void showMethods();
    void showApproximations();
    void showEnergy();
    /// Raises every worker's cancel flag and waits for each thread to end (destruction, app exit).
    void cancelAndJoinWorkers();

    /// A worker thread with its cancel flag; the thread is a child of the chart.
    struct Worker {
        QPointer<QThread> thread;
        std::shared_ptr<std::atomic<bool>> cancel;
    };

    MaterialDocument* m_doc;
    QChartView* m_methodsView;
    QChartView* m_approxView;
    QSpinBox* m_mipSpin;
    QComboBox* m_costCombo;
    QLabel* m_status;
    QLabel* m_approxStatus;
    QTableWidget* m_energyTable;
    QLabel* m_energyStatus;
    QPushButton* m_measureButton;
    QProgressBar* m_progress;
    QPushButton* m_cancelButton;
    QProgressBar* m_approxProgress;
    QPushButton* m_approxCancelButton;
    QTimer* m_debounce;
    std::shared_ptr<const EvaluationReport> m_report;
    std::shared_ptr<const ApproximationReport> m_approximations;
    QString m_evaluatedKey;
    QString m_runningKey;
    bool m_evaluating = false;
    bool m_measuring = false;
    /// Increases with every evaluation started: a result of an older one is dropped.
    quint64 m_evaluationGeneration = 0;
    Worker m_evaluation;     // the current evaluation (thread null when none runs)
    Worker m_approximation;  // the current approximations measurement
    QList<Worker> m_workers; // every thread started and not yet ended, cancelled ones included
    CostAxis m_costAxis = CostAxis::NsPerLobe;
};

} // namespace burnish::studio
