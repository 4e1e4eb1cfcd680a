// Bake & Export: preset, method, format, compression, mips and output folder for the current
// document, run through core's shared job (bake_job.h, the same as `burnish bake`) on a worker
// thread with a progress dialog that can cancel; the result is summarised in the dialog.
#pragma once

#include "material_document.h"
#include "worker_runner.h"

#include <burnish/core/jobs/bake_job.h>

#include <QDialog>
#include <QMessageBox>
#include <QObject>

#include <atomic>
#include <functional>
#include <memory>
#include <optional>

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
/// `preset` and `method` export with another preset or method than the document's (empty / none:
/// the document's; a method the preset cannot store: the preset's default). The powers are the
/// document's: under a preset of another gloss encoding a gloss map or paint goes in re-encoded, as
/// the authored gloss.
BakeJobSpec bakeJobSpecFor(const MaterialDocument& doc, const QString& preset = {},
                           std::optional<Method> method = std::nullopt);

/// A bake's message with its command-line advice ("use --force", "--allow-8bit") put in the
/// dialog's own words: no message in the studio names a command-line option.
QString inStudioWords(QString message);

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

    QComboBox* presetCombo() const { return m_preset; }
    QComboBox* methodCombo() const { return m_method; }
    QComboBox* formatCombo() const { return m_format; }
    QComboBox* compressionCombo() const { return m_compression; }
    QSpinBox* mipsSpin() const { return m_mips; }
    QLineEdit* outputEdit() const { return m_output; }
    QLabel* resultLabel() const { return m_result; }
    /// The dialog's export fields (format, compression, mips, folder, replace, shaded fit) written to
    /// the document's export settings, which the project keeps (one undo step when anything changed).
    void commitSettings();
    /// The preset and method this export uses. They are the dialog's own: choosing them leaves the
    /// document (its preset, method, painted layers, history) as it was. Each time the dialog opens
    /// they start from the document's.
    void choosePreset(const QString& name);
    void chooseMethod(Method method);
    QString exportPreset() const;
    Method exportMethod() const;
    /// Commits the settings and starts the bake; bakeFinished reports the outcome. When the folder
    /// already holds files of this export and replacing is not ticked, asks "Overwrite…?" first.
    void startBake();

    /// Asks a question; returns the button chosen (tests replace it to answer without a box).
    std::function<QMessageBox::StandardButton(const QString& title, const QString& text,
                                              QMessageBox::StandardButtons buttons)>
        ask;

signals:
    void bakeFinished(bool ok, const QString& message);

protected:
    void showEvent(QShowEvent* event) override;

private:
    /// Every field from the document's export settings, then refreshChoice().
    void refresh();
    /// The preset and method combos, their note, and what they enable.
    void refreshChoice();
    void browse();
    /// DDS compression applies only where the format (or the export preset's default) is DDS.
    void updateCompression();

    MaterialDocument* m_doc;
    QComboBox* m_preset;
    QComboBox* m_method;
    QComboBox* m_format;
    QComboBox* m_compression;
    QSpinBox* m_mips;
    QLineEdit* m_output;
    QCheckBox* m_overwrite;
    QCheckBox* m_shadedFit;
    QLabel* m_choiceNote; // where the export's preset or method is not the document's
    QLabel* m_result;
    QString m_chosenPreset; // the export's preset; empty: the document's
    std::optional<Method>
        m_chosenMethod; // the export's method; none: the document's (or the preset's default)
    QPushButton* m_bake;
    BakeRunner* m_runner;
    QProgressDialog* m_progress = nullptr;
};

} // namespace burnish::studio
