// The central 2D texture pane: which texture to show (the normal map as colours, the authored gloss —
// the document's painted layers composited over the gloss map or base gloss —, or the current
// method's bake of that authored gloss at a chosen mip, baked by core in a worker thread) over a
// TextureView.
#pragma once

#include "material_document.h"
#include "texture_view.h"

#include <burnish/core/bake/bake.h>

#include <QImage>
#include <QWidget>

#include <atomic>
#include <memory>

class QComboBox;
class QLabel;
class QSpinBox;

namespace burnish::studio {

class ElidedLabel;

enum class TextureMode { Normal, Gloss, BakedGloss };

/// The normal map as colours (n·0.5 + 0.5 in RGB).
QImage normalMapImage(const NormalMap& map);
/// One channel of a mip of a baked texture as grey.
QImage bakedChannelImage(const TextureMip& mip, int channels, int channel);
/// The baked texture a "baked gloss" view shows for a method: the gloss map where the method has
/// one, else the first non-normal role (Toksvig map, CLEAN variance, LEAN moments), else the normal.
const BakedTexture* displayedBakedTexture(const BakeOutput& output);

class TexturePane : public QWidget {
    Q_OBJECT
public:
    explicit TexturePane(MaterialDocument* doc, QWidget* parent = nullptr);
    ~TexturePane() override;

    TextureView* view() const { return m_view; }
    TextureMode mode() const { return m_mode; }
    void setMode(TextureMode mode);
    void setMip(int mip);
    /// Paint mode draws the authored values over the view: the info line says so.
    void setPaintOverlay(bool on);
    QString infoText() const;
    /// True while a bake for the baked view is running.
    bool baking() const { return m_bakeRunning; }

signals:
    /// The displayed image changed (a bake finished, the mode or the document changed).
    void imageUpdated();

private:
    void refresh();
    void startBake();
    void showBaked();

    MaterialDocument* m_doc;
    TextureView* m_view;
    QComboBox* m_modeCombo;
    QSpinBox* m_mipSpin;
    ElidedLabel* m_info;
    bool m_paintOverlay = false;
    void setInfo(const QString& text);
    TextureMode m_mode = TextureMode::Normal;
    int m_mip = 0;
    std::shared_ptr<const BakeOutput> m_baked;
    QString m_bakeError;
    bool m_bakeRunning = false;
    bool m_bakeStale = true;
    int m_generation = 0;
    // Set to stop the running bake when a newer one starts (it stops at its next level).
    std::shared_ptr<std::atomic<bool>> m_bakeCancel;
    // The normal map's image, kept while the document's map stays the same.
    std::shared_ptr<const NormalMap> m_normalImageOf;
    QImage m_normalImage;
};

} // namespace burnish::studio
