#include "bake_dialog.h"

#include <burnish/core/jobs/bake_ninja.h>
#include <burnish/core/util/numeric.h>

#include <QCheckBox>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QFileDialog>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QLineEdit>
#include <QProgressDialog>
#include <QPushButton>
#include <QRegularExpression>
#include <QSettings>
#include <QShowEvent>
#include <QSpinBox>

#include <QVBoxLayout>
#include <fmt/format.h>

#include <filesystem>

namespace burnish::studio {

namespace {

QString qs(std::string_view s) {
    return QString::fromUtf8(s.data(), int(s.size()));
}

// Progress bar resolution: per mille of the job.
constexpr int kProgressSteps = 1000;

const Preset* presetNamed(const QString& name) {
    for (const auto& p : builtinPresets())
        if (QString::fromStdString(p.name) == name) return &p;
    return nullptr;
}

Method exportMethodFor(const MaterialDocument& doc, const QString& presetName, std::optional<Method> method) {
    const Method wanted = method.value_or(doc.settings().method);
    const Preset* preset = presetNamed(presetName);
    if (!preset || checkPresetMethod(*preset, wanted)) return wanted;
    return preset->method; // the document's method cannot be stored by this preset: its default
}

} // namespace

BakeJobSpec bakeJobSpecFor(const MaterialDocument& doc, const QString& presetName,
                           std::optional<Method> method) {
    const MaterialSettings& s = doc.settings();
    const QString exportPreset = presetName.isEmpty() ? s.preset : presetName;
    const Preset* preset = presetNamed(exportPreset);
    const Preset& encodingPreset = preset ? *preset : doc.preset();
    const Method exportMethod = exportMethodFor(doc, exportPreset, method);
    // Another preset's gloss encoding: the authored gloss (gloss map and paint) keeps its powers, as a
    // preset change in the document keeps them (MaterialDocument::setPreset), without the document changing.
    const bool reencode = encodingPreset.encoding.name() != doc.preset().encoding.name();
    BakeJobSpec spec;
    spec.input = s.normalMapPath.isEmpty() ? std::string(kSampleInputPrefix) + kSampleName
                                           : s.normalMapPath.toStdString();
    spec.out = s.exportSettings.outputFolder.toStdString();
    spec.preset = exportPreset.toStdString();
    spec.method = std::string(methodName(exportMethod));
    if (!s.glossMapPath.isEmpty()) spec.gloss = s.glossMapPath.toStdString();
    const bool painted = doc.paintLayer(PaintLayerKind::Gloss).painted() ||
                         doc.paintLayer(PaintLayerKind::VarianceOffset).painted();
    if ((painted || (reencode && !s.glossMapPath.isEmpty())) && doc.authoredGloss()) {
        // The layers composited over the gloss map (or the base gloss): what the views show. It
        // overrides the gloss file (then only named in bake.json) and holds the base power per texel.
        // The document copies before its next edit while this is shared, so the worker reads a
        // snapshot.
        spec.authoredGloss = doc.authoredGloss();
        if (reencode) {
            auto values = std::make_shared<std::vector<float>>(*doc.authoredGloss());
            for (float& v : *values)
                v = float(saturate(encodingPreset.encoding.value(doc.preset().encoding.power(v))));
            spec.authoredGloss = std::move(values);
        }
    } else if (s.glossMapPath.isEmpty()) {
        spec.power = doc.power();
    }
    if (!s.exportSettings.format.isEmpty()) spec.format = s.exportSettings.format.toStdString();
    if (!s.exportSettings.compression.isEmpty())
        spec.compression = s.exportSettings.compression.toStdString();
    if (s.exportSettings.mips > 0) spec.mips = s.exportSettings.mips;
    if (!s.detailMapPath.isEmpty()) spec.detail = s.detailMapPath.toStdString();
    // A map the artist loaded anyway bakes as `--allow-implausible` (which covers the job's detail map too).
    spec.allowImplausible =
        (s.allowImplausibleNormal && !s.normalMapPath.isEmpty()) || (s.allowImplausibleDetail && spec.detail);
    if (encodingPreset.findParameter("metallic"))
        spec.metallic = s.materialClass == MaterialClass::Metal ? 1.0 : 0.0;
    // The picked colour as numbers (a calibrated pick is its table value), so bake.json records it in the
    // preset engine's terms as `burnish bake --specular R,G,B --material-class C` does.
    spec.specular = fmt::format("{:.17g},{:.17g},{:.17g}", s.specular.r, s.specular.g, s.specular.b);
    spec.materialClass = s.materialClass == MaterialClass::Metal ? "metal" : "dielectric";
    spec.force = s.exportSettings.overwrite;
    spec.shadedFit = exportMethod == Method::Mixture && s.exportSettings.shadedFit;
    // The lobes the viewport draws; a preset laid out as the mixture's writes that many lobe files.
    if (exportMethod == Method::Mixture) spec.lobes = s.mixtureLobes;
    return spec;
}

void BakeRunner::start(const BakeJobSpec& spec) {
    auto job = resolveBakeJob(spec);
    if (!job) {
        emit finished(false, QString::fromStdString(job.error()));
        return;
    }
    launch([job = std::move(job.value())](const Progress& progress) {
        auto result = runBakeJob(job, progress);
        return result ? std::pair{true, QString::fromStdString(result->summary.dump(2))}
                      : std::pair{false, QString::fromStdString(result.error())};
    });
}

BakeDialog::BakeDialog(MaterialDocument* doc, QWidget* parent)
    : QDialog(parent)
    , m_doc(doc)
    , m_runner(new BakeRunner(this)) {
    setWindowTitle("Bake & Export Textures");
    ask = [this](const QString& title, const QString& text, QMessageBox::StandardButtons buttons) {
        return QMessageBox::question(this, title, text, buttons);
    };
    m_preset = new QComboBox(this);
    for (const auto& p : builtinPresets())
        m_preset->addItem(QString::fromStdString(p.name + " — " + p.title), QString::fromStdString(p.name));
    m_method = new QComboBox(this);
    m_format = new QComboBox(this);
    m_format->addItem("preset default", QString());
    for (ExportFormat f : allExportFormats())
        m_format->addItem(qs(exportFormatName(f)), qs(exportFormatName(f)));
    m_compression = new QComboBox(this);
    m_compression->addItem("per file (preset)", QString());
    for (DdsCompression c : allDdsCompressions())
        m_compression->addItem(qs(ddsCompressionName(c)), qs(ddsCompressionName(c)));
    m_mips = new QSpinBox(this);
    m_mips->setRange(0, 32); // 32 levels cover a 2^31-texel side: more than any image holds
    m_mips->setSpecialValueText("all, down to 1×1");
    m_mips->setKeyboardTracking(false);
    m_output = new QLineEdit(this);
    m_output->setPlaceholderText("output folder");
    auto* browseButton = new QPushButton("Browse…", this);
    m_overwrite = new QCheckBox("Replace an existing set (still all-or-nothing)", this);
    m_shadedFit = new QCheckBox("Fit the mixture to the shaded truth (closer highlights, slower bake)", this);
    m_shadedFit->setToolTip("The mixture's lobes on mips 2 and up refined against the ground truth itself "
                            "(burnish bake --shaded-fit): closer highlights at texel centres, about the "
                            "same between texels, and tens of times the moment fit's bake time.");
    m_choiceNote = new QLabel(this);
    m_choiceNote->setWordWrap(true);
    m_choiceNote->setVisible(false);
    m_result = new QLabel(this);
    m_result->setWordWrap(true);
    m_result->setTextInteractionFlags(Qt::TextSelectableByMouse);
    m_result->setMinimumHeight(48);

    auto* form = new QFormLayout;
    form->addRow("Preset", m_preset);
    form->addRow("Method", m_method);
    form->addRow("", m_choiceNote);
    form->addRow("Format", m_format);
    form->addRow("DDS compression", m_compression);
    form->addRow("Mip levels", m_mips);
    form->addRow("", m_shadedFit);
    auto* outRow = new QHBoxLayout;
    outRow->addWidget(m_output, 1);
    outRow->addWidget(browseButton);
    form->addRow("Output folder", outRow);
    form->addRow("", m_overwrite);

    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Close, this);
    m_bake = buttons->addButton("Bake && Export", QDialogButtonBox::AcceptRole);
    m_bake->setDefault(true);
    connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
    connect(m_bake, &QPushButton::clicked, this, &BakeDialog::startBake);
    connect(browseButton, &QPushButton::clicked, this, &BakeDialog::browse);

    auto* layout = new QVBoxLayout(this);
    layout->addLayout(form);
    layout->addWidget(m_result);
    layout->addWidget(buttons);
    resize(560, 360);

    connect(m_preset, &QComboBox::activated, this,
            [this](int i) { choosePreset(m_preset->itemData(i).toString()); });
    connect(m_method, &QComboBox::activated, this,
            [this](int i) { chooseMethod(Method(m_method->itemData(i).toInt())); });
    connect(m_format, &QComboBox::currentIndexChanged, this, &BakeDialog::updateCompression);
    // Kept at once: a document change before the bake redraws the dialog from the settings.
    connect(m_shadedFit, &QCheckBox::clicked, this, [this] { commitSettings(); });
    connect(m_doc, &MaterialDocument::changed, this, &BakeDialog::refresh);

    connect(m_runner, &BakeRunner::progress, this, [this](double fraction, const QString& stage) {
        if (!m_progress) return;
        // The label first: setValue() on a window-modal QProgressDialog processes events, which
        // may deliver `finished` and delete the dialog before this slot resumes.
        m_progress->setLabelText("Bake & export: " + stage + "…");
        m_progress->setValue(int(fraction * kProgressSteps));
    });
    connect(m_runner, &BakeRunner::finished, this, [this](bool ok, const QString& message) {
        if (m_progress) {
            m_progress->reset();
            m_progress->deleteLater();
            m_progress = nullptr;
        }
        m_bake->setEnabled(true);
        if (ok) {
            const auto summary = nlohmann::json::parse(message.toStdString());
            m_result->setText(
                QString("Wrote %1 files + bake.json to %2 — preset %3, method %4, format %5, %6 mips, "
                        "%7 s.")
                    .arg(summary["files"].size())
                    .arg(QString::fromStdString(summary["out"].get<std::string>()),
                         QString::fromStdString(summary["preset"].get<std::string>()),
                         QString::fromStdString(summary["method"].get<std::string>()),
                         QString::fromStdString(summary["format"].get<std::string>()))
                    .arg(summary["mipCount"].get<int>())
                    .arg(summary["seconds"].get<double>(), 0, 'f', 2));
            // The picked colour as the preset's engine takes it, and what it cannot hold.
            if (summary.contains("material")) {
                QString text =
                    m_result->text() + "\nSpecular colour in " +
                    QString::fromStdString(summary["material"]["engine"]["convention"].get<std::string>()) +
                    "'s terms: " + QString::fromStdString(summary["material"]["engine"]["values"].dump());
                for (const auto& w : summary["warnings"])
                    text += "\nWarning: " + QString::fromStdString(w.get<std::string>());
                m_result->setText(text);
            }
        } else {
            m_result->setText("Not exported: " + inStudioWords(message));
        }
        emit bakeFinished(ok, message);
    });
    refresh();
}

QString inStudioWords(QString message) {
    // The bake's advice names command-line options; the dialog's controls say the same.
    message.replace("(use --force to replace the set)", "(tick \"Replace an existing set\")");
    message.replace(QRegularExpression("\\(choose png16[^()]*--allow-8bit\\)"),
                    "(choose a 16-bit or float Format, or DDS with the rgba16f compression)");
    return message;
}

QString BakeDialog::exportPreset() const {
    return m_chosenPreset.isEmpty() ? m_doc->settings().preset : m_chosenPreset;
}

Method BakeDialog::exportMethod() const {
    return exportMethodFor(*m_doc, exportPreset(), m_chosenMethod);
}

void BakeDialog::choosePreset(const QString& name) {
    if (!presetNamed(name)) {
        m_result->setText(QString("Preset '%1' is not known.").arg(name));
        return;
    }
    m_chosenPreset = name;
    refreshChoice(); // the fields typed but not yet committed stay
}

void BakeDialog::chooseMethod(Method method) {
    m_chosenMethod = method;
    refreshChoice();
}

void BakeDialog::showEvent(QShowEvent* event) {
    // Opened again: the export starts from the material as it is now.
    m_chosenPreset.clear();
    m_chosenMethod.reset();
    refresh();
    QDialog::showEvent(event);
}

void BakeDialog::refresh() {
    const MaterialSettings& s = m_doc->settings();
    m_format->setCurrentIndex(m_format->findData(s.exportSettings.format));
    m_compression->setCurrentIndex(std::max(0, m_compression->findData(s.exportSettings.compression)));
    m_mips->setValue(s.exportSettings.mips);
    if (!m_output->hasFocus()) m_output->setText(s.exportSettings.outputFolder);
    m_overwrite->setChecked(s.exportSettings.overwrite);
    m_shadedFit->setChecked(s.exportSettings.shadedFit);
    refreshChoice();
}

void BakeDialog::refreshChoice() {
    const MaterialSettings& s = m_doc->settings();
    const QString preset = exportPreset();
    const Method method = exportMethod();
    m_preset->setCurrentIndex(m_preset->findData(preset));
    m_method->clear();
    if (const Preset* p = presetNamed(preset))
        for (Method m : compatibleMethods(*p))
            m_method->addItem(qs(methodName(m)), int(m));
    m_method->setCurrentIndex(m_method->findData(int(method)));
    const bool differs = preset != s.preset || method != s.method;
    m_choiceNote->setVisible(differs);
    if (differs)
        m_choiceNote->setText(QString("For this export only: the material keeps preset %1 and method %2.")
                                  .arg(s.preset, qs(methodName(s.method))));
    m_shadedFit->setEnabled(method == Method::Mixture);
    updateCompression(); // the format "preset default" may mean DDS now
}

void BakeDialog::updateCompression() {
    const QString f = m_format->currentData().toString();
    const Preset* preset = presetNamed(exportPreset());
    const bool dds = f == "dds" || (f.isEmpty() && preset && preset->format == ExportFormat::Dds);
    m_compression->setEnabled(dds);
    if (!dds) m_compression->setCurrentIndex(0);
}

void BakeDialog::browse() {
    QSettings settings;
    const QString start =
        m_output->text().isEmpty() ? settings.value("folders/export").toString() : m_output->text();
    const QString dir = QFileDialog::getExistingDirectory(this, "Output folder", start);
    if (dir.isEmpty()) return;
    settings.setValue("folders/export", dir);
    m_output->setText(dir);
    commitSettings();
}

void BakeDialog::commitSettings() {
    ExportSettings e;
    e.format = m_format->currentData().toString();
    e.compression = m_compression->isEnabled() ? m_compression->currentData().toString() : QString();
    e.mips = m_mips->value();
    e.outputFolder = m_output->text().trimmed();
    e.overwrite = m_overwrite->isChecked();
    e.shadedFit = m_shadedFit->isChecked();
    m_doc->setExportSettings(e);
}

void BakeDialog::startBake() {
    commitSettings();
    if (m_doc->settings().exportSettings.outputFolder.isEmpty()) {
        m_result->setText("Not exported: choose an output folder first.");
        emit bakeFinished(false, m_result->text());
        return;
    }
    BakeJobSpec spec = bakeJobSpecFor(*m_doc, exportPreset(), m_chosenMethod);
    if (!spec.force) {
        // The files this export writes, from the plan (nothing baked yet): ask before replacing.
        QStringList existing;
        if (const auto job = resolveBakeJob(spec))
            if (const auto outputs = plannedBakeOutputs(*job)) {
                std::error_code ec;
                for (const auto& path : *outputs)
                    if (std::filesystem::exists(std::filesystem::symlink_status(path, ec)))
                        existing << QString::fromStdString(std::filesystem::path(path).filename().string());
            }
        if (!existing.isEmpty()) {
            const QString shown =
                existing.size() > 4 ? existing.mid(0, 4).join(", ") + ", …" : existing.join(", ");
            const auto answer =
                ask("Overwrite export",
                    QString("%1 already holds %2 of the files this export writes (%3). Overwrite them? The "
                            "folder is left with exactly the new set.")
                        .arg(m_doc->settings().exportSettings.outputFolder)
                        .arg(existing.size())
                        .arg(shown),
                    QMessageBox::Yes | QMessageBox::Cancel);
            if (answer != QMessageBox::Yes) {
                m_result->setText("Not exported: the folder's set was left as it was.");
                emit bakeFinished(false, m_result->text());
                return;
            }
            spec.force = true; // this export only: "Replace an existing set" stays as it was
        }
    }
    m_bake->setEnabled(false);
    m_result->setText("Baking…");
    m_progress = new QProgressDialog("Bake & export…", "Cancel", 0, kProgressSteps, this);
    m_progress->setWindowModality(Qt::WindowModal);
    m_progress->setMinimumDuration(300); // a quick bake finishes without a flashing dialog
    connect(m_progress, &QProgressDialog::canceled, m_runner, &BakeRunner::cancel);
    m_runner->start(spec);
}

} // namespace burnish::studio
