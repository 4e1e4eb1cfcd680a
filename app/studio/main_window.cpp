#include "main_window.h"

#include "autosave_writer.h"
#include "bake_dialog.h"
#include "charts/charts_panel.h"
#include "environment_panel.h"
#include "gltf_import.h"
#include "material_panel.h"
#include "paint_tool.h"
#include "project.h"
#include "texture_pane.h"
#include "viewport.h"
#include "viewport_panel.h"

#include <QAction>
#include <QApplication>
#include <QCloseEvent>
#include <QDialog>
#include <QDir>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QGuiApplication>
#include <QKeyEvent>
#include <QLabel>
#include <QMenuBar>
#include <QMimeData>
#include <QProgressDialog>
#include <QScreen>
#include <QScrollArea>
#include <QScrollBar>
#include <QSettings>
#include <QShowEvent>
#include <QSpinBox>
#include <QStatusBar>
#include <QTextBrowser>
#include <QTimer>
#include <QUndoStack>
#include <QUndoView>
#include <QVBoxLayout>

#include <algorithm>

namespace burnish::resources {
extern const std::string_view kStudioGuide;
} // namespace burnish::resources

namespace burnish::studio {

namespace {

// Recent projects kept in the File menu: as many as fit a glance.
constexpr int kMaxRecent = 8;
// Autosave this long after an edit unless the settings ("autosaveDelaySeconds") say otherwise: soon
// enough that a crash loses seconds, late enough that a burst of edits makes one write.
constexpr int kDefaultAutosaveDelaySeconds = 3;
// Below this window size the first layout is the compact one (see applyDefaultDockSizes): paint,
// viewport and material side by side need about 1500 px, the charts under the viewport about 900.
constexpr int kCompactLayoutBelowWidth = 1500;
constexpr int kCompactLayoutBelowHeight = 900;
// The docks' arrangement a saved window state belongs to: 2 since the texture view became a dock
// (a state from 1, with the texture view beside the viewport, hid the viewport behind it).
constexpr int kLayoutVersion = 2;
// Redo's second key, beside the platform's (Ctrl+Shift+Z here).
constexpr QKeyCombination kSecondRedo(Qt::CTRL, Qt::Key_Y);

QString qs(std::string_view s) {
    return QString::fromUtf8(s.data(), int(s.size()));
}

bool isProjectFile(const QString& path) {
    return QFileInfo(path).suffix().compare(kProjectSuffix, Qt::CaseInsensitive) == 0;
}

const QString kProjectFilter = QString("Burnish projects (*.%1);;All files (*)").arg(kProjectSuffix);

// Ctrl+Z / Ctrl+Shift+Z in a number field whose value is committed undo and redo the document, as in
// Blender or Substance: a field (its line edit) otherwise claims the keys for its own text history, and a
// committed edit could be undone only from the Edit menu. The filter claims the shortcut for the field
// (so no window shortcut runs twice) and turns the key press into the document's undo or redo. While
// typed text is not yet the field's value, the field keeps the keys for that text.
class NumberFieldUndo : public QObject {
public:
    NumberFieldUndo(QUndoStack* stack, QObject* parent)
        : QObject(parent)
        , m_stack(stack) {}

protected:
    bool eventFilter(QObject* watched, QEvent* event) override {
        if (event->type() != QEvent::ShortcutOverride && event->type() != QEvent::KeyPress) return false;
        const auto* key = static_cast<QKeyEvent*>(event);
        const QKeySequence pressed(key->keyCombination());
        auto is = [&](QKeySequence::StandardKey k) { return QKeySequence::keyBindings(k).contains(pressed); };
        const bool undo = is(QKeySequence::Undo),
                   redo = is(QKeySequence::Redo) || pressed == QKeySequence(kSecondRedo);
        if (!undo && !redo) return false;
        auto* spin = qobject_cast<QAbstractSpinBox*>(watched);
        if (!spin && watched->parent()) spin = qobject_cast<QAbstractSpinBox*>(watched->parent());
        auto inThisWindow = [&](const QObject* o) { // floating docks included
            for (; o; o = o->parent())
                if (o == parent()) return true;
            return false;
        };
        if (!spin || !inThisWindow(spin)) return false;
        const auto* number = qobject_cast<QDoubleSpinBox*>(spin);
        const auto* integer = qobject_cast<QSpinBox*>(spin);
        bool parsed = false;
        const bool committed =
            (number && number->cleanText() == number->textFromValue(number->value())) ||
            (integer && integer->locale().toInt(integer->cleanText(), &parsed) == integer->value() && parsed);
        if (!committed) return false;
        event->accept();
        if (event->type() == QEvent::KeyPress) {
            if (undo)
                m_stack->undo();
            else
                m_stack->redo();
        }
        return true;
    }

private:
    QUndoStack* m_stack;
};

} // namespace

QRect fitInside(const QRect& window, const QRect& available) {
    if (available.isEmpty()) return window;
    QRect r = window;
    r.setWidth(std::min(r.width(), available.width()));
    r.setHeight(std::min(r.height(), available.height()));
    r.moveLeft(std::clamp(r.left(), available.left(), available.right() - r.width() + 1));
    r.moveTop(std::clamp(r.top(), available.top(), available.bottom() - r.height() + 1));
    return r;
}

MainWindow::MainWindow(QWidget* parent)
    : QMainWindow(parent)
    , m_doc(new MaterialDocument(this))
    , m_gltfRunner(new GltfRunner(this)) {
    showMessage = [this](const QString& title, const QString& text) {
        QMessageBox::warning(this, title, text);
    };
    showResult = [this](const QString& title, const QString& text) {
        QMessageBox::information(this, title, text);
    };
    connect(m_gltfRunner, &GltfRunner::progress, this, [this](double fraction, const QString& stage) {
        if (!m_gltfProgress) return;
        m_gltfProgress->setLabelText("glTF: " + stage + "…");
        m_gltfProgress->setValue(int(fraction * 1000));
    });
    connect(m_gltfRunner, &GltfRunner::finished, this, [this](bool ok, const QString& message) {
        if (m_gltfProgress) {
            m_gltfProgress->reset();
            m_gltfProgress->deleteLater();
            m_gltfProgress = nullptr;
        }
        statusBar()->showMessage(ok ? "glTF asset written" : "glTF: " + message, 10000);
        emit gltfFinished(ok, message);
        if (ok)
            showResult("glTF asset written", message);
        else if (message != "cancelled")
            showMessage("Cannot write the glTF asset", message);
    });
    ask = [this](const QString& title, const QString& text, QMessageBox::StandardButtons buttons) {
        return QMessageBox::question(this, title, text, buttons);
    };
    setObjectName("burnishStudioMainWindow");
    setAcceptDrops(true);
    setDockNestingEnabled(true);

    // The 3D viewport is the central widget: every other panel is a dock an artist can move, tab,
    // float or close (View menu), and the first layout gives the viewport the most room
    // (applyDefaultDockSizes).
    auto* viewport = new ViewportPanel(m_doc, this);
    connect(viewport, &ViewportPanel::errorOccurred, this,
            [this](const QString& title, const QString& text) { showMessage(title, text); });
    setCentralWidget(viewport);
    m_texturePane = new TexturePane(m_doc, this);
    m_textureDock = new QDockWidget("Texture", this);
    m_textureDock->setObjectName("textureDock");
    m_textureDock->setWidget(m_texturePane);

    m_paintTool = new PaintTool(m_doc, m_texturePane->view(), this);
    m_paintTool->attachViewport(viewport->viewport());
    connect(m_paintTool, &PaintTool::paintModeChanged, m_texturePane, &TexturePane::setPaintOverlay);
    m_paintDock = new QDockWidget("Paint", this);
    m_paintDock->setObjectName("paintDock");
    m_paintDock->setWidget(m_paintTool);
    // The views paint only while the Paint panel is in view; turning paint mode on brings it there.
    connect(m_paintDock, &QDockWidget::visibilityChanged, m_paintTool, &PaintTool::setPanelVisible);
    connect(m_paintTool, &PaintTool::paintModeChanged, this, [this](bool on) {
        if (!on || m_paintTool->armed()) return;
        m_paintDock->show();
        m_paintDock->raise();
    });

    m_panel = new MaterialPanel(m_doc, this);
    auto* scroll = new QScrollArea(this);
    scroll->setWidget(m_panel);
    scroll->setWidgetResizable(true);
    scroll->setFrameShape(QFrame::NoFrame);
    scroll->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
    // Never narrower than the panel's rows (with no horizontal scroll bar they would be cut off).
    scroll->setMinimumWidth(m_panel->minimumSizeHint().width() +
                            scroll->verticalScrollBar()->sizeHint().width() + 2 * scroll->frameWidth());
    m_materialDock = new QDockWidget("Material", this);
    m_materialDock->setObjectName("materialDock");
    m_materialDock->setWidget(scroll);

    auto* history = new QUndoView(m_doc->undoStack(), this);
    history->setEmptyLabel("<opened>");
    m_historyDock = new QDockWidget("History", this);
    m_historyDock->setObjectName("historyDock");
    m_historyDock->setWidget(history);

    // The environment lighting of the viewport, tabbed with the history. The library lists the HDR
    // files of $BURNISH_ENVIRONMENTS (the repository's shared data folder holds courtyard and studio).
    auto* environment = new EnvironmentPanel(m_doc, this);
    environment->setLibraryFolder(qEnvironmentVariable("BURNISH_ENVIRONMENTS"));
    auto* environmentDock = new QDockWidget("Environment", this);
    environmentDock->setObjectName("environmentDock");
    environmentDock->setWidget(environment);

    // The charts (specular colour, gloss, BRDF plots, error vs cost) under the central pane.
    // The right column runs the window's full height, so the Material panel is not squeezed above
    // the charts.
    setCorner(Qt::BottomRightCorner, Qt::RightDockWidgetArea);
    auto* charts = new ChartsPanel(m_doc, this);
    m_chartsDock = charts;
    placeDocks();

    m_statusPower = new QLabel(this);
    m_statusGloss = new QLabel(this);
    m_statusMethod = new QLabel(this);
    m_statusPreset = new QLabel(this);
    for (QLabel* l : {m_statusPreset, m_statusMethod, m_statusGloss, m_statusPower}) {
        l->setContentsMargins(8, 0, 8, 0);
        statusBar()->addPermanentWidget(l);
    }

    buildMenus();
    connect(m_doc, &MaterialDocument::changed, this, &MainWindow::updateStatus);
    connect(m_doc, &MaterialDocument::notice, this,
            [this](const QString& text) { statusBar()->showMessage(text, 10000); });
    // Background loads: the window stays live while a big map decodes, and says so.
    connect(m_doc, &MaterialDocument::mapLoadStarted, this, [this](MapSlot slot, const QString& path) {
        statusBar()->showMessage(
            QString("Loading the %1 map %2…").arg(mapSlotName(slot), QFileInfo(path).fileName()));
    });
    connect(m_doc, &MaterialDocument::mapLoadFinished, this,
            [this](MapSlot slot, const QString& path, bool ok, const QString& error) {
                if (ok) {
                    statusBar()->showMessage(
                        QString("Loaded the %1 map %2").arg(mapSlotName(slot), QFileInfo(path).fileName()),
                        4000);
                    return;
                }
                statusBar()->clearMessage();
                if (m_doc->holdsRefusedMap(slot)) {
                    // Refused by the plausibility check alone: the artist may know better (an odd but
                    // real map). Asked after this signal returns, never inside a drop or a load.
                    QTimer::singleShot(0, this,
                                       [this, slot, path, error] { offerLoadAnyway(slot, path, error); });
                    return;
                }
                showMessage(QString("Cannot load the %1 map").arg(mapSlotName(slot)), error);
            });
    connect(m_doc->undoStack(), &QUndoStack::cleanChanged, this, &MainWindow::updateTitle);
    connect(m_panel, &MaterialPanel::errorOccurred, this,
            [this](const QString& title, const QString& text) { showMessage(title, text); });

    m_autosaveWriter = new AutosaveWriter(this);
    connect(m_autosaveWriter, &AutosaveWriter::finished, this, [this](bool ok, const QString& error) {
        if (ok) {
            statusBar()->showMessage("Autosaved", 2000);
            return;
        }
        m_autosavedIndex = -1; // the next edit tries again
        // Autosave runs unattended: a failure goes to the status bar, not a modal box every time.
        statusBar()->showMessage("Autosave failed: " + error, 8000);
    });
    m_autosaveTimer = new QTimer(this);
    m_autosaveTimer->setSingleShot(true);
    connect(m_autosaveTimer, &QTimer::timeout, this, [this] {
        // A write still running (a big painted layer): try again after another delay.
        if (m_autosaveWriter->busy() && isModified())
            m_autosaveTimer->start(m_autosaveDelayMs);
        else
            autosave();
    });
    // The first edit after an autosave starts the clock; edits while it runs join that autosave.
    connect(m_doc->undoStack(), &QUndoStack::indexChanged, this, [this] {
        if (m_autosaveDelayMs > 0 && !m_autosaveTimer->isActive()) m_autosaveTimer->start(m_autosaveDelayMs);
    });
    m_untitledCopy = newUntitledAutosavePath();
    claimAutosaveCopy();
    connect(m_doc, &MaterialDocument::layersChanged, this, [this](const TexelRect& rect) {
        for (TexelRect& stale : m_layerStale)
            stale.unite(rect);
    });
    resize(1400, 880);
    restoreSettings();
    updateStatus();
    updateTitle();
}

MainWindow::~MainWindow() {
    // The document outlives every view of it. Left to ~QWidget, the document (the first child)
    // would die first: its undo stack emits cleanChanged into this half-destroyed window, and the
    // panels, viewport and charts that hold it would outlive it. So: stop listening, delete the
    // views, then the document.
    m_doc->undoStack()->disconnect(this);
    m_doc->disconnect(this);
    qDeleteAll(findChildren<QWidget*>(QString(), Qt::FindDirectChildrenOnly));
    delete m_doc;
}

void MainWindow::buildMenus() {
    QMenu* file = menuBar()->addMenu("&File");
    file->addAction("&New", QKeySequence::New, this, &MainWindow::newDocument);
    file->addAction("&Open…", QKeySequence::Open, this, &MainWindow::open);
    m_recentMenu = file->addMenu("Open &Recent");
    file->addSeparator();
    file->addAction("&Save", QKeySequence::Save, this, &MainWindow::save);
    // QKeySequence::SaveAs is empty on some desktops: Ctrl+Shift+S is what every editor uses.
    file->addAction("Save &As…", QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_S), this, &MainWindow::saveAs);
    file->addSeparator();
    file->addAction("&Export Textures…", QKeySequence(Qt::CTRL | Qt::Key_E), this,
                    &MainWindow::exportTextures);
    file->addAction("Export g&lTF…", QKeySequence(Qt::CTRL | Qt::ALT | Qt::Key_G), this,
                    &MainWindow::chooseGltfExport);
    file->addAction("Process &glTF Asset…", QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_G), this,
                    &MainWindow::chooseGltfAsset);
    file->addSeparator();
    file->addAction("&Quit", QKeySequence::Quit, this, &QWidget::close);

    qApp->installEventFilter(new NumberFieldUndo(m_doc->undoStack(), this)); // removed with the window
    QMenu* edit = menuBar()->addMenu("&Edit");
    QAction* undo = m_doc->undoStack()->createUndoAction(this, "&Undo");
    undo->setShortcut(QKeySequence::Undo);
    QAction* redo = m_doc->undoStack()->createRedoAction(this, "&Redo");
    // The platform's redo and Ctrl+Y, which many tools use, both.
    QList<QKeySequence> redoKeys = QKeySequence::keyBindings(QKeySequence::Redo);
    if (!redoKeys.contains(QKeySequence(kSecondRedo))) redoKeys << QKeySequence(kSecondRedo);
    redo->setShortcuts(redoKeys);
    edit->addAction(undo);
    edit->addAction(redo);

    m_viewMenu = menuBar()->addMenu("&View");
    QAction* material = m_materialDock->toggleViewAction();
    material->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_1));
    QAction* history = m_historyDock->toggleViewAction();
    history->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_2));
    m_viewMenu->addAction(material);
    m_viewMenu->addAction(history);
    if (auto* charts = findChild<ChartsPanel*>("chartsDock")) {
        QAction* chartsToggle = charts->toggleViewAction();
        chartsToggle->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_3));
        m_viewMenu->addAction(chartsToggle);
    }
    // Every panel, so one closed by its title bar's button can always be brought back.
    QAction* paint = m_paintDock->toggleViewAction();
    paint->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_4));
    m_viewMenu->addAction(paint);
    if (auto* environment = findChild<QDockWidget*>("environmentDock")) {
        QAction* environmentToggle = environment->toggleViewAction();
        environmentToggle->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_5));
        m_viewMenu->addAction(environmentToggle);
    }
    QAction* texture = m_textureDock->toggleViewAction();
    texture->setShortcut(QKeySequence(Qt::CTRL | Qt::Key_6));
    m_viewMenu->addAction(texture);
    m_viewMenu->addAction("Reset &Layout", this, &MainWindow::resetLayout);
    m_viewMenu->addSeparator();
    // Each shows the texture view (raised from behind its tabs) in that mode; the gloss entries
    // take the preset's own word (retitled by updateStatus).
    auto raiseTexture = [this] {
        m_textureDock->show();
        m_textureDock->raise();
    };
    auto showTexture = [this, raiseTexture](TextureMode mode) {
        raiseTexture();
        m_texturePane->setMode(mode);
    };
    m_viewMenu->addAction("Normal Map", QKeySequence(Qt::Key_1), this,
                          [showTexture] { showTexture(TextureMode::Normal); });
    m_authoredAction = m_viewMenu->addAction("Authored Gloss", QKeySequence(Qt::Key_2), this,
                                             [showTexture] { showTexture(TextureMode::Gloss); });
    m_bakedAction = m_viewMenu->addAction("Baked Gloss", QKeySequence(Qt::Key_3), this,
                                          [showTexture] { showTexture(TextureMode::BakedGloss); });
    m_viewMenu->addAction("Fit Texture", QKeySequence(Qt::Key_F), this, [this, raiseTexture] {
        raiseTexture();
        m_texturePane->view()->fit();
    });
    m_viewMenu->addAction("Frame Object", QKeySequence(Qt::SHIFT | Qt::Key_F), this,
                          [this] { findChild<ViewportPanel*>("viewportPanel")->viewport()->frameObject(); });

    QMenu* help = menuBar()->addMenu("&Help");
    help->addAction("Studio &Guide", QKeySequence::HelpContents, this, &MainWindow::showGuide);
    help->addAction("&About Burnish Studio", this, [this] {
        QMessageBox::about(
            this, "About Burnish Studio",
            QString("<b>Burnish Studio %1</b><p>Real-time material authoring: calibrated "
                    "specular colour and gloss, normal-map detail below a pixel turned into "
                    "roughness per mip, measured against the ground truth.</p><p>Help ▸ Studio "
                    "Guide describes every panel; <code>burnish --help</code> the command "
                    "line.</p>")
                .arg(QApplication::applicationVersion()));
    });
    updateRecentMenu();
}

QString studioGuideMarkdown() {
    return QString::fromUtf8(resources::kStudioGuide.data(), qsizetype(resources::kStudioGuide.size()));
}

void MainWindow::showGuide() {
    if (!m_guide) {
        m_guide = new QDialog(this);
        m_guide->setObjectName("studioGuide");
        m_guide->setWindowTitle("Burnish Studio Guide");
        auto* text = new QTextBrowser(m_guide);
        text->setMarkdown(studioGuideMarkdown());
        text->setOpenExternalLinks(true);
        auto* layout = new QVBoxLayout(m_guide);
        layout->addWidget(text);
        m_guide->resize(720, 560);
    }
    m_guide->show();
    m_guide->raise();
}

bool MainWindow::isModified() const {
    return !m_doc->undoStack()->isClean();
}

BakeDialog* MainWindow::bakeDialog() {
    if (!m_bakeDialog) {
        m_bakeDialog = new BakeDialog(m_doc, this);
        // One way of asking for the whole window (tests answer through it).
        m_bakeDialog->ask = [this](const QString& title, const QString& text,
                                   QMessageBox::StandardButtons b) { return ask(title, text, b); };
    }
    return m_bakeDialog;
}

void MainWindow::updateTitle() {
    const QString name = m_projectPath.isEmpty() ? "untitled" : QFileInfo(m_projectPath).fileName();
    setWindowTitle(QString("%1[*] — Burnish Studio").arg(name));
    setWindowModified(isModified());
}

void MainWindow::updateStatus() {
    const MaterialSettings& s = m_doc->settings();
    m_statusPreset->setText("preset " + s.preset);
    m_statusMethod->setText("method " + qs(methodName(s.method)));
    m_statusGloss->setText(
        QString("%1 %2").arg(glossQuantity(m_doc->preset().encoding, false)).arg(glossText(s.gloss)));
    m_statusPower->setText(QString("power %1").arg(m_doc->power(), 0, 'g', 5));
    if (m_authoredAction) {
        const QString term = glossQuantity(m_doc->preset().encoding);
        m_authoredAction->setText("Authored " + term);
        m_bakedAction->setText("Baked " + term);
    }
}

QStringList MainWindow::recentProjects() const {
    return QSettings().value("recentProjects").toStringList();
}

void MainWindow::addRecent(const QString& path) {
    QStringList recent = recentProjects();
    const QString absolute = QFileInfo(path).absoluteFilePath();
    recent.removeAll(absolute);
    recent.prepend(absolute);
    while (recent.size() > kMaxRecent)
        recent.removeLast();
    QSettings().setValue("recentProjects", recent);
    QSettings().setValue("folders/projects", QFileInfo(absolute).absolutePath());
    updateRecentMenu();
}

void MainWindow::updateRecentMenu() {
    m_recentMenu->clear();
    const QStringList recent = recentProjects();
    for (int i = 0; i < recent.size(); ++i) {
        const QString path = recent[i];
        QAction* a = m_recentMenu->addAction(QString("&%1 %2").arg(i + 1).arg(QFileInfo(path).fileName()),
                                             this, [this, path] {
                                                 if (maybeSave()) openProject(path);
                                             });
        a->setToolTip(path);
        a->setStatusTip(path);
    }
    m_recentMenu->setEnabled(!recent.isEmpty());
}

bool MainWindow::maybeSave() {
    if (!isModified()) return true;
    const auto answer = ask("Unsaved changes", "The material has unsaved changes. Save them?",
                            QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel);
    if (answer == QMessageBox::Save) return save();
    if (answer != QMessageBox::Discard) return false;
    // Discarded means gone: the autosave copy of those changes must not come back at the next start.
    removeAutosave();
    return true;
}

bool MainWindow::newDocument() {
    if (!maybeSave()) return false;
    removeAutosave();
    if (const Status st = m_doc->reset(MaterialDocument::defaultSettings()); !st) {
        showMessage("New material", QString::fromStdString(st.error()));
        return false;
    }
    m_autosaveWriter->forgetLayers(); // other layers: the next autosave copies them whole
    m_projectPath.clear();
    claimAutosaveCopy();
    m_autosavedIndex = -1;
    updateTitle();
    return true;
}

void MainWindow::open() {
    // A project, or an image to open as the normal map (what the command line and a drop do). The file
    // first: a cancelled dialog leaves the document and its unsaved changes alone.
    const QString filter =
        QString("Projects and normal maps (*.%1 *.png *.tga *.jpg *.jpeg *.exr *.tif *.tiff "
                "*.dds *.hdr);;Burnish projects (*.%1);;All files (*)")
            .arg(kProjectSuffix);
    const QString path = QFileDialog::getOpenFileName(
        this, "Open project or normal map", QSettings().value("folders/projects").toString(), filter);
    if (path.isEmpty()) return;
    // A project replaces the document (after asking about unsaved changes); an image becomes its
    // normal map, one undoable step.
    if (!isProjectFile(path) || maybeSave()) openFile(path);
}

bool MainWindow::openProject(const QString& path) {
    const QString absolute = QFileInfo(path).absoluteFilePath();
    const auto project = loadProject(absolute);
    if (!project) {
        showMessage("Cannot open project", QString::fromStdString(project.error()));
        return false;
    }
    if (const Status st = m_doc->reset(project->settings, project->layers); !st) {
        showMessage("Cannot open project",
                    QString("project '%1': %2").arg(absolute, QString::fromStdString(st.error())));
        return false;
    }
    m_autosaveWriter->forgetLayers(); // other layers: the next autosave copies them whole
    applyView(project->view);
    m_projectPath = absolute;
    claimAutosaveCopy();
    m_autosavedIndex = -1;
    addRecent(absolute);
    updateTitle();
    statusBar()->showMessage("Opened " + absolute, 4000);
    // A newer autosave of this project (a crash after the last save) is offered right away.
    offerRecovery();
    return true;
}

ProjectView MainWindow::currentView() const {
    const ViewSettings& v = findChild<ViewportPanel*>("viewportPanel")->viewport()->viewSettings();
    ProjectView view;
    view.mesh = v.mesh;
    view.objPath = v.objPath;
    view.yawDegrees = v.yawDegrees;
    view.pitchDegrees = v.pitchDegrees;
    view.distance = v.distance;
    view.target = {v.target.x, v.target.y, v.target.z};
    return view;
}

void MainWindow::applyView(const std::optional<ProjectView>& view) {
    auto* panel = findChild<ViewportPanel*>("viewportPanel");
    const ProjectView shown = view.value_or(ProjectView{});
    // The mesh first (it aims the camera at its centre), then the camera the project saved. An OBJ
    // that cannot be read any more is said (loadMesh) and the sphere drawn instead.
    auto aim = [panel, shown](bool ok) {
        if (!ok) {
            panel->loadMesh(render::MeshKind::Sphere, {});
            return;
        }
        ViewSettings v = panel->viewport()->viewSettings();
        v.yawDegrees = float(shown.yawDegrees);
        v.pitchDegrees = float(shown.pitchDegrees);
        v.target = glm::vec3(float(shown.target[0]), float(shown.target[1]), float(shown.target[2]));
        panel->viewport()->setViewSettings(v);
        panel->viewport()->setDistance(float(shown.distance)); // clamped to the viewport's range
    };
    if (shown.mesh == render::MeshKind::Obj && panel->backgroundLoads()) {
        // A big OBJ is read off the GUI thread; the camera follows once it is drawn (a later load
        // or a cancel leaves the camera as it is).
        auto* once = new QObject(this);
        connect(panel, &ViewportPanel::meshLoaded, once, [once, aim, panel, path = shown.objPath](bool ok) {
            once->deleteLater();
            if (ok && panel->viewport()->viewSettings().objPath == path) aim(true);
        });
        panel->loadMeshInBackground(shown.objPath);
        return;
    }
    aim(panel->loadMesh(shown.mesh, shown.objPath));
}

void MainWindow::setBackgroundLoads(bool on) {
    m_panel->setBackgroundLoads(on);
    m_paintTool->setBackgroundBakes(on);
    if (auto* panel = findChild<ViewportPanel*>("viewportPanel")) {
        panel->viewport()->setBackgroundBakes(on);
        panel->setBackgroundLoads(on);
    }
}

bool MainWindow::openFile(const QString& path) {
    if (isProjectFile(path)) return openProject(path);
    return m_panel->loadMap(MapSlot::Normal, path);
}

bool MainWindow::save() {
    return m_projectPath.isEmpty() ? saveAs() : saveProjectAs(m_projectPath);
}

bool MainWindow::saveAs() {
    QString start = m_projectPath;
    if (start.isEmpty())
        start = QSettings().value("folders/projects", QDir::homePath()).toString() + "/material." +
                kProjectSuffix;
    QString path = QFileDialog::getSaveFileName(this, "Save project", start, kProjectFilter);
    if (path.isEmpty()) return false;
    if (QFileInfo(path).suffix().isEmpty()) path += QString(".") + kProjectSuffix;
    return saveProjectAs(path);
}

bool MainWindow::saveProjectAs(const QString& path) {
    const QString absolute = QFileInfo(path).absoluteFilePath();
    if (const Status st = saveProject(
            m_doc->settings(), absolute, {},
            {&m_doc->paintLayer(PaintLayerKind::Gloss), &m_doc->paintLayer(PaintLayerKind::VarianceOffset)},
            currentView());
        !st) {
        showMessage("Cannot save project", QString::fromStdString(st.error()));
        return false;
    }
    // The copy of the old name (or of the untitled work) is saved now: it goes.
    removeAutosave();
    m_projectPath = absolute;
    claimAutosaveCopy();
    removeAutosave(); // an old copy of the new name, if any: what it held is saved now too
    m_doc->undoStack()->setClean();
    addRecent(absolute);
    updateTitle();
    statusBar()->showMessage("Saved " + absolute, 4000);
    return true;
}

bool MainWindow::autosave() {
    if (!isModified() || m_doc->undoStack()->index() == m_autosavedIndex || m_autosaveWriter->busy())
        return false;
    AutosaveWriter::Snapshot snapshot{m_doc->settings(), autosaveCopy(), m_projectPath, {}, currentView()};
    // The writer's own copies of the layers (the artist paints on while the worker encodes them),
    // brought up to date where they were edited since the last autosave: a stroke's rectangle, not an
    // 8192² layer's 512 MB. The worker skips layers with no paint.
    for (const PaintLayerKind kind : {PaintLayerKind::Gloss, PaintLayerKind::VarianceOffset}) {
        const PaintLayer& layer = m_doc->paintLayer(kind);
        if (!layer.allocated()) continue;
        if (!m_autosaveWriter->syncLayer(layer, m_layerStale[size_t(kind)])) {
            // A big layer's copy is still being made off this thread: the next autosave takes it.
            if (m_autosaveDelayMs > 0) m_autosaveTimer->start(m_autosaveDelayMs);
            return false;
        }
        m_layerStale[size_t(kind)] = {};
        snapshot.layers.push_back(m_autosaveWriter->layerCopy(kind));
    }
    if (!m_autosaveWriter->start(std::move(snapshot))) return false;
    m_autosavedIndex = m_doc->undoStack()->index();
    return true;
}

Status MainWindow::waitForAutosave() {
    return m_autosaveWriter->wait();
}

void MainWindow::setAutosaveDelay(int milliseconds) {
    m_autosaveDelayMs = std::max(0, milliseconds);
    if (m_autosaveDelayMs == 0) m_autosaveTimer->stop();
}

QString MainWindow::autosaveCopy() const {
    return m_projectPath.isEmpty() ? m_untitledCopy : autosavePathFor(m_projectPath);
}

void MainWindow::claimAutosaveCopy() {
    m_autosaveLock.reset();
    m_autosaveLock = claimAutosave(autosaveCopy());
    if (!m_autosaveLock)
        statusBar()->showMessage("This project is open in another Burnish window too: the last one to save "
                                 "keeps its changes",
                                 10000);
}

void MainWindow::removeAutosave() {
    // A write in flight would put the copy back after it was removed.
    (void)m_autosaveWriter->wait();
    // Another live window's copy of the same project is its work, not this window's to delete.
    if (m_autosaveLock) (void)removeProject(autosaveCopy());
    m_autosavedIndex = -1;
}

void MainWindow::offerRecovery() {
    // A copy another live window holds is that window's unsaved work, not a crash's.
    if (!m_autosaveLock || m_projectPath.isEmpty()) return;
    const auto copy = recoverableAutosave(m_projectPath);
    if (!copy) return;
    const auto answer = ask(
        "Recover autosave",
        QString("An autosave of %1 from %2 is newer than the saved project. Recover it? "
                "(No keeps the autosave for later; Discard deletes it.)")
            .arg(QFileInfo(m_projectPath).fileName(), QFileInfo(*copy).lastModified().toString(Qt::TextDate)),
        QMessageBox::Yes | QMessageBox::No | QMessageBox::Discard);
    // Only an explicit Discard deletes the artist's unsaved work; anything else keeps the copy.
    if (answer == QMessageBox::Discard) {
        (void)removeProject(*copy);
        return;
    }
    if (answer == QMessageBox::Yes) (void)recoverFrom(*copy, m_projectPath);
}

void MainWindow::offerRecoveryAtLaunch(const QString& opened) {
    // A project named on the command line had its own copy offered as it opened; the others wait for
    // a start that names none rather than replace what the artist asked for.
    if (!opened.isEmpty() && isProjectFile(opened)) return;
    const auto copies = recoverableAutosaves();
    for (const AutosaveCopy& copy : copies) {
        if (copy.path == autosaveCopy()) continue; // this window's own (nothing written yet)
        const QString what =
            copy.autosaveOf.isEmpty() ? QString("unsaved work") : QFileInfo(copy.autosaveOf).fileName();
        QString text = QString("Burnish Studio did not close normally. An autosave of %1 from %2 was found")
                           .arg(what, copy.modified.toString(Qt::TextDate));
        if (copies.size() > 1) text += QString(" (%1 in all, newest first)").arg(copies.size());
        text += ". Recover it?";
        text += opened.isEmpty()
                    ? QString(" (No keeps it for the next start; Discard deletes it.)")
                    : QString(" Recovering replaces %1, which you opened; No opens %1 and keeps the "
                              "autosave for the next start; Discard deletes it.")
                          .arg(QFileInfo(opened).fileName());
        const auto answer =
            ask("Recover autosave", text, QMessageBox::Yes | QMessageBox::No | QMessageBox::Discard);
        if (answer == QMessageBox::Discard) {
            (void)removeProject(copy.path);
            continue;
        }
        if (answer == QMessageBox::Yes && recoverFrom(copy.path, copy.autosaveOf)) return;
    }
}

bool MainWindow::recoverFrom(const QString& copy, const QString& projectPath) {
    const auto project = loadProject(copy);
    if (!project) {
        showMessage("Cannot recover autosave", QString::fromStdString(project.error()));
        return false;
    }
    if (const Status st = m_doc->reset(project->settings, project->layers); !st) {
        showMessage("Cannot recover autosave", QString::fromStdString(st.error()));
        return false;
    }
    m_autosaveWriter->forgetLayers(); // other layers: the next autosave copies them whole
    applyView(project->view);
    // The copy becomes this window's: its next autosave replaces it, saving or discarding removes it.
    if (projectPath != m_projectPath || (projectPath.isEmpty() && copy != m_untitledCopy)) {
        removeAutosave(); // this window's own copy, superseded
        if (projectPath.isEmpty()) m_untitledCopy = copy;
        m_projectPath = projectPath;
        claimAutosaveCopy();
        if (!projectPath.isEmpty()) addRecent(projectPath);
    }
    // The recovered state is not what the project file holds: it stays unsaved until saved.
    m_doc->undoStack()->resetClean();
    m_autosavedIndex = -1;
    updateTitle();
    statusBar()->showMessage(
        "Recovered the autosave of " + (projectPath.isEmpty() ? QString("unsaved work") : projectPath), 6000);
    return true;
}

void MainWindow::exportTextures() {
    BakeDialog* dialog = bakeDialog();
    dialog->show();
    dialog->raise();
    dialog->activateWindow();
}

void MainWindow::chooseGltfAsset() {
    QSettings settings;
    const QString input =
        QFileDialog::getOpenFileName(this, "Process glTF asset", settings.value("folders/gltf").toString(),
                                     "glTF 2.0 assets (*.gltf *.glb)");
    if (input.isEmpty()) return;
    const QFileInfo info(input);
    settings.setValue("folders/gltf", info.absolutePath());
    const QString outDir = QFileDialog::getExistingDirectory(
        this, "Folder for the processed asset (its KTX2 textures go beside it)", info.absolutePath());
    if (outDir.isEmpty()) return;
    processGltfAsset(input, outDir);
}

void MainWindow::processGltfAsset(const QString& input, const QString& outDir) {
    if (m_gltfRunner->running()) return;
    GltfOptions options;
    setGltfMethod(*m_doc, options);
    const QFileInfo info(input);
    // The asset file is the set's index: it exists when a previous run of this asset is there.
    const QString target = QDir(outDir).filePath(info.completeBaseName() +
                                                 (info.suffix().toLower() == "glb" ? ".glb" : ".gltf"));
    if (!beginGltfJob("Processing " + info.fileName() + "…", target, options)) return;
    m_gltfRunner->start(input, outDir, std::move(options));
}

bool MainWindow::beginGltfJob(const QString& label, const QString& target, GltfOptions& options) {
    if (QFileInfo::exists(target)) {
        if (ask("Replace glTF asset?", QString("%1 already exists. Replace it and its textures?").arg(target),
                QMessageBox::Yes | QMessageBox::Cancel) != QMessageBox::Yes)
            return false;
        options.overwrite = Overwrite::Allow;
    }
    m_gltfProgress = new QProgressDialog(label, "Cancel", 0, 1000, this);
    m_gltfProgress->setWindowModality(Qt::WindowModal);
    m_gltfProgress->setMinimumDuration(300);
    connect(m_gltfProgress, &QProgressDialog::canceled, m_gltfRunner, &GltfRunner::cancel);
    return true;
}

void MainWindow::chooseGltfExport() {
    QSettings settings;
    const QString outDir = QFileDialog::getExistingDirectory(this, "Export the material as glTF into",
                                                             settings.value("folders/gltfExport").toString());
    if (outDir.isEmpty()) return;
    settings.setValue("folders/gltfExport", outDir);
    exportGltf(outDir);
}

void MainWindow::exportGltf(const QString& outDir) {
    if (m_gltfRunner->running()) return;
    const std::string name =
        m_projectPath.isEmpty() ? "material" : QFileInfo(m_projectPath).completeBaseName().toStdString();
    GltfMaterialSource material = gltfMaterialSourceFor(*m_doc, name);
    GltfOptions options;
    setGltfMethod(*m_doc, options);
    const QString target = QDir(outDir).filePath(QString::fromStdString(name) + ".gltf");
    if (!beginGltfJob("Exporting the material as glTF…", target, options)) return;
    m_gltfRunner->startExport(std::move(material), outDir, std::move(options));
}

void MainWindow::offerLoadAnyway(MapSlot slot, const QString& path, const QString& reason) {
    if (!m_doc->holdsRefusedMap(slot)) return; // superseded by a newer load meanwhile
    const QString name = QFileInfo(path).fileName();
    const auto answer =
        ask(QString("Load the %1 map anyway?").arg(mapSlotName(slot)),
            QString("%1\n\nBurnish would refuse %2 as a %3 map. Load it anyway if you know it is a "
                    "tangent-space normal map: the views, exports and bakes will use it as one, and the "
                    "project remembers the choice.")
                .arg(reason, name, mapSlotName(slot)),
            QMessageBox::Yes | QMessageBox::No);
    if (answer != QMessageBox::Yes) {
        m_doc->dropRefusedMap(slot);
        statusBar()->showMessage(QString("The %1 map %2 was not loaded").arg(mapSlotName(slot), name), 8000);
        return;
    }
    if (const Status st = m_doc->acceptRefusedMap(slot); !st) {
        showMessage(QString("Cannot load the %1 map").arg(mapSlotName(slot)),
                    QString::fromStdString(st.error()));
        return;
    }
    statusBar()->showMessage(QString("Loaded the %1 map %2 anyway").arg(mapSlotName(slot), name), 8000);
}

void MainWindow::closeEvent(QCloseEvent* event) {
    if (!maybeSave()) {
        event->ignore();
        return;
    }
    removeAutosave();
    saveSettings();
    event->accept();
}

void MainWindow::dragEnterEvent(QDragEnterEvent* event) {
    if (event->mimeData()->hasUrls() && event->mimeData()->urls().first().isLocalFile())
        event->acceptProposedAction();
}

void MainWindow::dropEvent(QDropEvent* event) {
    const QList<QUrl> urls = event->mimeData()->urls();
    if (urls.isEmpty() || !urls.first().isLocalFile()) return;
    const QString path = urls.first().toLocalFile();
    event->acceptProposedAction();
    // Routed by what is dropped, after the drop has finished: a question or a message box inside the
    // drop kept the drag source waiting until it gave up.
    QTimer::singleShot(0, this, [this, path] { openDropped(path); });
}

void MainWindow::openDropped(const QString& path) {
    // A project replaces the document (after asking about unsaved changes); an OBJ becomes the 3D
    // view's mesh; an image dropped anywhere but on a slot goes to the normal slot.
    if (isProjectFile(path)) {
        if (maybeSave()) openProject(path);
    } else if (QFileInfo(path).suffix().compare("obj", Qt::CaseInsensitive) == 0) {
        auto* panel = findChild<ViewportPanel*>("viewportPanel");
        if (panel->backgroundLoads())
            panel->loadMeshInBackground(path);
        else
            panel->loadMesh(render::MeshKind::Obj, path);
    } else if (isImageFileName(path)) {
        openFile(path);
    } else {
        showMessage(
            "Cannot use this file",
            QString("'%1' is not an image (PNG, TGA, JPEG, EXR, TIFF, DDS, HDR), an OBJ mesh or a Burnish "
                    "project")
                .arg(path));
    }
}

void MainWindow::restoreSettings() {
    QSettings settings;
    if (settings.contains("window/geometry")) {
        restoreGeometry(settings.value("window/geometry").toByteArray());
        // Clamped to the screen when first shown (fitToScreen), when the frame's size is known.
        m_fitPending = true;
    } else if (const QScreen* screen = QGuiApplication::primaryScreen()) {
        // First run: most of the screen, up to 1600×1000 (the charts' labels need about 1000
        // rows beside the views), centred.
        const QRect free = screen->availableGeometry();
        const QSize size(std::min(1600, free.width() * 9 / 10), std::min(1000, free.height() * 9 / 10));
        resize(size);
        move(free.center() - QPoint(size.width() / 2, size.height() / 2));
    }
    // A state saved by another arrangement of the docks (kLayoutVersion) is not restored: its
    // splits would cover the viewport with docks it never held. The first layout is made instead.
    m_defaultLayoutPending = !(settings.contains("window/state") &&
                               restoreState(settings.value("window/state").toByteArray(), kLayoutVersion));
    setAutosaveDelay(settings.value("autosaveDelaySeconds", kDefaultAutosaveDelaySeconds).toInt() * 1000);
}

void MainWindow::fitToScreen() {
    // A geometry saved on a larger screen (or by an older, wider layout) is clamped to the screen
    // the window opens on: every edge on screen, nothing out of reach.
    const QScreen* screen = QGuiApplication::screenAt(geometry().center());
    if (!screen) screen = this->screen();
    if (!screen || isMaximized() || isFullScreen()) return;
    const QRect frame = frameGeometry(), inner = geometry();
    const QMargins margins(inner.left() - frame.left(), inner.top() - frame.top(),
                           frame.right() - inner.right(), frame.bottom() - inner.bottom());
    const QRect fitted = fitInside(frame, screen->availableGeometry());
    if (fitted != frame) setGeometry(fitted.marginsRemoved(margins));
}

void MainWindow::showEvent(QShowEvent* event) {
    QMainWindow::showEvent(event);
    if (m_fitPending) {
        m_fitPending = false;
        fitToScreen();
    }
    if (!m_defaultLayoutPending) return;
    m_defaultLayoutPending = false;
    // After the first layout pass, when the docks have their real extents to share.
    QTimer::singleShot(0, this, [this] { applyDefaultDockSizes(); });
}

void MainWindow::placeDocks() {
    // The wide arrangement (a compact window rearranges it: applyDefaultDockSizes): Material over
    // History, Environment and Paint at the right, the charts under the views, the 2D texture view
    // left of the viewport.
    addDockWidget(Qt::RightDockWidgetArea, m_materialDock);
    addDockWidget(Qt::RightDockWidgetArea, m_historyDock);
    if (auto* environment = findChild<QDockWidget*>("environmentDock"))
        tabifyDockWidget(m_historyDock, environment);
    tabifyDockWidget(m_historyDock, m_paintDock);
    addDockWidget(Qt::BottomDockWidgetArea, m_chartsDock);
    addDockWidget(Qt::LeftDockWidgetArea, m_textureDock);
    m_paintDock->raise();
}

void MainWindow::resetLayout() {
    // Every panel shown and docked, placed as at the first start, then that start's proportions.
    for (QDockWidget* dock : findChildren<QDockWidget*>()) {
        dock->setFloating(false);
        dock->show();
    }
    placeDocks();
    applyDefaultDockSizes();
}

void MainWindow::applyDefaultDockSizes() {
    const int w = width(), h = height();
    if (w < kCompactLayoutBelowWidth || h < kCompactLayoutBelowHeight) {
        // Compact: nothing under or beside the viewport. Paint and the charts (their rows scroll) are
        // tabs behind Material, the texture view a tab over History and Environment.
        tabifyDockWidget(m_materialDock, m_paintDock);
        tabifyDockWidget(m_materialDock, m_chartsDock);
        tabifyDockWidget(m_historyDock, m_textureDock);
        m_materialDock->raise();
        m_textureDock->raise();
        resizeDocks({m_materialDock, m_textureDock}, {h * 3 / 5, h * 2 / 5}, Qt::Vertical);
        resizeDocks({m_materialDock}, {std::min(w * 9 / 25, 440)}, Qt::Horizontal);
        return;
    }
    // Material 60% of the right column, Paint, History and Environment the rest; the charts half
    // the height under the texture view and the viewport; the texture view about square.
    resizeDocks({m_materialDock, m_historyDock}, {h * 3 / 5, h * 2 / 5}, Qt::Vertical);
    resizeDocks({m_chartsDock}, {h / 2}, Qt::Vertical);
    resizeDocks({m_textureDock}, {h / 2}, Qt::Horizontal);
}

void MainWindow::saveSettings() {
    QSettings settings;
    settings.setValue("window/geometry", saveGeometry());
    settings.setValue("window/state", saveState(kLayoutVersion));
}

} // namespace burnish::studio
