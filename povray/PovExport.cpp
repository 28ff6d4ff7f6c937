// PovExporter: the scene's [render], [shot] and magnets, and the files of a frame and of the
// shot written under the output directory (atomically, only when changed).
#include "povray/PovText.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/magnets/MagnetState.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/magnets/MagnetScene.hpp"
#include "sim/scene/SimSceneFile.hpp"

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace ferro {

namespace fs = std::filesystem;

bool writeTextFile(const std::string& path, const std::string& text, bool onlyIfChanged)
{
    if (onlyIfChanged) {
        std::ifstream in(path, std::ios::binary);
        if (in) {
            std::ostringstream old;
            old << in.rdbuf();
            if (old.str() == text)
                return false;
        }
    }
    try {
        writeFileAtomically(path, [&](std::ostream& out) { out.write(text.data(), std::streamsize(text.size())); });
    } catch (const AtomicFileError& e) {
        throw PovExportError("cannot write " + path + ": " + e.what());
    }
    return true;
}

PovScene parsePovScene(const SceneDocument& doc, int shotFirst, int shotLast, PovOutput what)
{
    if (what == PovOutput::ShotAndFrames)
        return {describeShot(doc, shotFirst, shotLast), parseMagnets(doc), parseSolids(doc)};
    // Only what exportFrame uses, so that a [render] or [container] edit does not re-export
    // every frame (scripts/shot.mk stamps the export with exactly the keys read here).
    PovScene scene;
    scene.shot.fps = parseShotFps(doc);
    scene.shot.render = parseRenderFrameParams(doc);
    scene.tracks = parseMagnets(doc);
    scene.solids = parseSolids(doc);
    return scene;
}

PovExporter::PovExporter(const SceneDocument& doc, std::string outDir, int shotFirst, int shotLast, PovOutput what)
    : PovExporter(parsePovScene(doc, shotFirst, shotLast, what), std::move(outDir), what)
{
}

PovExporter::PovExporter(PovScene scene, std::string outDir, PovOutput what)
    : outDir_(std::move(outDir)), what_(what), shot_(std::move(scene.shot)), tracks_(std::move(scene.tracks)),
      solids_(std::move(scene.solids)), solidShapes_(solidRenderShapes(solids_, "scene"))
{
    std::error_code ec;
    fs::create_directories(outDir_, ec);
    if (ec || !fs::is_directory(outDir_))
        throw PovExportError("cannot create directory " + outDir_);
}

bool PovExporter::writeShotFiles(bool forceTemplate) const
{
    if (what_ != PovOutput::ShotAndFrames)
        throw std::logic_error("PovExporter::writeShotFiles: made for the frame includes only");
    const fs::path dir(outDir_);
    writeTextFile((dir / "shot.pov").string(), masterScene(shot_), true);
    writeTextFile((dir / "render.ini").string(), renderIni(shot_), true);
    writeTextFile((dir / "shot.ini").string(), shotIni(shot_), true);
    // Motion blur's two passes, only while it is on (scripts/shot.mk renders through blur.ini
    // when it is there).
    for (const auto& [name, text] : {std::make_pair("blur.ini", blurIni(shot_)),
                                     std::make_pair("average.ini", averageIni(shot_)),
                                     std::make_pair("average.pov", averageScene(shot_))}) {
        std::error_code gone;
        if (shot_.render.motionBlur > 1) writeTextFile((dir / name).string(), text, true);
        else fs::remove(dir / name, gone);
    }
    std::error_code ec;
    fs::create_directories(dir / "frames", ec);
    const fs::path look = dir / "look.inc";
    if (!forceTemplate && fs::exists(look))
        return false;
    writeTextFile(look.string(), lookTemplate());
    return true;
}

std::string PovExporter::meshIncludePath(int frame) const
{
    return (fs::path(outDir_) / ("mesh_" + frameTag(frame) + ".inc")).string();
}

std::string PovExporter::magnetIncludePath(int frame) const
{
    return (fs::path(outDir_) / ("magnets_" + frameTag(frame) + ".inc")).string();
}

void PovExporter::exportFrame(const TriangleMesh& mesh, int frame) const
{
    ParticleTable header;
    header.comments = mesh.comments;
    double time = header.commentNumber("time", frame / shot_.fps);
    if (!std::isfinite(time))
        time = frame / shot_.fps;
    const std::vector<Magnet> magnets = frameMagnets(mesh, tracks_, time);
    writeTextFile(meshIncludePath(frame), meshInclude(mesh, frame, shot_.render.motionBlur > 1));
    std::string text = magnetInclude(magnets, shot_.render, frame, time);
    if (!solids_.empty()) text += solidInclude(solids_, solidShapes_, time); // none: the file as before
    writeTextFile(magnetIncludePath(frame), text);
}

void PovExporter::exportFrameFile(const std::string& meshPath, int frame) const
{
    refuseToOverwriteInputs("--out", meshIncludePath(frame), {meshPath});
    refuseToOverwriteInputs("--out", magnetIncludePath(frame), {meshPath});
    requireReadable(meshPath);
    const TriangleMesh mesh = readMesh(meshPath); // its errors name the file already
    try {
        exportFrame(mesh, frame);
    } catch (const MeshFileError& e) {
        throw MeshFileError(meshPath + ": " + e.what(), e.code());
    }
}

} // namespace ferro
