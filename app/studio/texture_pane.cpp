#include "texture_pane.h"

#include "elided_label.h"

#include <burnish/core/bake/export.h>

#include <QComboBox>
#include <QCoreApplication>
#include <QHBoxLayout>
#include <QLabel>
#include <QPointer>
#include <QSpinBox>
#include <QThread>
#include <QVBoxLayout>

// Qt's `emit` keyword is a macro that TBB's headers use as a name.
#pragma push_macro("emit")
#undef emit
#include <tbb/parallel_for.h>
#pragma pop_macro("emit")

#include <algorithm>

namespace burnish::studio {

// Rows converted in parallel (an 8192² map is 67 million texels).
QImage normalMapImage(const NormalMap& map) {
    QImage image(map.width, map.height, QImage::Format_RGB888);
    tbb::parallel_for(0, map.height, [&](int y) {
        uchar* row = image.scanLine(y);
        for (int x = 0; x < map.width; ++x) {
            const glm::vec3& n = map.at(x, y);
            row[3 * x + 0] = toByte(n.x * 0.5 + 0.5);
            row[3 * x + 1] = toByte(n.y * 0.5 + 0.5);
            row[3 * x + 2] = toByte(n.z * 0.5 + 0.5);
        }
    });
    return image;
}

QImage bakedChannelImage(const TextureMip& mip, int channels, int channel) {
    QImage image(mip.width, mip.height, QImage::Format_Grayscale8);
    tbb::parallel_for(0, mip.height, [&](int y) {
        uchar* row = image.scanLine(y);
        for (int x = 0; x < mip.width; ++x)
            row[x] = toByte(
                mip.texels[(size_t(y) * size_t(mip.width) + size_t(x)) * size_t(channels) + size_t(channel)]);
    });
    return image;
}

const BakedTexture* displayedBakedTexture(const BakeOutput& output) {
    if (const BakedTexture* gloss = output.find(TextureRole::Gloss)) return gloss;
    for (const auto& t : output.textures)
        if (t.role != TextureRole::Normal) return &t;
    return output.textures.empty() ? nullptr : &output.textures.front();
}

TexturePane::TexturePane(MaterialDocument* doc, QWidget* parent)
    : QWidget(parent)
    , m_doc(doc) {
    m_view = new TextureView(this);
    m_modeCombo = new QComboBox(this);
    m_modeCombo->addItem("Normal map", int(TextureMode::Normal));
    m_modeCombo->addItem("Authored gloss", int(TextureMode::Gloss)); // retitled in the preset's word
    m_modeCombo->addItem("Baked gloss (method)", int(TextureMode::BakedGloss));
    m_modeCombo->setToolTip("Which texture the view shows");
    m_mipSpin = new QSpinBox(this);
    m_mipSpin->setPrefix("mip ");
    m_mipSpin->setRange(0, 0);
    m_mipSpin->setToolTip("Mip level of the baked texture");
    m_mipSpin->setKeyboardTracking(false);
    // The header elides instead of widening the window; the whole text is in its tooltip.
    m_info = new ElidedLabel(this);
    m_modeCombo->setSizeAdjustPolicy(QComboBox::AdjustToMinimumContentsLengthWithIcon);
    m_modeCombo->setMinimumContentsLength(10);

    auto* bar = new QHBoxLayout;
    bar->setContentsMargins(8, 6, 8, 6);
    bar->setSpacing(8);
    bar->addWidget(m_modeCombo);
    bar->addWidget(m_mipSpin);
    bar->addStretch(1);
    m_info->setContentsMargins(8, 0, 8, 4);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->setSpacing(0);
    layout->addLayout(bar);
    layout->addWidget(m_info); // its own line: readable beside a narrow view
    layout->addWidget(m_view, 1);

    connect(m_modeCombo, &QComboBox::currentIndexChanged, this,
            [this](int index) { setMode(TextureMode(m_modeCombo->itemData(index).toInt())); });
    connect(m_mipSpin, &QSpinBox::valueChanged, this, [this](int mip) { setMip(mip); });
    connect(m_doc, &MaterialDocument::changed, this, [this] {
        m_bakeStale = true;
        refresh();
    });
    // While a stroke goes on: the authored view follows each dab (a conversion, no bake); the baked
    // view is baked again when the stroke ends (its undo step emits changed()).
    connect(m_doc, &MaterialDocument::layersChanged, this, [this] {
        m_bakeStale = true;
        if (m_mode == TextureMode::Gloss) refresh();
    });
    refresh();
}

TexturePane::~TexturePane() {
    // A running worker stops at its next level and finishes into a QPointer that is null by then.
    ++m_generation;
    if (m_bakeCancel) m_bakeCancel->store(true);
}

void TexturePane::setMode(TextureMode mode) {
    m_mode = mode;
    const int index = m_modeCombo->findData(int(mode));
    if (m_modeCombo->currentIndex() != index) m_modeCombo->setCurrentIndex(index);
    refresh();
}

void TexturePane::setMip(int mip) {
    m_mip = std::max(0, mip);
    if (m_mipSpin->value() != m_mip) m_mipSpin->setValue(m_mip);
    refresh();
}

void TexturePane::setPaintOverlay(bool on) {
    m_paintOverlay = on;
    refresh();
}

QString TexturePane::infoText() const {
    return m_info->text();
}

void TexturePane::setInfo(const QString& text) {
    // In Paint mode the view shows the authored values drawn over whatever the mode shows: say so.
    m_info->setText(m_paintOverlay ? QString("Authored %1 shown (Paint on; orange: over-shine) · %2")
                                         .arg(glossQuantity(m_doc->preset().encoding, false), text)
                                   : text);
}

void TexturePane::refresh() {
    // The preset's own word (roughness for gltf, unreal, …; gloss for the log-power presets).
    const QString term = glossQuantity(m_doc->preset().encoding, false);
    m_modeCombo->setItemText(m_modeCombo->findData(int(TextureMode::Gloss)), "Authored " + term);
    m_modeCombo->setItemText(m_modeCombo->findData(int(TextureMode::BakedGloss)),
                             QString("Baked %1 (method)").arg(term));
    m_mipSpin->setEnabled(m_mode == TextureMode::BakedGloss);
    const NormalMap& normal = *m_doc->maps().normal;
    switch (m_mode) {
    case TextureMode::Normal:
        // Made once per map: a method or gloss change does not touch it.
        if (m_normalImageOf != m_doc->maps().normal) {
            m_normalImage = normalMapImage(normal);
            m_normalImageOf = m_doc->maps().normal;
        }
        m_view->setImage(m_normalImage);
        setInfo(QString("normal map %1×%2").arg(normal.width).arg(normal.height));
        emit imageUpdated();
        return;
    case TextureMode::Gloss:
        if (const auto authored = m_doc->authoredGloss()) {
            // What the bake and the viewport read: the painted layers over the gloss map or base gloss.
            const TextureMip mip{normal.width, normal.height,
                                 TexelVector(authored->begin(), authored->end())};
            m_view->setImage(bakedChannelImage(mip, 1, 0));
            const bool painted = m_doc->paintLayer(PaintLayerKind::Gloss).painted() ||
                                 m_doc->paintLayer(PaintLayerKind::VarianceOffset).painted();
            setInfo(QString("authored %1 %2×%3: %4")
                        .arg(term)
                        .arg(normal.width)
                        .arg(normal.height)
                        .arg(!painted              ? QString("%1 map (first channel)").arg(term)
                             : m_doc->maps().gloss ? QString("painted layers over the %1 map").arg(term)
                                                   : QString("painted layers over base %1 %2")
                                                         .arg(term, glossText(m_doc->settings().gloss))));
        } else if (const auto& gloss = m_doc->maps().gloss) {
            TextureMip mip{gloss->width, gloss->height,
                           TexelVector(gloss->pixels.begin(), gloss->pixels.end())};
            m_view->setImage(bakedChannelImage(mip, gloss->channels, 0));
            setInfo(QString("authored %1 map %2×%3 (first channel)")
                        .arg(term)
                        .arg(gloss->width)
                        .arg(gloss->height));
        } else {
            // No map: the bake uses the base gloss on every texel, and that is what is shown.
            QImage flat(normal.width, normal.height, QImage::Format_Grayscale8);
            // Rounded through float as the composited gloss stores it, so that the first stroke does
            // not move the unpainted texels by a grey level.
            flat.fill(toByte(double(float(m_doc->settings().gloss))));
            m_view->setImage(flat);
            setInfo(QString("no %1 map: base %1 %2 on every texel")
                        .arg(term, glossText(m_doc->settings().gloss)));
        }
        emit imageUpdated();
        return;
    case TextureMode::BakedGloss:
        if (m_bakeStale) startBake();
        showBaked();
        return;
    }
}

void TexturePane::startBake() {
    m_bakeStale = false;
    m_bakeRunning = true;
    const int generation = ++m_generation;
    BakeOptions options;
    options.method = m_doc->settings().method;
    options.encoding = m_doc->preset().encoding;
    options.basePower = m_doc->power();
    // The chain the viewport and the exports bake: the method's own kernel (box for the fitted lobe).
    options.pyramid.kernel = defaultKernel(options.method);
    std::shared_ptr<const NormalMap> map = m_doc->maps().normal;
    // Only the texture the view shows (each texture is the same whatever others are baked).
    if (const auto shape = bakeShape(options, map->width, map->height))
        if (const BakedTexture* shown = displayedBakedTexture(*shape))
            options.roles = std::vector<TextureRole>{shown->role};
    // A newer bake stops this one at its next level; its fraction done is shown as it goes.
    if (m_bakeCancel) m_bakeCancel->store(true);
    auto cancel = m_bakeCancel = std::make_shared<std::atomic<bool>>(false);
    QPointer<TexturePane> progressTarget(this);
    options.progress = [cancel, progressTarget, generation, shown = std::make_shared<int>(-1)](double f) {
        if (const int percent = int(100.0 * f); percent != *shown) {
            *shown = percent;
            QMetaObject::invokeMethod(
                QCoreApplication::instance(),
                [progressTarget, generation, percent] {
                    if (progressTarget && generation == progressTarget->m_generation &&
                        progressTarget->m_bakeRunning && progressTarget->m_mode == TextureMode::BakedGloss)
                        progressTarget->setInfo(QString("baking… %1%").arg(percent));
                },
                Qt::QueuedConnection);
        }
        return !cancel->load();
    };
    std::shared_ptr<const Image> glossImage = m_doc->maps().gloss;
    // The composited authored gloss (painted layers over the gloss map or base gloss) when there is
    // one: the document copies before its next edit while the worker shares it.
    std::shared_ptr<const std::vector<float>> authored = m_doc->authoredGloss();
    QPointer<TexturePane> self(this);
    QThread* worker = QThread::create([self, generation, options, map, glossImage, authored]() mutable {
        QString error;
        std::shared_ptr<const BakeOutput> output;
        if (authored) {
            options.authoredGloss = *authored;
        } else if (glossImage) {
            auto gloss = glossFromImage(*glossImage, map->width, map->height);
            if (gloss)
                options.authoredGloss = std::move(gloss.value());
            else
                error = QString::fromStdString(gloss.error());
        }
        if (error.isEmpty()) {
            auto baked = bake(*map, options);
            if (baked)
                output = std::make_shared<const BakeOutput>(std::move(baked.value()));
            else
                error = QString::fromStdString(baked.error());
        }
        QMetaObject::invokeMethod(
            QCoreApplication::instance(),
            [self, generation, output, error] {
                if (!self || generation != self->m_generation) return; // a newer bake supersedes this one
                self->m_bakeRunning = false;
                self->m_baked = output;
                self->m_bakeError = error;
                self->showBaked();
            },
            Qt::QueuedConnection);
    });
    connect(worker, &QThread::finished, worker, &QObject::deleteLater);
    worker->start();
}

void TexturePane::showBaked() {
    if (m_mode != TextureMode::BakedGloss) return;
    if (m_bakeRunning) {
        setInfo("baking…");
        return;
    }
    if (!m_baked) {
        setInfo("bake failed: " + m_bakeError);
        return;
    }
    const BakedTexture* texture = displayedBakedTexture(*m_baked);
    if (!texture || texture->mips.empty()) return;
    const int mipCount = int(texture->mips.size());
    m_mipSpin->setRange(0, mipCount - 1);
    const int mip = std::min(m_mip, mipCount - 1);
    const TextureMip& level = texture->mips[size_t(mip)];
    const int channel = texture->role == TextureRole::Normal ? -1 : 0;
    if (channel < 0) {
        NormalMap shown;
        shown.width = level.width;
        shown.height = level.height;
        for (size_t i = 0; i < level.texels.size(); i += size_t(texture->channels))
            shown.normals.emplace_back(level.texels[i] * 2 - 1, level.texels[i + 1] * 2 - 1,
                                       texture->channels > 2 ? level.texels[i + 2] * 2 - 1 : 1.0f);
        m_view->setImage(normalMapImage(shown));
    } else {
        m_view->setImage(bakedChannelImage(level, texture->channels, channel));
    }
    // The gloss texture in the preset's own word; the other roles (Toksvig map, LEAN moments) by name.
    const QString role =
        texture->role == TextureRole::Gloss
            ? glossQuantity(m_doc->preset().encoding, false)
            : QString::fromUtf8(roleName(texture->role).data(), int(roleName(texture->role).size()));
    setInfo(QString("%1 · %2 (%3) · mip %4: %5×%6")
                .arg(QString::fromUtf8(methodName(m_baked->method).data(),
                                       int(methodName(m_baked->method).size())),
                     role, QString::fromStdString(texture->decode.empty() ? "" : texture->decode[0].name))
                .arg(mip)
                .arg(level.width)
                .arg(level.height));
    emit imageUpdated();
}

} // namespace burnish::studio
