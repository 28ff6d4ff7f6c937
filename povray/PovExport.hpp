#pragma once
// POV-Ray export of a shot: per frame a mesh2 include and a magnets include, per shot a
// master scene, two .ini files and the artist-editable look template.
//
// Coordinates. Ferro works in SI metres, z up, right-handed. POV-Ray is y up and
// left-handed. A Ferro point (x, y, z) [m] is exported as <1000 x, 1000 z, 1000 y>:
//   - swapping y and z puts Ferro's up (z) on POV-Ray's up (y); a swap of two axes is a
//     reflection, which is exactly what turns the right-handed frame into POV-Ray's
//     left-handed one, so the picture is not mirrored (Ferro's +x is to the right of a
//     camera that looks along Ferro's +y, as it is in POV-Ray looking along its +z);
//   - POV-Ray units are millimetres: POV-Ray's intersection tolerances are absolute (of the
//     order of 1e-4..1e-6 units) and were made for scenes a few units across, so a 10 cm dish
//     with sub-millimetre triangles must not be modelled in metres.
//
// Files in the shot directory SHOTDIR:
//   mesh_NNNN.inc     #declare FerroMesh = mesh2 {...} (only if the mesh has triangles) and
//                     FerroMeshTriangles, FerroMeshVertices, FerroMeshMin/Max  (per frame)
//   magnets_NNNN.inc  FerroMagnetCount and, if > 0, arrays FerroMagnetKind/Position/
//                     Direction/Length/Radius/Strength and the objects FerroMagnetsNorth,
//                     FerroMagnetsSouth; with [[solids]], FerroSolidCount and
//                     FerroSolids                                                (per frame)
//   shot.pov          master scene: scene data as #declares, picks the frame's includes
//                     from frame_number, includes look.inc       (rewritten on every export)
//   render.ini        image settings of [render] (size, quality, antialiasing), no animation
//   shot.ini          render.ini + the shot's frame range as an animation, so
//                     `povray shot.ini +SF10 +EF20` renders frames 10..20 into frames/
//   look.inc          camera, lights, materials, dish, floor, magnets: the artists' file,
//                     written only when missing or with forceTemplate
// Every file is written atomically; shot.pov and the .ini files are only replaced when their
// text changes, so re-exporting frames does not make finished renders look stale to make.
#include "povray/RenderParams.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/solids/SolidParams.hpp"
#include "sim/scene/SimParams.hpp"
#include "sim/core/StageErrors.hpp"
#include "sim/core/TriangleMesh.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace ferro {

class SceneDocument;

/// A file that could not be written (exit code 4 in ferro-pov).
class PovExportError : public StageError {
public:
    explicit PovExportError(const std::string& what) : StageError(kExitIoError, what) {}
};

/// An input mesh that is missing or cannot be opened (exit 4; requireReadable throws it); a
/// file that opens but is not a usable mesh is a MeshFileError (exit 2).
using PovInputMissing = InputMissingError;

/// POV-Ray units per metre: exported scenes are in millimetres.
constexpr double kPovUnitsPerMetre = 1000.0;
/// Decimals written for positions (in mm: 1e-3 mm = 1 micrometre) and unit normals.
constexpr int kPositionDecimals = 3;
constexpr int kNormalDecimals = 4;

/// Ferro point (x, y, z) [m] -> POV-Ray point <1000 x, 1000 z, 1000 y> [mm].
Vec3d toPovPoint(const Vec3d& p);
/// Ferro direction (x, y, z) -> POV-Ray <x, z, y> (same length).
Vec3d toPovDirection(const Vec3d& d);

/// Appends `v` rounded to `decimals` digits after the point, with trailing zeros and a
/// trailing point removed: 1.5, -0.002, 3, 0 (never "-0"). Non-finite values are written as 0
/// (POV-Ray has no literal for them); meshInclude rejects meshes with non-finite vertices first.
void appendNumber(std::string& out, double v, int decimals);
/// Appends "<a,b,c>" with appendNumber.
void appendVector(std::string& out, const Vec3d& v, int decimals);

/// Text of mesh_NNNN.inc for `mesh` (Ferro coordinates). Vertex normals are written when the
/// mesh has one per vertex, else computed from the triangles. An empty mesh gives a file that
/// declares FerroMeshTriangles = 0 and no FerroMesh (POV-Ray rejects a mesh2 without faces).
/// Throws MeshFileError for an out-of-range index or a non-finite vertex. With `motion` and a
/// velocity per vertex, each vertex is written as its position plus FerroShift [s] times its
/// velocity (FerroShift 0 unless the scene declares it: motion blur's sub-frames).
std::string meshInclude(const TriangleMesh& mesh, int frame, bool motion = false);

/// The magnets at a frame: the ones in the mesh's header comments (`comment magnet_count`,
/// copied by every stage from the particle file) if there are any, else `tracks` at `time`.
/// Throws MeshFileError on malformed magnet comments.
std::vector<Magnet> frameMagnets(const TriangleMesh& mesh, const std::vector<MagnetTrack>& tracks,
                                 double time);

/// Text of magnets_NNNN.inc for `magnets` (Ferro coordinates and units).
std::string magnetInclude(const std::vector<Magnet>& magnets, const RenderParams& render,
                          int frame, double time);

/// What the shot-level files are made of.
struct ShotDescription {
    RenderParams render;
    ContainerParams container;
    double fps = 30.0;
    int firstFrame = 0;             ///< frame range of shot.ini (Initial_Frame .. Final_Frame)
    int lastFrame = 0;
    double floorLevel = 0.0;        ///< z of the floor [m]: below the vessel and every magnet of the shot
    double setRadius = 0.05;        ///< size of the set [m] the look scales its lights with
    Vec3d setCenter{0, 0, 0};       ///< centre of the set [m]
};

/// Collects [render], [container], [shot] and [[magnets]] of `doc` (validating them) into a
/// ShotDescription for frames `first`..`last` (-1: the shot's full range 0..duration*fps).
/// Throws SceneError.
ShotDescription describeShot(const SceneDocument& doc, int first = -1, int last = -1);

/// Texts of the shot-level files.
std::string masterScene(const ShotDescription& shot);
std::string renderIni(const ShotDescription& shot);
std::string shotIni(const ShotDescription& shot);
/// Motion blur (render.motion_blur > 1): blur.ini renders a frame's sub-frames (an animation
/// of motion_blur frames whose clock runs -0.5 .. 0.5 over the shutter, into sub/), and
/// average.ini / average.pov average them into the frame (in linear light).
std::string blurIni(const ShotDescription& shot);
std::string averageIni(const ShotDescription& shot);
std::string averageScene(const ShotDescription& shot);
std::string lookTemplate();

/// Writes `text` to `path` atomically (temporary file + rename). With `onlyIfChanged`, a file
/// that already holds exactly `text` is left alone (keeps its modification time).
/// Returns true if the file was written. Throws PovExportError.
bool writeTextFile(const std::string& path, const std::string& text, bool onlyIfChanged = false);

/// Everything ferro-pov reads from a scene: the shot, the magnets' tracks and the solids.
struct PovScene {
    ShotDescription shot;
    std::vector<MagnetTrack> tracks;
    std::vector<SolidParams> solids;
};

/// The solids' meshes for rendering (a generated shape at a twelfth of its radius, a mesh
/// file as it is). Throws SceneError (naming `where`) for a mesh that cannot be used.
std::vector<ShapeMesh> solidRenderShapes(const std::vector<SolidParams>& solids, const std::string& where);
/// The solids at `time`, appended to magnets_NNNN.inc: FerroSolidCount and FerroSolids (a
/// union of a mesh2 each; POV-Ray millimetres, y up).
std::string solidInclude(const std::vector<SolidParams>& solids, const std::vector<ShapeMesh>& shapes, double time);

/// What an export writes: the shot files and the frame includes, or the frame includes only
/// (mesh_NNNN.inc, magnets_NNNN.inc), which need only the frame rate, the magnets' tracks and
/// their display sizes.
enum class PovOutput { ShotAndFrames, FramesOnly };

/// The whole of ferro-pov's scene parsing (so its --print-scene-inputs lists exactly what an
/// export reads). ShotAndFrames: describeShot and the [[magnets]] tracks; FramesOnly: shot.fps,
/// render.magnet_length / magnet_radius and the tracks (the rest of `shot` is default, and
/// a PovExporter made from it must not write the shot files). Throws SceneError.
PovScene parsePovScene(const SceneDocument& doc, int shotFirst = -1, int shotLast = -1,
                       PovOutput what = PovOutput::ShotAndFrames);

/// Exports one shot into a directory.
class PovExporter {
public:
    /// `outDir` is created if missing. Throws SceneError on a bad scene.
    PovExporter(const SceneDocument& doc, std::string outDir, int shotFirst = -1, int shotLast = -1,
                PovOutput what = PovOutput::ShotAndFrames);
    PovExporter(PovScene scene, std::string outDir, PovOutput what = PovOutput::ShotAndFrames);

    /// shot.pov, render.ini, shot.ini (each only if its text changed) and look.inc (only if
    /// missing, or always with `forceTemplate`). Returns true if look.inc was written.
    bool writeShotFiles(bool forceTemplate) const;

    /// mesh_NNNN.inc and magnets_NNNN.inc of `frame` from an in-memory mesh. The frame's time
    /// is the mesh's `comment time` if present, else frame / fps.
    void exportFrame(const TriangleMesh& mesh, int frame) const;
    /// Same, reading the mesh from a file (any format readMesh reads). Throws PovInputMissing when
    /// the file cannot be opened, MeshFileError when it is not a usable mesh.
    void exportFrameFile(const std::string& meshPath, int frame) const;

    const ShotDescription& shot() const { return shot_; }
    const std::string& outDir() const { return outDir_; }
    /// Path of the frame's include files in outDir.
    std::string meshIncludePath(int frame) const;
    std::string magnetIncludePath(int frame) const;

private:
    std::string outDir_;
    PovOutput what_;
    ShotDescription shot_;
    std::vector<MagnetTrack> tracks_;
    std::vector<SolidParams> solids_;
    std::vector<ShapeMesh> solidShapes_;
};

} // namespace ferro
