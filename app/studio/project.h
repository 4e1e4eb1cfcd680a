// The project file (.burnish): versioned JSON holding every setting of a MaterialDocument, with
// texture paths relative to the project file; and the autosave copies kept beside the user's data.
//
// Format, version 1:
//   {
//     "format": "burnish-project", "version": 1,
//     "material": {"class": "metal"|"dielectric",
//                  "specular": {"material": "iron"|null, "linear": [r, g, b]},
//                  "albedo": [r, g, b], "gloss": g},          // gloss in the preset's encoding
//     "maps": {"normal": path|null, "gloss": path|null, "detail": path|null,  // null normal = sample
//              "allowImplausible": ["normal", "detail"]},  // optional: maps loaded past the
//                                                          // plausibility check ("Load Anyway")
//     "method": "variance-to-gloss", "preset": "blackops",
//     "export": {"format": name|null, "compression": name|null, "mips": 0, "outputFolder": path|null,
//                "overwrite": false},
//     "environment": {"source": "off"|"studio"|"file", "file": path|null, // the viewport's lighting
//                     "rotation": degrees, "intensity": x, "lobe": "blinn-phong"|"phong",
//                     "fis": false, "fisSamples": n},     // optional: absent = the defaults
//     "layers": [{"name": "gloss"|"variance-offset", "file": "<project>.layers/<name>.exr"}],
//                                          // painted layers: float EXR (value, coverage) beside the
//                                          // project, written atomically; only painted layers
//     "view": {"mesh": "sphere"|"plane"|"torus"|"obj", "obj": path|null,  // the 3D view; optional:
//              "yaw": deg, "pitch": deg, "distance": radii, "target": [x, y, z]},  // absent = defaults
//     "autosaveOf": path                                                  // autosave copies only
//   }
// Paths are relative to the file's folder (absolute when no relative form exists).
#pragma once

#include "material_document.h"

#include <burnish/core/util/result.h>
#include <burnish/render/features.h>

#include <QDateTime>
#include <QLockFile>
#include <QString>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace burnish::studio {

inline constexpr const char* kProjectFormat = "burnish-project";
/// The newest project version this studio reads and the one it writes.
inline constexpr int kProjectVersion = 1;
inline constexpr const char* kProjectSuffix = "burnish";

/// The 3D view a project reopens with: the viewport's mesh and camera (not undoable edits of the
/// material, so kept beside its settings).
struct ProjectView {
    render::MeshKind mesh = render::MeshKind::Sphere;
    QString objPath; // absolute; for MeshKind::Obj
    double yawDegrees = 30.0;
    double pitchDegrees = 20.0;
    double distance = 3.0; // from the target, in the mesh's radii
    std::array<double, 3> target{0.0, 0.0, 0.0};
};

/// The project JSON for `settings` saved as `projectFile` (paths made relative to its folder).
/// `autosaveOf` is recorded in autosave copies: the project the copy belongs to.
std::string projectToJson(const MaterialSettings& settings, const QString& projectFile,
                          const QString& autosaveOf = {}, const std::vector<LayerFile>& layers = {},
                          const std::optional<ProjectView>& view = std::nullopt);

/// The folder of a project's painted layers: <folder>/<project name>.layers.
QString layerFolderFor(const QString& projectFile);
/// Where a layer of a project is saved: <layer folder>/<layer name>-<content hash>.exr.
QString layerPathFor(const QString& projectFile, const PaintLayer& layer);
/// Removes the layer files Burnish wrote for `projectFile` that `keep` does not name (and the
/// layer folder when that leaves it empty). Other files are never touched.
void removeStaleLayerFiles(const QString& projectFile, const std::vector<LayerFile>& keep);
/// Removes a project file and its layer files (an autosave copy no longer needed).
Status removeProject(const QString& projectFile);

struct ParsedProject {
    MaterialSettings settings;       // paths absolute
    QString autosaveOf;              // empty unless the file is an autosave copy
    std::vector<LayerFile> layers;   // painted layers to load (paths absolute)
    std::optional<ProjectView> view; // absent in projects saved before views were
};

/// Parses and validates a project read from `projectFile` (relative paths resolve against its
/// folder). Every field is checked before anything is returned; the error is one line naming the
/// file and the field. Loading the maps is the document's job (MaterialDocument::reset).
Result<ParsedProject> parseProject(std::string_view json, const QString& projectFile);

/// Writes the project atomically (core's writeFileAtomic).
/// Painted `layers` (those with any coverage) are written first, each atomically, as EXR files at
/// layerPathFor() (named by content); the JSON names them; then the layer files no longer named
/// are removed. A save interrupted anywhere leaves the previous project and its layers whole.
Status saveProject(const MaterialSettings& settings, const QString& projectFile,
                   const QString& autosaveOf = {}, const std::vector<const PaintLayer*>& layers = {},
                   const std::optional<ProjectView>& view = std::nullopt);
/// Reads and parses a project file.
Result<ParsedProject> loadProject(const QString& projectFile);

/// The folder autosave copies go to: <AppDataLocation>/autosave.
QString autosaveFolder();
/// The autosave copy of a project: <autosaveFolder>/<name>-<hash of the absolute path>.burnish.
QString autosavePathFor(const QString& projectFile);
/// A fresh name for an untitled document's copy, unique to this process and moment
/// (<autosaveFolder>/untitled-<date>-<time>-<pid>-<n>.burnish): one window's untitled work never
/// overwrites another's, nor a crashed run's.
QString newUntitledAutosavePath();
/// The autosave copy to offer for recovery: it exists and is newer than the project (or the
/// project file is missing). Empty when there is nothing to recover.
std::optional<QString> recoverableAutosave(const QString& projectFile);

/// The lock a window holds on the autosave copy it writes (<copy>.lock, QLockFile: the process id,
/// never stale while that process lives). A copy whose lock a live process holds is that window's
/// work in progress, not a crash's leftover. Null when another live process (or window) holds it.
std::unique_ptr<QLockFile> claimAutosave(const QString& copy);

/// An autosave copy left by a window that is gone (a crash, a kill).
struct AutosaveCopy {
    QString path;
    QString autosaveOf; // the project it belongs to; empty for untitled work (or an unreadable copy)
    QDateTime modified;
};
/// Every copy in autosaveFolder() worth offering after a crash, newest first: not held by a live
/// window, and untitled, or newer than its project, or its project gone.
std::vector<AutosaveCopy> recoverableAutosaves();

} // namespace burnish::studio
