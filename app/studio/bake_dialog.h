// Bake & Export: preset, method, format, compression, mips and output folder for the current
// document, run through core's shared job (bake_job.h, the same as `burnish bake`) on a worker
// thread with a progress dialog that can cancel; the result is summarised in the dialog.
#pragma once

#include "material_document.h"
#include "worker_runner.h"

#include <burnish/core/bake/bake_job.h>

#include <QDialog>
#include <QMessageBox>
#include <QObject>

#include <atomic>
#include <functional>
#include <memory>

class QCheckBox;
class QComboBox;
class QLabel;
class QLineEdit;
class QProgressDialog;
class QPushButton;
class QSpinBox;

namespace burnish::studio {

/// The job the document's settings describe (the input file or "sample:hammered", the base power
/// from the gloss unless a gloss map is set, metallic 1/0 for presets that store it). With painted
/// layers, the document's composited authored gloss goes in as the job's in-memory authored gloss
/// (overriding the gloss map, which bake.json names as what was painted over; no base power).
BakeJobSpec bakeJobSpecFor(const MaterialDocument& doc);

/// Runs one bake job on a worker thread (WorkerRunner); finished carries the summary JSON text.
class BakeRunner : public WorkerRunner {
    Q_OBJECT
public:
    using WorkerRunner::WorkerRunner;
    /// Starts the job (resolve errors are reported through finished at once).
    void start(const BakeJobSpec& spec);
};

class BakeDialog : public QDialog {
    Q_OBJECT
public:
    explicit BakeDialog(MaterialDocument* doc, QWidget* parent = nullptr);

    QComboBox* formatCombo() const { return m_format; }
    QComboBox* compressionCombo() const { return m_compression; }
    QSpinBox* mipsSpin() const { return m_mips; }
    QLineEdit* outputEdit() const { return m_output; }
    QLabel* resultLabel() const { return m_result; }
    /// The dialog's fields written to the document (one undo step when anything changed).
    void commitSettings();
    /// Commits the settings and starts the bake; bakeFinished reports the outcome. When the folder
    /// already holds files of this export and replacing is not ticked, asks "Overwrite…?" first.
    void startBake();

    /// Asks a question; returns the button chosen (tests replace it to answer without a box).
    std::function<QMessageBox::StandardButton(const QString& title, const QString& text,
                                              QMessageBox::StandardButtons buttons)>
        ask;

signals:
    void bakeFinished(bool ok, const QString& message);

private:
    void refresh();
    void browse();

    MaterialDocument* m_doc;
    QComboBox* m_preset;
    QComboBox* m_method;
    QComboBox* m_format;
    QComboBox* m_compression;
    QSpinBox* m_mips;
    QLineEdit* m_output;
    QCheckBox* m_overwrite;
    QCheckBox* m_shadedFit;
    QLabel* m_result;
    QPushButton* m_bake;
    BakeRunner* m_runner;
    QProgressDialog* m_progress = nullptr;
};

} // namespace burnish::studio
