#include "material_panel.h"

#include <QCheckBox>
#include <QColorDialog>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QDragEnterEvent>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QGridLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QMimeData>
#include <QPushButton>
#include <QSettings>
#include <QSlider>
#include <QSpinBox>
#include <QVBoxLayout>

#include <cmath>

namespace burnish::studio {

namespace {

QString qs(std::string_view s) {
    return QString::fromUtf8(s.data(), int(s.size()));
}

QLabel* swatch(QWidget* parent) {
    auto* l = new QLabel(parent);
    l->setFixedSize(36, 22);
    l->setFrameShape(QFrame::Box);
    return l;
}

void paintSwatch(QLabel* label, const LinearRgb& c) {
    label->setStyleSheet(QString("background: %1; border: 1px solid #111;").arg(srgbHex(c)));
}

QColor toQColor(const LinearRgb& c) {
    const Srgb8 s = toSrgb8(c);
    return QColor(s.r, s.g, s.b);
}

LinearRgb fromQColor(const QColor& c) {
    return {srgb8ToLinear(uint8_t(c.red())), srgb8ToLinear(uint8_t(c.green())),
            srgb8ToLinear(uint8_t(c.blue()))};
}

// The image formats the studio offers and takes from a drop.
const QStringList kImageSuffixes = {"png", "tga", "jpg", "jpeg", "exr", "tif", "tiff", "dds", "hdr"};
const QString kImageFilter = "Images (*." + kImageSuffixes.join(" *.") + ");;All files (*)";

} // namespace

bool isImageFileName(const QString& path) {
    return kImageSuffixes.contains(QFileInfo(path).suffix().toLower());
}

QString srgbHex(const LinearRgb& c) {
    return toQColor(c).name(QColor::HexRgb);
}

QString colorText(const LinearRgb& c) {
    const Srgb8 s = toSrgb8(c);
    return QString("sRGB %1 %2 %3 · linear %4 %5 %6")
        .arg(s.r)
        .arg(s.g)
        .arg(s.b)
        .arg(c.r, 0, 'f', 3)
        .arg(c.g, 0, 'f', 3)
        .arg(c.b, 0, 'f', 3);
}

void MapSlotWidget::setTitle(const QString& title) {
    m_title->setText("<b>" + title.toHtmlEscaped() + "</b>");
}

MapSlotWidget::MapSlotWidget(MapSlot slot, const QString& title, QWidget* parent)
    : QFrame(parent)
    , m_slot(slot) {
    setAcceptDrops(true);
    setFrameShape(QFrame::StyledPanel);
    setObjectName("mapSlot");
    auto* name = new QLabel(this);
    m_title = name;
    setTitle(title);
    m_file = new QLabel(this);
    m_file->setTextInteractionFlags(Qt::TextSelectableByMouse);
    m_diagnostics = new QLabel(this);
    m_diagnostics->setWordWrap(true);
    m_diagnostics->setStyleSheet("color: palette(mid);");
    auto* load = new QPushButton("Load…", this);
    m_clear = new QPushButton("Clear", this);
    load->setToolTip("Load an image into this slot (or drop one here)");
    connect(load, &QPushButton::clicked, this, [this] { emit loadRequested(m_slot, {}); });
    connect(m_clear, &QPushButton::clicked, this, [this] { emit clearRequested(m_slot); });

    auto* top = new QHBoxLayout;
    top->addWidget(name);
    top->addStretch(1);
    top->addWidget(load);
    top->addWidget(m_clear);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(8, 6, 8, 6);
    layout->setSpacing(2);
    layout->addLayout(top);
    layout->addWidget(m_file);
    layout->addWidget(m_diagnostics);
}

void MapSlotWidget::setState(const QString& path, const QStringList& diagnostics, bool isSample) {
    m_file->setText(path.isEmpty() ? (isSample ? "built-in sample" : "— none (drop an image here) —")
                                   : QFileInfo(path).fileName());
    m_file->setToolTip(path);
    m_diagnostics->setText(diagnostics.join("\n"));
    m_diagnostics->setVisible(!diagnostics.isEmpty());
    m_clear->setEnabled(!path.isEmpty());
}

void MapSlotWidget::dragEnterEvent(QDragEnterEvent* event) {
    // Only images are a slot's; a project or a mesh is not accepted here and goes to the window.
    if (event->mimeData()->hasUrls() && event->mimeData()->urls().first().isLocalFile() &&
        isImageFileName(event->mimeData()->urls().first().toLocalFile())) {
        event->acceptProposedAction();
        setStyleSheet("#mapSlot { border: 1px solid palette(highlight); }");
        return;
    }
    event->ignore();
}

void MapSlotWidget::dragLeaveEvent(QDragLeaveEvent*) {
    setStyleSheet({});
}

void MapSlotWidget::dropEvent(QDropEvent* event) {
    setStyleSheet({});
    const QList<QUrl> urls = event->mimeData()->urls();
    if (urls.isEmpty() || !urls.first().isLocalFile() || !isImageFileName(urls.first().toLocalFile())) {
        event->ignore();
        return;
    }
    event->acceptProposedAction();
    emit loadRequested(m_slot, urls.first().toLocalFile());
}

MaterialPanel::MaterialPanel(MaterialDocument* doc, QWidget* parent)
    : QWidget(parent)
    , m_doc(doc) {
    m_preset = new QComboBox(this);
    m_preset->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_preset->setMinimumContentsLength(8);
    for (const auto& p : builtinPresets())
        m_preset->addItem(QString::fromStdString(p.name), QString::fromStdString(p.name));
    m_preset->setToolTip("Engine preset: gloss encoding, packing and default method");
    m_method = new QComboBox(this);
    m_method->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_method->setMinimumContentsLength(10);
    m_method->setToolTip("Prefiltering method (those the preset can store)");
    m_lobes = new QSpinBox(this);
    m_lobes->setRange(1, kMaxMixtureLobes);
    m_lobes->setKeyboardTracking(false); // commit on Enter or focus-out, not per keystroke
    m_lobes->setObjectName("materialLobes");
    m_lobes->setToolTip("Lobes per texel of the mixture (K): more keeps more of each footprint's highlight "
                        "shape, at one more texture and lobe evaluation each; 1 is LEAN, 3 the default");
    m_class = new QComboBox(this);
    m_class->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_class->setMinimumContentsLength(8);
    m_class->addItem("Metal", int(MaterialClass::Metal));
    m_class->addItem("Dielectric", int(MaterialClass::Dielectric));

    m_specular = new QComboBox(this);
    m_specular->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_specular->setMinimumContentsLength(10);
    for (const auto& m : builtinMaterialTable().materials)
        m_specular->addItem(QString("%1 (%2)").arg(QString::fromStdString(m.name), toString(m.materialClass)),
                            QString::fromStdString(m.name));
    m_specular->addItem("Custom colour…", QString());
    m_specular->setToolTip("Calibrated specular colour (F0) from core's material table, or a custom colour");
    m_specularSwatch = swatch(this);
    // F0 as numbers: linear (what the shading and the exports use) and 8-bit sRGB (what charts and
    // colour pickers print); either edits the colour, which becomes a custom one.
    const char* channelNames[3] = {"red", "green", "blue"};
    for (int c = 0; c < 3; ++c) {
        auto* linear = new QDoubleSpinBox(this);
        linear->setRange(0.0, 1.0);
        linear->setDecimals(kF0Decimals);
        linear->setSingleStep(0.005);
        linear->setKeyboardTracking(false); // commit on Enter or focus-out, not per keystroke
        linear->setButtonSymbols(QAbstractSpinBox::NoButtons);
        linear->setObjectName(QString("specularLinear%1").arg(c));
        linear->setToolTip(
            QString("Linear F0, %1 channel (0.04 is a common dielectric)").arg(channelNames[c]));
        m_specularLinear[c] = linear;
        auto* srgb = new QSpinBox(this);
        srgb->setRange(0, 255);
        srgb->setKeyboardTracking(false);
        srgb->setButtonSymbols(QAbstractSpinBox::NoButtons);
        srgb->setObjectName(QString("specularSrgb%1").arg(c));
        srgb->setToolTip(QString("F0 as 8-bit sRGB, %1 channel").arg(channelNames[c]));
        m_specularSrgb[c] = srgb;
    }
    m_specularGrey = new QCheckBox("grey (one value for all)", this);
    m_specularGrey->setObjectName("specularGrey");
    m_specularGrey->setChecked(true);
    m_specularGrey->setToolTip("On: a number typed into one channel sets all three (a grey F0, as "
                               "dielectrics have); off: each channel on its own (a tinted metal)");
    auto* pickSpecular = new QPushButton("Pick…", this);
    pickSpecular->setToolTip("Choose a custom specular colour in a colour dialog (sRGB)");
    m_albedoSwatch = swatch(this);
    m_albedoValues = new QLabel(this);
    auto* albedoButton = new QPushButton("Choose…", this);

    m_glossSlider = new QSlider(Qt::Horizontal, this);
    m_glossSlider->setRange(0, kGlossSteps);
    m_glossSpin = new QDoubleSpinBox(this);
    m_glossSpin->setRange(0.0, 1.0);
    m_glossSpin->setDecimals(kGlossDecimals);
    m_glossSpin->setSingleStep(0.01);
    m_glossSpin->setKeyboardTracking(false); // commit on Enter or focus-out, not per keystroke
    m_glossSpin->setObjectName("materialGloss");
    m_power = new QLabel(this);
    m_power->setMinimumWidth(90);
    m_encoding = new QLabel(this);
    m_encoding->setStyleSheet("color: palette(mid);");

    auto* materialBox = new QGroupBox("Material", this);
    auto* form = new QFormLayout(materialBox);
    m_form = form;
    form->setLabelAlignment(Qt::AlignRight);
    form->addRow("Preset", m_preset);
    form->addRow("Method", m_method);
    form->addRow("Lobes", m_lobes);
    form->addRow("Class", m_class);
    form->addRow("Specular", m_specular);
    auto* specGrid = new QGridLayout;
    specGrid->setHorizontalSpacing(4);
    specGrid->addWidget(m_specularSwatch, 0, 0);
    specGrid->addWidget(new QLabel("linear", this), 0, 1);
    specGrid->addWidget(new QLabel("sRGB", this), 1, 1);
    for (int c = 0; c < 3; ++c) {
        specGrid->addWidget(m_specularLinear[c], 0, 2 + c);
        specGrid->addWidget(m_specularSrgb[c], 1, 2 + c);
        specGrid->setColumnStretch(2 + c, 1);
    }
    specGrid->addWidget(pickSpecular, 1, 0);
    specGrid->addWidget(m_specularGrey, 2, 2, 1, 3);
    form->addRow("F0", specGrid);
    auto* albedoRow = new QHBoxLayout;
    albedoRow->addWidget(m_albedoSwatch);
    albedoRow->addWidget(m_albedoValues, 1);
    albedoRow->addWidget(albedoButton);
    form->addRow("Albedo", albedoRow);
    auto* glossRow = new QHBoxLayout;
    glossRow->addWidget(m_glossSlider, 1);
    glossRow->addWidget(m_glossSpin);
    glossRow->addWidget(m_power);
    m_glossLabel = new QLabel("Gloss", this); // the preset's word: refresh()
    form->addRow(m_glossLabel, glossRow);
    form->addRow("", m_encoding);

    auto* mapsBox = new QGroupBox("Maps", this);
    auto* mapsLayout = new QVBoxLayout(mapsBox);
    m_slots[0] = new MapSlotWidget(MapSlot::Normal, "Normal", this);
    m_slots[1] = new MapSlotWidget(MapSlot::Gloss, "Gloss", this);
    m_slots[2] = new MapSlotWidget(MapSlot::Detail, "Detail normal", this);
    for (auto* s : m_slots) {
        mapsLayout->addWidget(s);
        connect(s, &MapSlotWidget::loadRequested, this, &MaterialPanel::loadMap);
        connect(s, &MapSlotWidget::clearRequested, m_doc, &MaterialDocument::clearMap);
    }

    // Combos size to a short minimum and stretch with the dock, never forcing a horizontal scroll.
    for (QComboBox* c : {m_preset, m_method, m_class, m_specular}) {
        c->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
        c->setMinimumContentsLength(12);
    }
    m_albedoValues->setWordWrap(true);
    m_encoding->setWordWrap(true);

    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(8, 8, 8, 8);
    layout->setSpacing(10);
    layout->addWidget(materialBox);
    layout->addWidget(mapsBox);
    layout->addStretch(1);

    connect(m_preset, &QComboBox::activated, this, [this](int i) {
        if (const Status st = m_doc->setPreset(m_preset->itemData(i).toString()); !st)
            emit errorOccurred("Preset", QString::fromStdString(st.error()));
    });
    connect(m_method, &QComboBox::activated, this, [this](int i) {
        if (const Status st = m_doc->setMethod(Method(m_method->itemData(i).toInt())); !st)
            emit errorOccurred("Method", QString::fromStdString(st.error()));
    });
    connect(m_lobes, &QSpinBox::valueChanged, this, [this](int k) {
        if (!m_refreshing) m_doc->setMixtureLobes(k);
    });
    connect(m_class, &QComboBox::activated, this,
            [this](int i) { m_doc->setMaterialClass(MaterialClass(m_class->itemData(i).toInt())); });
    connect(m_specular, &QComboBox::activated, this, [this](int i) {
        const QString name = m_specular->itemData(i).toString();
        if (name.isEmpty()) {
            chooseCustomSpecular();
            refresh(); // a cancelled dialog puts the combo back on the document's choice
            return;
        }
        if (const Status st = m_doc->setSpecularMaterial(name); !st)
            emit errorOccurred("Specular colour", QString::fromStdString(st.error()));
    });
    for (int c = 0; c < 3; ++c) {
        connect(m_specularLinear[c], &QDoubleSpinBox::valueChanged, this,
                [this, c](double v) { editSpecularChannel(c, v); });
        connect(m_specularSrgb[c], &QSpinBox::valueChanged, this,
                [this, c](int v) { editSpecularChannel(c, srgb8ToLinear(uint8_t(v))); });
    }
    connect(pickSpecular, &QPushButton::clicked, this, &MaterialPanel::chooseCustomSpecular);
    connect(albedoButton, &QPushButton::clicked, this, &MaterialPanel::chooseAlbedo);
    connect(m_glossSlider, &QSlider::valueChanged, this, [this](int v) {
        if (!m_refreshing) m_doc->setGloss(double(v) / kGlossSteps, m_glossSlider->isSliderDown());
    });
    connect(m_glossSlider, &QSlider::sliderReleased, m_doc, &MaterialDocument::endMerge);
    connect(m_glossSpin, &QDoubleSpinBox::valueChanged, this, [this](double v) {
        if (!m_refreshing) m_doc->setGloss(v, false);
    });
    connect(m_doc, &MaterialDocument::changed, this, &MaterialPanel::refresh);
    refresh();
}

MapSlotWidget* MaterialPanel::slotWidget(MapSlot slot) const {
    return m_slots[int(slot)];
}

bool MaterialPanel::loadMap(MapSlot slot, const QString& requested) {
    QString path = requested;
    if (path.isEmpty()) {
        QSettings settings;
        path = QFileDialog::getOpenFileName(this, QString("Load %1 map").arg(mapSlotName(slot)),
                                            settings.value("folders/maps").toString(), kImageFilter);
        if (path.isEmpty()) return false;
        settings.setValue("folders/maps", QFileInfo(path).absolutePath());
    }
    if (m_backgroundLoads) {
        m_doc->loadMapInBackground(slot, QFileInfo(path).absoluteFilePath());
        return true;
    }
    if (const Status st = m_doc->loadMap(slot, QFileInfo(path).absoluteFilePath()); !st) {
        emit errorOccurred(QString("Cannot load the %1 map").arg(mapSlotName(slot)),
                           QString::fromStdString(st.error()));
        return false;
    }
    return true;
}

void MaterialPanel::chooseCustomSpecular() {
    const QColor c =
        QColorDialog::getColor(toQColor(m_doc->settings().specular), this, "Custom specular colour (sRGB)");
    if (c.isValid()) m_doc->setCustomSpecular(fromQColor(c));
}

void MaterialPanel::editSpecularChannel(int channel, double linear) {
    if (m_refreshing) return;
    LinearRgb f0 = m_doc->settings().specular;
    double* channels[3] = {&f0.r, &f0.g, &f0.b};
    if (m_specularGrey->isChecked())
        f0 = LinearRgb::grey(linear);
    else
        *channels[channel] = linear;
    m_doc->setCustomSpecular(f0);
}

void MaterialPanel::chooseAlbedo() {
    const QColor c = QColorDialog::getColor(toQColor(m_doc->settings().albedo), this, "Albedo (sRGB)");
    if (c.isValid()) m_doc->setAlbedo(fromQColor(c));
}

void MaterialPanel::refresh() {
    m_refreshing = true;
    const MaterialSettings& s = m_doc->settings();
    m_preset->setCurrentIndex(m_preset->findData(s.preset));
    m_preset->setToolTip(QString::fromStdString(m_doc->preset().title + "\n" + m_doc->preset().conversion));

    m_method->clear();
    for (Method m : m_doc->availableMethods())
        m_method->addItem(qs(methodName(m)), int(m));
    m_method->setCurrentIndex(m_method->findData(int(s.method)));
    m_method->setToolTip(qs(methodDescription(s.method)));
    m_lobes->setValue(s.mixtureLobes);
    m_form->setRowVisible(m_lobes, s.method == Method::Mixture);

    m_class->setCurrentIndex(m_class->findData(int(s.materialClass)));
    m_specular->setCurrentIndex(m_specular->findData(s.specularName));
    paintSwatch(m_specularSwatch, s.specular);
    const F0Classification f0 = classifyF0(builtinMaterialTable(), s.specular);
    m_specularSwatch->setToolTip(
        QString("%1 — classified as %2%3")
            .arg(colorText(s.specular), toString(f0.f0Class), f0.tinted ? ", tinted" : ""));
    const Srgb8 srgb = toSrgb8(s.specular);
    const double linear[3] = {s.specular.r, s.specular.g, s.specular.b};
    const int srgbChannels[3] = {srgb.r, srgb.g, srgb.b};
    for (int c = 0; c < 3; ++c) {
        m_specularLinear[c]->setValue(linear[c]);
        m_specularSrgb[c]->setValue(srgbChannels[c]);
    }
    // A tinted colour is edited per channel; a grey one keeps the artist's choice.
    if (!(s.specular.r == s.specular.g && s.specular.g == s.specular.b)) m_specularGrey->setChecked(false);
    paintSwatch(m_albedoSwatch, s.albedo);
    m_albedoValues->setText(colorText(s.albedo));

    m_glossSlider->setValue(int(std::lround(s.gloss * kGlossSteps)));
    m_glossSpin->setValue(s.gloss);
    m_power->setText(QString("power %1").arg(m_doc->power(), 0, 'g', 5));
    const Preset& preset = m_doc->preset();
    m_glossLabel->setText(glossQuantity(preset.encoding));
    m_glossSpin->setToolTip(
        QString("%1 in the preset's encoding, 0 to 1").arg(glossQuantity(preset.encoding)));
    m_slots[1]->setTitle(glossQuantity(preset.encoding));
    m_encoding->setText(QString("encoding %1: %2")
                            .arg(QString::fromStdString(preset.encoding.name()),
                                 QString::fromStdString(preset.encoding.formula())));

    for (auto* slot : m_slots) {
        QString path;
        switch (slot->slot()) {
        case MapSlot::Normal:
            path = s.normalMapPath;
            break;
        case MapSlot::Gloss:
            path = s.glossMapPath;
            break;
        case MapSlot::Detail:
            path = s.detailMapPath;
            break;
        }
        slot->setState(path, m_doc->diagnostics(slot->slot()), slot->slot() == MapSlot::Normal);
    }
    m_refreshing = false;
}

} // namespace burnish::studio
