// burnish-studio's main window: the material document with its undo stack, the central 2D texture
// pane (the 3D viewport joins the central splitter later), dockable panels, menus with shortcuts,
// the status bar, settings kept between runs, drag and drop, projects with autosave and recovery.
#pragma once

#include "material_document.h"
#include "project.h"

#include <burnish/core/jobs/gltf.h>

#include <burnish/core/util/result.h>

#include <QMainWindow>
#include <QMessageBox>

#include <array>
#include <functional>
#include <memory>

class QDialog;
class QLockFile;
class QAction;
class QDockWidget;
class QLabel;
class QMenu;
class QProgressDialog;
class QTimer;

namespace burnish::studio {

class AutosaveWriter;
class BakeDialog;
class GltfRunner;
class MaterialPanel;
class PaintTool;
class TexturePane;

/// docs/studio-guide.md (Markdown, written for artists), which Help ▸ Studio Guide shows.
QString studioGuideMarkdown();

/// `window` moved and shrunk as little as it takes to lie inside `available` (a screen's free area).
QRect fitInside(const QRect& window, const QRect& available);

class MainWindow : public QMainWindow {
    Q_OBJECT
public:
    explicit MainWindow(QWidget* parent = nullptr);
    ~MainWindow() override;

    MaterialDocument* document() const { return m_doc; }
    MaterialPanel* materialPanel() const { return m_panel; }
    TexturePane* texturePane() const { return m_texturePane; }
    PaintTool* paintTool() const { return m_paintTool; }
    /// The dock holding the texture pane (the 2D view).
    QDockWidget* textureDock() const { return m_textureDock; }
    /// View ▸ Reset Layout: every panel shown, docked and placed as the first layout places it.
    void resetLayout();
    BakeDialog* bakeDialog();
    QString projectPath() const { return m_projectPath; }
    bool isModified() const;

    /// Opens a project: on any error the message is shown and the document stays as it was.
    bool openProject(const QString& path);
    /// A .burnish project is opened; any other file is loaded as the normal map of the current
    /// document (what dropping it on the window does). False, with the message shown, on an error.
    bool openFile(const QString& path);
    /// Images dropped or loaded are decoded, and the viewport's bakes run, off the GUI thread (the
    /// studio does this; tests that read the document or the frame right after a change leave it off).
    void setBackgroundLoads(bool on);
    bool saveProjectAs(const QString& path);
    /// New document (the built-in sample), after asking about unsaved changes.
    bool newDocument();
    /// Starts writing the autosave copy (on a worker thread) when there are changes since the last
    /// save or autosave; false when there is nothing to write or a write is still running.
    bool autosave();
    /// Waits for an autosave write in flight; its outcome (ok when none runs).
    Status waitForAutosave();
    /// Autosave this long after an edit (0: never). Edits while it waits join that autosave.
    void setAutosaveDelay(int milliseconds);
    /// The copy this window autosaves to: its project's, or its own untitled one.
    QString autosaveCopy() const;
    /// Offers to recover this project's autosave copy where it is newer than the project.
    void offerRecovery();
    /// At start-up: offers, newest first, the copies of windows that did not close (a crash, a kill),
    /// saved projects and untitled work alike. `opened` is the file named on the command line: a
    /// project's own copy was offered when it opened and others wait for a start without one; over an
    /// opened image the question says that recovering replaces it.
    void offerRecoveryAtLaunch(const QString& opened = {});
    QStringList recentProjects() const;
    /// A file dropped on the window (or on a slot that does not take it), by its kind: a project is
    /// opened (after asking about unsaved changes), an OBJ becomes the mesh, an image the normal map;
    /// anything else is refused with a message. Drops call it once the drop has finished.
    void openDropped(const QString& path);
    /// The 3D view's mesh and camera, as a project saves them.
    ProjectView currentView() const;
    /// Shows a project's view: its mesh (an OBJ that cannot be read is reported, the sphere shown)
    /// and camera; the defaults where a project has none.
    void applyView(const std::optional<ProjectView>& view);
    /// Processes a glTF asset into `outDir` as `burnish gltf` does (gltfMethodFor's method), on a worker
    /// thread with a progress dialog that can cancel; an existing output is replaced only after asking.
    /// gltfFinished reports the outcome, which is also shown (showResult, or showMessage for an error).
    void processGltfAsset(const QString& input, const QString& outDir);
    /// Writes the current material on a quad as a glTF asset into `outDir` (exportMaterialGltf, named
    /// after the project, or "material"), the same way: asks before replacing, reports through
    /// gltfFinished.
    void exportGltf(const QString& outDir);
    GltfRunner* gltfRunner() const { return m_gltfRunner; }
    /// A map the plausibility check refused (held by the document, decoded): asks whether to load it
    /// anyway (`ask`), then takes it in (one undo step, remembered by the project) or drops it.
    void offerLoadAnyway(MapSlot slot, const QString& path, const QString& reason);

signals:
    void gltfFinished(bool ok, const QString& message);

public:
    /// How the window reports to the user; tests replace them to read the text without a modal box.
    std::function<void(const QString& title, const QString& text)> showMessage;
    /// How a finished job's summary is shown (an information box).
    std::function<void(const QString& title, const QString& text)> showResult;
    /// Asks a question; returns the button chosen.
    std::function<QMessageBox::StandardButton(const QString& title, const QString& text,
                                              QMessageBox::StandardButtons buttons)>
        ask;

protected:
    void closeEvent(QCloseEvent* event) override;
    void dragEnterEvent(QDragEnterEvent* event) override;
    void dropEvent(QDropEvent* event) override;
    void showEvent(QShowEvent* event) override;

private:
    void buildMenus();
    void updateTitle();
    void updateStatus();
    void updateRecentMenu();
    void addRecent(const QString& path);
    /// Save/Discard/Cancel when there are unsaved changes; false to stop.
    bool maybeSave();
    bool save();
    bool saveAs();
    void open();
    void exportTextures();
    /// File ▸ Process glTF Asset…: asks for the asset and the output folder.
    void chooseGltfAsset();
    /// File ▸ Export glTF…: asks for the output folder.
    void chooseGltfExport();
    /// The progress dialog of a glTF job; false when `target` exists and replacing it was declined.
    bool beginGltfJob(const QString& label, const QString& target, GltfOptions& options);
    /// Deletes this window's autosave copy (after any write in flight).
    void removeAutosave();
    /// Claims the lock of autosaveCopy() (after the project path changed), releasing the old one.
    void claimAutosaveCopy();
    /// Replaces the document with an autosave copy, which becomes this window's copy; unsaved.
    bool recoverFrom(const QString& copy, const QString& projectPath);
    void restoreSettings();
    void saveSettings();
    /// The first-run arrangement of the docks for the window's actual size. A wide window: the
    /// texture view left of the viewport, the charts under both, Material over Paint, History and
    /// Environment at the right. A compact one (a 1280 or 1366 px screen): the viewport gets the
    /// whole middle, at least half the window; Paint and the charts are tabs behind Material, the
    /// texture view a tab over History and Environment.
    void applyDefaultDockSizes();
    /// Puts every dock in its area and tab group as the first start does (constructor, Reset Layout).
    void placeDocks();
    void showGuide();
    void fitToScreen();

    MaterialDocument* m_doc;
    TexturePane* m_texturePane;
    QDockWidget* m_textureDock;
    QAction* m_authoredAction = nullptr; // View ▸ Authored Gloss/Roughness
    QAction* m_bakedAction = nullptr;
    MaterialPanel* m_panel;
    QDockWidget* m_materialDock;
    QDockWidget* m_historyDock;
    QDockWidget* m_chartsDock;
    bool m_defaultLayoutPending = false; // no saved layout: size the docks once shown
    bool m_fitPending = false;
    QDialog* m_guide = nullptr; // a restored geometry: clamp it to the screen once shown
    PaintTool* m_paintTool;
    QDockWidget* m_paintDock;
    BakeDialog* m_bakeDialog = nullptr;
    GltfRunner* m_gltfRunner;
    QProgressDialog* m_gltfProgress = nullptr;
    QMenu* m_viewMenu = nullptr;
    QMenu* m_recentMenu = nullptr;
    QLabel* m_statusPower;
    QLabel* m_statusGloss;
    QLabel* m_statusMethod;
    QLabel* m_statusPreset;
    QTimer* m_autosaveTimer;
    int m_autosaveDelayMs = 0;
    AutosaveWriter* m_autosaveWriter;
    /// The lock on autosaveCopy(): tells this window's copy from a crashed one's (null if another
    /// live window holds it, which then owns that copy).
    std::unique_ptr<QLockFile> m_autosaveLock;
    QString m_untitledCopy;
    /// Per painted layer, the texels edited since the autosave writer's copy was last brought up to date.
    std::array<TexelRect, 2> m_layerStale;
    QString m_projectPath;
    /// Undo index at the last autosave (-1: none since the last save).
    int m_autosavedIndex = -1;
};

} // namespace burnish::studio
