// The environment panel (a dock): the viewport's environment lighting — Off, the procedural studio,
// or an equirectangular HDR file (.exr/.hdr/.tif, from a library folder or Browse…) — with its
// rotation, intensity, prefilter lobe, filtered importance sampling with a sample count, and whether
// it is drawn behind the mesh. Every
// control edits the MaterialDocument (undoable); the panel redraws from its changed() signal.
#pragma once

#include "material_document.h"

#include <QWidget>

#include <functional>

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QPushButton;
class QSlider;
class QSpinBox;

namespace burnish::studio {

class EnvironmentPanel : public QWidget {
    Q_OBJECT
public:
    explicit EnvironmentPanel(MaterialDocument* doc, QWidget* parent = nullptr);

    /// Lists the HDR files of `folder` (.exr, .hdr, .tif, .tiff) in the source picker, after Off and
    /// the procedural studio. A missing folder lists none.
    void setLibraryFolder(const QString& folder);
    /// Chooses a file as the environment (one undo step); an empty path asks with a file dialog.
    void chooseFile(const QString& path);

    // The controls, for tests.
    QComboBox* sourceCombo() const { return m_source; }
    QSlider* rotationSlider() const { return m_rotation; }
    QDoubleSpinBox* intensitySpin() const { return m_intensity; }
    QComboBox* lobeCombo() const { return m_lobe; }
    QCheckBox* fisCheck() const { return m_fis; }
    QSpinBox* samplesSpin() const { return m_samples; }
    QCheckBox* backgroundCheck() const { return m_background; }

    /// The extensions the picker accepts, lower case without the dot.
    static QStringList fileExtensions();

private:
    void syncFromDocument();
    void sourceChosen(int index);
    void edit(const std::function<void(EnvironmentSettings&)>& change, bool merge = false);

    MaterialDocument* m_doc;
    QComboBox* m_source;
    QPushButton* m_browse;
    QLabel* m_file;
    QSlider* m_rotation;
    QLabel* m_rotationValue;
    QDoubleSpinBox* m_intensity;
    QComboBox* m_lobe;
    QCheckBox* m_fis;
    QSpinBox* m_samples;
    QCheckBox* m_background;
    QStringList m_library; // absolute paths listed after the two fixed entries
};

} // namespace burnish::studio
