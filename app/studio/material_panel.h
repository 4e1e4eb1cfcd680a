// The material panel (a dock): preset, method, metal/dielectric, specular colour (core's calibrated
// table or a custom colour, shown as sRGB and linear), albedo, base gloss with its power, and the
// normal/gloss/detail map slots (drop an image on a slot, or Load…). Every control edits the
// MaterialDocument; the panel redraws from the document's changed() signal.
#pragma once

#include "material_document.h"

#include <QFrame>
#include <QWidget>

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QFormLayout;
class QSpinBox;
class QLabel;
class QPushButton;
class QSlider;

namespace burnish::studio {

/// Whether a file name is one of the image formats the studio reads (by its extension: PNG, TGA,
/// JPEG, EXR, TIFF, DDS, HDR): what a map slot takes when dropped on it.
bool isImageFileName(const QString& path);

/// One image slot: title, file name, Load…/Clear, the decoder's diagnostics; accepts dropped images
/// (anything else dropped on it goes on to the window, which routes it by its kind).
class MapSlotWidget : public QFrame {
    Q_OBJECT
public:
    MapSlotWidget(MapSlot slot, const QString& title, QWidget* parent = nullptr);
    MapSlot slot() const { return m_slot; }
    void setState(const QString& path, const QStringList& diagnostics, bool isSample);
    void setTitle(const QString& title);

signals:
    void loadRequested(MapSlot slot, const QString& path); // path empty: ask with a file dialog
    void clearRequested(MapSlot slot);

protected:
    void dragEnterEvent(QDragEnterEvent* event) override;
    void dragLeaveEvent(QDragLeaveEvent* event) override;
    void dropEvent(QDropEvent* event) override;

private:
    MapSlot m_slot;
    QLabel* m_title;
    QLabel* m_file;
    QLabel* m_diagnostics;
    QPushButton* m_clear;
};

class MaterialPanel : public QWidget {
    Q_OBJECT
public:
    explicit MaterialPanel(MaterialDocument* doc, QWidget* parent = nullptr);

    // The controls, for tests and for the main window's shortcuts.
    QComboBox* presetCombo() const { return m_preset; }
    QComboBox* methodCombo() const { return m_method; }
    QComboBox* classCombo() const { return m_class; }
    QComboBox* specularCombo() const { return m_specular; }
    QSlider* glossSlider() const { return m_glossSlider; }
    QDoubleSpinBox* glossSpin() const { return m_glossSpin; }
    /// The mixture's lobe count K (its row shows while the method is the mixture).
    QSpinBox* lobesSpin() const { return m_lobes; }
    /// F0 as numbers: linear and 8-bit sRGB per channel, and whether one typed value sets all three.
    QDoubleSpinBox* specularLinearSpin(int channel) const { return m_specularLinear[channel]; }
    QSpinBox* specularSrgbSpin(int channel) const { return m_specularSrgb[channel]; }
    QCheckBox* specularGreyCheck() const { return m_specularGrey; }
    MapSlotWidget* slotWidget(MapSlot slot) const;

    /// Loads a map into a slot (a file dialog when path is empty). False when it is not loaded: an
    /// error (sent to errorOccurred, nothing changes) or a cancelled dialog.
    bool loadMap(MapSlot slot, const QString& path);
    /// Decode maps on a worker thread (the studio's own window: a big file never freezes it); the
    /// load then reports through the document's mapLoadFinished. Off by default (tests read the
    /// document right after loadMap).
    void setBackgroundLoads(bool on) { m_backgroundLoads = on; }

    /// Slider steps across the gloss range [0, 1].
    static constexpr int kGlossSteps = 1000;
    /// Places of the linear F0 fields (0.0400; iron's 0.5620).
    static constexpr int kF0Decimals = 4;

signals:
    /// A one-line message for the user (a map that failed to load, ...).
    void errorOccurred(const QString& title, const QString& message);

private:
    void refresh();
    void chooseCustomSpecular();
    /// A number typed into an F0 field: that channel (or, with "grey" on, all three), as a custom colour.
    void editSpecularChannel(int channel, double linear);
    void chooseAlbedo();

    MaterialDocument* m_doc;
    QComboBox* m_preset;
    QComboBox* m_method;
    QSpinBox* m_lobes;
    QFormLayout* m_form;
    QComboBox* m_class;
    QComboBox* m_specular;
    QLabel* m_specularSwatch;
    QDoubleSpinBox* m_specularLinear[3];
    QSpinBox* m_specularSrgb[3];
    QCheckBox* m_specularGrey;
    QLabel* m_albedoSwatch;
    QLabel* m_albedoValues;
    QSlider* m_glossSlider;
    QDoubleSpinBox* m_glossSpin;
    QLabel* m_power;
    QLabel* m_glossLabel;
    QLabel* m_encoding;
    MapSlotWidget* m_slots[3];
    bool m_refreshing = false;
    bool m_backgroundLoads = false;
};

/// "#rrggbb" of a linear colour's sRGB encoding.
QString srgbHex(const LinearRgb& c);
/// "sRGB 212 212 212 · linear 0.651 0.651 0.651".
QString colorText(const LinearRgb& c);

} // namespace burnish::studio
