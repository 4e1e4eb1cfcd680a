#include "environment_panel.h"

#include <burnish/core/env/sampling.h>

#include <QCheckBox>
#include <QComboBox>
#include <QDir>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QSettings>
#include <QSignalBlocker>
#include <QSlider>
#include <QSpinBox>

#include <cmath>

namespace burnish::studio {

namespace {

// The source combo's item data: the choice, and for files the absolute path.
constexpr int kChoiceRole = Qt::UserRole;
constexpr int kPathRole = Qt::UserRole + 1;

const QString kEnvironmentFilter = "HDR environments (*.exr *.hdr *.tif *.tiff);;All files (*)";

} // namespace

QStringList EnvironmentPanel::fileExtensions() {
    return {"exr", "hdr", "tif", "tiff"};
}

EnvironmentPanel::EnvironmentPanel(MaterialDocument* doc, QWidget* parent)
    : QWidget(parent)
    , m_doc(doc) {
    setObjectName("environmentPanel");
    auto* form = new QFormLayout(this);

    m_source = new QComboBox(this);
    m_source->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_source->setMinimumContentsLength(10);
    m_source->setObjectName("environmentSource");
    m_browse = new QPushButton("Browse…", this);
    auto* sourceRow = new QHBoxLayout;
    sourceRow->addWidget(m_source, 1);
    sourceRow->addWidget(m_browse);
    form->addRow("Source", sourceRow);
    m_file = new QLabel(this);
    m_file->setWordWrap(true);
    m_file->setTextInteractionFlags(Qt::TextSelectableByMouse);
    form->addRow("", m_file);

    m_rotation = new QSlider(Qt::Horizontal, this);
    m_rotation->setObjectName("environmentRotation");
    m_rotation->setRange(-180, 180);
    m_rotationValue = new QLabel(this);
    m_rotationValue->setMinimumWidth(48);
    auto* rotationRow = new QHBoxLayout;
    rotationRow->addWidget(m_rotation, 1);
    rotationRow->addWidget(m_rotationValue);
    form->addRow("Rotation", rotationRow);

    m_intensity = new QDoubleSpinBox(this);
    m_intensity->setObjectName("environmentIntensity");
    m_intensity->setRange(0.0, kMaxEnvironmentIntensity);
    m_intensity->setDecimals(3);
    m_intensity->setSingleStep(0.1);
    m_intensity->setKeyboardTracking(false); // commit on Enter or focus-out, not per keystroke
    form->addRow("Intensity", m_intensity);

    m_lobe = new QComboBox(this);
    m_lobe->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_lobe->setMinimumContentsLength(12);
    m_lobe->setObjectName("environmentLobe");
    m_lobe->addItem("Blinn-Phong (matches the material's power)", int(LobeModel::BlinnPhong));
    m_lobe->addItem("Phong (read at a quarter of the power)", int(LobeModel::Phong));
    form->addRow("Lobe", m_lobe);
    m_lobe->setToolTip("The prefilter lobe of the environment map");

    m_fis = new QCheckBox("Filtered importance sampling", this);
    m_fis->setObjectName("environmentFis");
    m_fis->setToolTip("Sample the lobe at shading time (Beckmann, GGX or LEAN, as the material) instead "
                      "of reading the prefiltered map");
    m_samples = new QSpinBox(this);
    m_samples->setObjectName("environmentSamples");
    m_samples->setRange(1, int(kMaxFisSamples));
    m_samples->setSuffix(" samples");
    m_samples->setKeyboardTracking(false);
    form->addRow("", m_fis);
    form->addRow("Samples", m_samples);
    m_background = new QCheckBox("Show as background", this);
    m_background->setObjectName("environmentBackground");
    m_background->setToolTip("Draw the environment behind the mesh, turned and scaled as its lighting");
    form->addRow("", m_background);

    connect(m_source, &QComboBox::activated, this, &EnvironmentPanel::sourceChosen);
    connect(m_browse, &QPushButton::clicked, this, [this] { chooseFile({}); });
    connect(m_rotation, &QSlider::valueChanged, this, [this](int degrees) {
        edit([degrees](EnvironmentSettings& e) { e.rotationDegrees = degrees; }, m_rotation->isSliderDown());
    });
    connect(m_rotation, &QSlider::sliderReleased, m_doc, &MaterialDocument::endMerge);
    connect(m_intensity, &QDoubleSpinBox::valueChanged, this,
            [this](double v) { edit([v](EnvironmentSettings& e) { e.intensity = v; }); });
    connect(m_lobe, &QComboBox::activated, this, [this](int index) {
        const auto lobe = LobeModel(m_lobe->itemData(index).toInt());
        edit([lobe](EnvironmentSettings& e) { e.lobe = lobe; });
    });
    connect(m_fis, &QCheckBox::toggled, this,
            [this](bool on) { edit([on](EnvironmentSettings& e) { e.fis = on; }); });
    connect(m_samples, &QSpinBox::valueChanged, this,
            [this](int n) { edit([n](EnvironmentSettings& e) { e.fisSamples = n; }); });
    connect(m_background, &QCheckBox::toggled, this,
            [this](bool on) { edit([on](EnvironmentSettings& e) { e.background = on; }); });
    connect(m_doc, &MaterialDocument::changed, this, &EnvironmentPanel::syncFromDocument);
    syncFromDocument();
}

void EnvironmentPanel::edit(const std::function<void(EnvironmentSettings&)>& change, bool merge) {
    EnvironmentSettings e = m_doc->settings().environment;
    change(e);
    m_doc->setEnvironment(e, merge);
}

void EnvironmentPanel::setLibraryFolder(const QString& folder) {
    m_library.clear();
    QStringList patterns;
    for (const QString& ext : fileExtensions())
        patterns << "*." + ext;
    const QDir dir(folder);
    if (dir.exists())
        for (const QFileInfo& info : dir.entryInfoList(patterns, QDir::Files | QDir::Readable, QDir::Name))
            m_library << info.absoluteFilePath();
    syncFromDocument();
}

void EnvironmentPanel::chooseFile(const QString& given) {
    QString path = given;
    if (path.isEmpty()) {
        QSettings settings;
        path = QFileDialog::getOpenFileName(this, "Choose an environment",
                                            settings.value("folders/environments").toString(),
                                            kEnvironmentFilter);
        if (path.isEmpty()) return;
        settings.setValue("folders/environments", QFileInfo(path).absolutePath());
    }
    const QString absolute = QFileInfo(path).absoluteFilePath();
    edit([&absolute](EnvironmentSettings& e) {
        e.choice = EnvironmentChoice::File;
        e.path = absolute;
    });
}

void EnvironmentPanel::sourceChosen(int index) {
    const auto choice = EnvironmentChoice(m_source->itemData(index, kChoiceRole).toInt());
    const QString path = m_source->itemData(index, kPathRole).toString();
    edit([&](EnvironmentSettings& e) {
        e.choice = choice;
        if (choice == EnvironmentChoice::File) e.path = path;
    });
}

void EnvironmentPanel::syncFromDocument() {
    const EnvironmentSettings& e = m_doc->settings().environment;
    {
        const QSignalBlocker block(m_source);
        m_source->clear();
        m_source->addItem("Off");
        m_source->setItemData(0, int(EnvironmentChoice::Off), kChoiceRole);
        m_source->addItem("Procedural studio");
        m_source->setItemData(1, int(EnvironmentChoice::ProceduralStudio), kChoiceRole);
        QStringList files = m_library;
        // A file chosen by Browse… is listed too, so the picker always shows the current source.
        if (e.choice == EnvironmentChoice::File && !e.path.isEmpty() && !files.contains(e.path))
            files << e.path;
        for (const QString& path : files) {
            const int i = m_source->count();
            m_source->addItem(QFileInfo(path).fileName());
            m_source->setItemData(i, int(EnvironmentChoice::File), kChoiceRole);
            m_source->setItemData(i, path, kPathRole);
            m_source->setItemData(i, path, Qt::ToolTipRole);
        }
        int current = e.choice == EnvironmentChoice::Off ? 0 : 1;
        if (e.choice == EnvironmentChoice::File) current = 2 + int(files.indexOf(e.path));
        m_source->setCurrentIndex(current);
    }
    m_file->setText(e.choice == EnvironmentChoice::File ? e.path : QString());
    m_file->setVisible(e.choice == EnvironmentChoice::File);
    const bool on = e.choice != EnvironmentChoice::Off;
    {
        const QSignalBlocker block(m_rotation);
        m_rotation->setValue(int(std::lround(e.rotationDegrees)));
    }
    m_rotationValue->setText(QString("%1°").arg(e.rotationDegrees, 0, 'f', 0));
    {
        const QSignalBlocker block(m_intensity);
        m_intensity->setValue(e.intensity);
    }
    {
        const QSignalBlocker block(m_lobe);
        m_lobe->setCurrentIndex(m_lobe->findData(int(e.lobe)));
    }
    {
        const QSignalBlocker block(m_fis);
        m_fis->setChecked(e.fis);
    }
    {
        const QSignalBlocker block(m_samples);
        m_samples->setValue(e.fisSamples);
    }
    {
        const QSignalBlocker block(m_background);
        m_background->setChecked(e.background);
    }
    for (QWidget* w : {static_cast<QWidget*>(m_rotation), static_cast<QWidget*>(m_intensity),
                       static_cast<QWidget*>(m_fis), static_cast<QWidget*>(m_background)})
        w->setEnabled(on);
    // The prefilter lobe matters only for the prefiltered map, the sample count only for FIS.
    m_lobe->setEnabled(on && !e.fis);
    m_samples->setEnabled(on && e.fis);
}

} // namespace burnish::studio
