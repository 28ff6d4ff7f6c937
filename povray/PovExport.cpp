#include "povray/PovExport.hpp"

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

Vec3d toPovPoint(const Vec3d& p)
{
    return kPovUnitsPerMetre * Vec3d(p.x(), p.z(), p.y());
}

Vec3d toPovDirection(const Vec3d& d)
{
    return Vec3d(d.x(), d.z(), d.y());
}

void appendNumber(std::string& out, double v, int decimals)
{
    if (!std::isfinite(v))
        v = 0.0;
    char buf[64];
    auto res = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
    char* end = res.ptr;
    if (res.ec != std::errc()) { // beyond 1e40 or so: never a mesh coordinate, but stay valid
        end = buf + std::snprintf(buf, sizeof buf, "%.9g", v);
    } else if (decimals > 0) {
        while (end[-1] == '0') --end;
        if (end[-1] == '.') --end;
    }
    // "-0" (a tiny negative rounded away) is just 0.
    if (end - buf == 2 && buf[0] == '-' && buf[1] == '0')
        out += '0';
    else
        out.append(buf, end);
}

void appendVector(std::string& out, const Vec3d& v, int decimals)
{
    out += '<';
    appendNumber(out, v.x(), decimals);
    out += ',';
    appendNumber(out, v.y(), decimals);
    out += ',';
    appendNumber(out, v.z(), decimals);
    out += '>';
}

namespace {

std::string frameTag(int frame)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "%04d", frame);
    return buf;
}

std::string number(double v, int decimals = 6)
{
    std::string s;
    appendNumber(s, v, decimals);
    return s;
}

std::string vec(const Vec3d& v, int decimals = 6)
{
    std::string s;
    appendVector(s, v, decimals);
    return s;
}

std::string quoted(const std::string& s)
{
    std::string q = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') q += '\\';
        q += c;
    }
    return q + '"';
}

// Unit vertex normals of `mesh`, computed from the triangles when the mesh has none.
std::vector<Vec3> vertexNormals(const TriangleMesh& mesh)
{
    if (mesh.normals.size() == mesh.vertices.size())
        return mesh.normals;
    std::vector<Vec3> normals;
    for (const Vec3d& n : areaWeightedNormals(mesh))
        normals.push_back(n.cast<Real>());
    return normals;
}

} // namespace

std::string meshInclude(const TriangleMesh& mesh, int frame)
{
    const size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
    std::string out;
    // About 25 bytes per vertex position, 20 per normal, 20 per triangle.
    out.reserve(256 + nv * 50 + nt * 22);
    out += "// mesh_" + frameTag(frame) + ".inc: the fluid surface of frame " + std::to_string(frame) +
           ", written by ferro-pov.\n// POV-Ray millimetres, y up: <x, y, z> here is Ferro's (x, z, y) in mm.\n";
    out += "#declare FerroMeshVertices = " + std::to_string(nt ? nv : 0) + ";\n";
    out += "#declare FerroMeshTriangles = " + std::to_string(nt) + ";\n";
    if (nt == 0)
        return out + "// Empty surface: no FerroMesh is declared (POV-Ray rejects a mesh2 without faces).\n";

    for (const auto& t : mesh.triangles)
        for (uint32_t i : t)
            if (i >= nv)
                throw MeshFileError("triangle refers to vertex " + std::to_string(i) + " of " + std::to_string(nv));
    // POV-Ray has no literal for inf or NaN; writing them as anything would hide a broken mesh.
    for (size_t i = 0; i < nv; ++i)
        if (!mesh.vertices[i].allFinite())
            throw MeshFileError("vertex " + std::to_string(i) + " is not finite");
    Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const Vec3& v : mesh.vertices) {
        const Vec3d p = toPovPoint(v.cast<double>());
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
    }
    out += "#declare FerroMeshMin = " + vec(lo, kPositionDecimals) + ";\n";
    out += "#declare FerroMeshMax = " + vec(hi, kPositionDecimals) + ";\n";

    out += "#declare FerroMesh = mesh2 {\n vertex_vectors { " + std::to_string(nv);
    for (const Vec3& v : mesh.vertices) {
        out += ",\n";
        appendVector(out, toPovPoint(v.cast<double>()), kPositionDecimals);
    }
    const std::vector<Vec3> normals = vertexNormals(mesh);
    out += "\n }\n normal_vectors { " + std::to_string(nv);
    for (const Vec3& n : normals) {
        Vec3d d = toPovDirection(n.cast<double>());
        const double len = d.norm();
        // A vertex without a defined normal (isolated, degenerate fan) gets "up": harmless,
        // POV-Ray only interpolates normals for shading.
        d = len > 0 && std::isfinite(len) ? Vec3d(d / len) : Vec3d(0, 1, 0);
        out += ",\n";
        appendVector(out, d, kNormalDecimals);
    }
    // Without normal_indices POV-Ray takes the face indices for the normals as well.
    out += "\n }\n face_indices { " + std::to_string(nt);
    char buf[48];
    for (const auto& t : mesh.triangles) {
        const int n = std::snprintf(buf, sizeof buf, ",\n<%u,%u,%u>", t[0], t[1], t[2]);
        out.append(buf, size_t(n));
    }
    out += "\n }\n}\n";
    return out;
}

std::vector<Magnet> frameMagnets(const TriangleMesh& mesh, const std::vector<MagnetTrack>& tracks, double time)
{
    ParticleTable header;
    header.comments = mesh.comments;
    if (!header.comment("magnet_count").empty()) {
        try {
            return readMagnetComments(header);
        } catch (const ParticleFileError& e) {
            throw MeshFileError(std::string("mesh header: ") + e.what());
        }
    }
    std::vector<Magnet> magnets;
    for (const MagnetTrack& t : tracks)
        magnets.push_back(t.at(time));
    return magnets;
}

std::string magnetInclude(const std::vector<Magnet>& magnets, const RenderParams& render, int frame, double time)
{
    std::ostringstream out;
    out << "// magnets_" << frameTag(frame) << ".inc: the magnets at frame " << frame << " (t = " << number(time)
        << " s), written by ferro-pov.\n"
           "// POV-Ray millimetres, y up. Direction is the magnetic axis, south -> north (flipped\n"
           "// for a negative strength); Length and Radius are display sizes (render.magnet_length,\n"
           "// render.magnet_radius for point dipoles, the pole distance of bar magnets, the loop radius).\n";
    // Uniform fields have no place and no body: they are listed but get no object.
    const size_t n = magnets.size();
    out << "#declare FerroMagnetCount = " << n << ";\n";
    if (n == 0)
        return out.str();
    auto array = [&](const char* name, auto&& item) {
        out << "#declare " << name << " = array[" << n << "] {";
        for (size_t i = 0; i < n; ++i)
            out << (i ? ", " : " ") << item(magnets[i]);
        out << " }\n";
    };
    auto axis = [](const Magnet& m) -> Vec3d {
        const double len = m.direction.norm();
        Vec3d d = len > 0 ? Vec3d(m.direction / len) : Vec3d(0, 0, 1);
        return m.strength < 0 ? Vec3d(-d) : d;
    };
    auto length = [&](const Magnet& m) {
        return magnetKindInfo(m.kind).usesLength && m.length > 0 ? m.length : render.magnetLength;
    };
    auto radius = [&](const Magnet& m) {
        return magnetKindInfo(m.kind).usesRadius && m.radius > 0 ? m.radius : render.magnetRadius;
    };
    array("FerroMagnetKind", [](const Magnet& m) { return quoted(magnetKindName(m.kind)); });
    array("FerroMagnetPosition", [](const Magnet& m) { return vec(toPovPoint(m.position)); });
    array("FerroMagnetDirection", [&](const Magnet& m) { return vec(toPovDirection(axis(m))); });
    array("FerroMagnetLength", [&](const Magnet& m) { return number(length(m) * kPovUnitsPerMetre); });
    array("FerroMagnetRadius", [&](const Magnet& m) { return number(radius(m) * kPovUnitsPerMetre); });
    array("FerroMagnetStrength", [](const Magnet& m) {
        std::ostringstream s;
        s.precision(9);
        s << std::fabs(m.strength);
        return s.str();
    });

    // Bodies: a cylinder per dipole or bar magnet, split at the centre into its north and south
    // halves; a torus (wire) per current loop, counted as "south" (the neutral body).
    std::vector<std::string> north, south;
    for (const Magnet& m : magnets) {
        const Vec3d c = toPovPoint(m.position);
        const Vec3d d = toPovDirection(axis(m));
        const double half = 0.5 * length(m) * kPovUnitsPerMetre;
        const double r = radius(m) * kPovUnitsPerMetre;
        const MagnetBody body = magnetKindInfo(m.kind).body;
        if (body == MagnetBody::Rod) {
            north.push_back("cylinder { " + vec(c) + ", " + vec(c + half * d) + ", " + number(r) + " }");
            south.push_back("cylinder { " + vec(c - half * d) + ", " + vec(c) + ", " + number(r) + " }");
        } else if (body == MagnetBody::Ring) {
            // A torus lies in the xz plane around y: map y onto the axis with an orthonormal
            // frame (any frame will do, the torus is round) and move it to the centre. POV-Ray's
            // matrix takes the images of x, y, z as rows, then the translation.
            const double wire = std::max(0.02 * r, 0.5);
            const Vec3d ex = (std::fabs(d.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitZ());
            const Vec3d bx = (ex - ex.dot(d) * d).normalized();
            const Vec3d bz(bx.y() * d.z() - bx.z() * d.y(), bx.z() * d.x() - bx.x() * d.z(), bx.x() * d.y() - bx.y() * d.x());
            auto row = [](const Vec3d& v) { return number(v.x()) + "," + number(v.y()) + "," + number(v.z()); };
            south.push_back("torus { " + number(r) + ", " + number(wire) + " matrix <" + row(bx) + ", " + row(d) + ", " +
                            row(bz) + ", " + row(c) + "> }");
        }
    }
    auto group = [&](const char* name, const std::vector<std::string>& parts) {
        if (parts.empty())
            return;
        out << "#declare " << name << " = ";
        if (parts.size() == 1) {
            out << parts[0] << "\n";
            return;
        }
        out << "union {\n";
        for (const auto& p : parts)
            out << "  " << p << "\n";
        out << "}\n";
    };
    group("FerroMagnetsNorth", north);
    group("FerroMagnetsSouth", south);
    return out.str();
}

ShotDescription describeShot(const SceneDocument& doc, int first, int last)
{
    const SimScene scene = parseSimScene(doc);
    ShotDescription shot;
    shot.render = parseRenderParams(doc);
    shot.container = scene.container;
    shot.fps = scene.shot.fps;
    shot.firstFrame = first >= 0 ? first : 0;
    shot.lastFrame = last >= 0 ? last : scene.shot.frameCount();
    if (shot.lastFrame < shot.firstFrame)
        shot.lastFrame = shot.firstFrame;

    // The set: the vessel if there is one, else the fluid's starting blocks.
    const ContainerParams& c = scene.container;
    double bottom = 0.0;
    if (c.type == ContainerParams::Type::Dish) {
        shot.setCenter = c.center;
        shot.setRadius = c.radius;
        bottom = c.center.z() - 0.002; // the look's dish has a floor 1.5 mm thick
    } else if (c.type == ContainerParams::Type::Box) {
        shot.setCenter = 0.5 * (c.min + c.max);
        shot.setCenter.z() = c.min.z();
        shot.setRadius = 0.5 * (c.max - c.min).head<2>().norm();
        bottom = c.min.z();
    } else {
        Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
        for (const FluidBlock& b : scene.fluid.blocks) {
            const bool box = b.shape == FluidBlock::Shape::Box;
            const Vec3d blo = box ? b.min : Vec3d(b.center - Vec3d(b.radius, b.radius, 0));
            const Vec3d bhi = box ? b.max : Vec3d(b.center + Vec3d(b.radius, b.radius, b.height));
            lo = lo.cwiseMin(blo);
            hi = hi.cwiseMax(bhi);
        }
        shot.setCenter = Vec3d(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), lo.z());
        shot.setRadius = std::max(0.5 * (hi - lo).head<2>().norm(), 1e-3);
        bottom = lo.z();
    }
    // The floor lies under the vessel and under every magnet at every frame of the shot, so a
    // magnet that approaches from below is seen under the dish instead of vanishing in the floor.
    double floor = bottom;
    const int frames = scene.shot.frameCount();
    for (const MagnetTrack& track : scene.magnets) {
        if (magnetKindInfo(track.base.kind).body == MagnetBody::None)
            continue;
        for (int f = 0; f <= frames; ++f) {
            const Magnet m = track.at(f / scene.shot.fps);
            const double len = magnetKindInfo(m.kind).usesLength ? m.length : shot.render.magnetLength;
            const double rad = magnetKindInfo(m.kind).usesRadius ? m.radius : shot.render.magnetRadius;
            const Vec3d d = m.direction.norm() > 0 ? Vec3d(m.direction.normalized()) : Vec3d(0, 0, 1);
            const double extent = 0.5 * len * std::fabs(d.z()) + rad * std::sqrt(std::max(0.0, 1 - d.z() * d.z()));
            floor = std::min(floor, m.position.z() - extent - 0.002);
        }
    }
    shot.floorLevel = floor;
    return shot;
}

std::string masterScene(const ShotDescription& shot)
{
    const RenderParams& r = shot.render;
    const ContainerParams& c = shot.container;
    std::ostringstream s;
    s << "// shot.pov: master scene of the shot, written by ferro-pov on every export.\n"
         "// Do not edit: your changes would be lost. The look (camera, lights, materials, dish,\n"
         "// floor, magnets) lives in look.inc, which ferro-pov never overwrites.\n"
         "//\n"
         "// Render: povray shot.ini (all frames), povray shot.ini +SF10 +EF20 (frames 10..20),\n"
         "//         povray render.ini Declare=FerroFrame=12 +Oframe.png (one frame, no animation).\n"
         "//\n"
         "// Coordinates: POV-Ray units are millimetres, y is up, left-handed. A Ferro point\n"
         "// (x, y, z) [m] (z up, right-handed) is <1000 x, 1000 z, 1000 y> here; swapping y and z\n"
         "// is the reflection that maps the right-handed frame onto POV-Ray's left-handed one.\n"
         "#version 3.7;\n\n"
         "// The frame: POV-Ray's animation frame_number unless given as Declare=FerroFrame=N.\n"
         "#ifndef (FerroFrame) #declare FerroFrame = frame_number; #end\n"
      << "#declare FerroFps = " << number(shot.fps) << ";\n"
      << "#declare FerroTime = FerroFrame / FerroFps;   // [s]\n"
      << "#declare FerroFirstFrame = " << shot.firstFrame << ";\n"
      << "#declare FerroLastFrame = " << shot.lastFrame << ";\n\n"
      << "// [render]\n"
      << "#declare FerroCameraLocation = " << vec(toPovPoint(r.cameraPosition)) << ";\n"
      << "#declare FerroCameraLookAt = " << vec(toPovPoint(r.cameraTarget)) << ";\n"
      << "#declare FerroCameraAngle = " << number(r.cameraAngle) << ";   // horizontal field of view [deg]\n"
      << "#declare FerroAspect = image_width / image_height;\n"
      << "#declare FerroLightSamples = " << r.lightSamples << ";   // area light grid N x N (look.inc's soft boxes)\n\n"
      << "// The set: its centre (on the vessel's floor) and radius, for lights and backdrop.\n"
      << "#declare FerroSetCenter = " << vec(toPovPoint(shot.setCenter)) << ";\n"
      << "#declare FerroSetRadius = " << number(shot.setRadius * kPovUnitsPerMetre) << ";\n"
      << "#declare FerroFloorLevel = " << number(shot.floorLevel * kPovUnitsPerMetre)
      << ";   // y of the floor: under the vessel and every magnet of the shot\n\n"
      << "// [container]\n";
    switch (c.type) {
    case ContainerParams::Type::Dish:
        s << "#declare FerroContainerType = \"dish\";\n"
          << "#declare FerroDishCenter = " << vec(toPovPoint(c.center)) << ";   // centre of the inner floor\n"
          << "#declare FerroDishRadius = " << number(c.radius * kPovUnitsPerMetre) << ";   // inner radius\n"
          << "#declare FerroDishHeight = " << number(c.height * kPovUnitsPerMetre) << ";   // wall height\n";
        break;
    case ContainerParams::Type::Box:
        s << "#declare FerroContainerType = \"box\";\n"
          << "#declare FerroBoxMin = " << vec(toPovPoint(c.min)) << ";\n"
          << "#declare FerroBoxMax = " << vec(toPovPoint(c.max)) << ";\n";
        break;
    case ContainerParams::Type::Mesh:
        s << "#declare FerroContainerType = \"mesh\";   // not drawn: model it in look.inc\n";
        break;
    case ContainerParams::Type::None:
        s << "#declare FerroContainerType = \"none\";\n";
        break;
    }
    s << "\n// The frame's data: FerroMesh (if the surface has triangles) and the magnets.\n"
         "#include concat(\"mesh_\", str(FerroFrame, -4, 0), \".inc\")\n"
         "#include concat(\"magnets_\", str(FerroFrame, -4, 0), \".inc\")\n\n"
         "// Everything that makes the picture.\n"
         "#include \"look.inc\"\n";
    return s.str();
}

std::string renderIni(const ShotDescription& shot)
{
    const RenderParams& r = shot.render;
    std::ostringstream s;
    s << "; render.ini: image settings from the scene's [render], written by ferro-pov on every export.\n"
         "; One frame: povray render.ini Declare=FerroFrame=12 +Oframe_0012.png\n"
      << "Input_File_Name=shot.pov\n"
      << "Width=" << r.width << "\nHeight=" << r.height << "\n"
      << "Quality=" << r.quality << "\n"
      << "Antialias=" << (r.antialias ? "on" : "off") << "\n"
      << "Antialias_Threshold=" << number(r.antialiasThreshold) << "\n"
      << "Antialias_Depth=" << r.antialiasDepth << "\n"
      << "Sampling_Method=2\n"
      << "Jitter=off\n"
      << "Output_File_Type=N\n"
      << "Output_Alpha=off\n"
      << "Display=off\n"
      << "Verbose=off\n";
    return s.str();
}

std::string shotIni(const ShotDescription& shot)
{
    std::ostringstream s;
    s << "; shot.ini: the shot as a POV-Ray animation, written by ferro-pov on every export.\n"
         "; povray shot.ini             renders every frame into frames/\n"
         "; povray shot.ini +SF10 +EF20 renders frames 10..20 (POV-Ray pads the frame number in\n"
         ";                             the file name to the digits of Final_Frame)\n"
         "render.ini\n"
      << "Initial_Frame=" << shot.firstFrame << "\n"
      << "Final_Frame=" << shot.lastFrame << "\n"
      << "Initial_Clock=" << number(shot.firstFrame / shot.fps) << "\n"
      << "Final_Clock=" << number(shot.lastFrame / shot.fps) << "\n"
      << "Cyclic_Animation=off\n"
      << "Output_File_Name=frames/shot_\n";
    return s.str();
}

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
        if (e.step() == AtomicFileError::Step::Rename)
            throw PovExportError("cannot write " + path + ": " + std::strerror(e.errorNumber()));
        throw PovExportError("cannot write " + path);
    }
    return true;
}

PovScene parsePovScene(const SceneDocument& doc, int shotFirst, int shotLast, PovOutput what)
{
    if (what == PovOutput::ShotAndFrames)
        return {describeShot(doc, shotFirst, shotLast), parseMagnets(doc)};
    // Only what exportFrame uses, so that a [render] or [container] edit does not re-export
    // every frame (scripts/shot.mk stamps the export with exactly the keys read here).
    PovScene scene;
    scene.shot.fps = parseShotFps(doc);
    scene.shot.render = parseRenderMagnetSizes(doc);
    scene.tracks = parseMagnets(doc);
    return scene;
}

PovExporter::PovExporter(const SceneDocument& doc, std::string outDir, int shotFirst, int shotLast, PovOutput what)
    : PovExporter(parsePovScene(doc, shotFirst, shotLast, what), std::move(outDir), what)
{
}

PovExporter::PovExporter(PovScene scene, std::string outDir, PovOutput what)
    : outDir_(std::move(outDir)), what_(what), shot_(std::move(scene.shot)), tracks_(std::move(scene.tracks))
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
    writeTextFile(meshIncludePath(frame), meshInclude(mesh, frame));
    writeTextFile(magnetIncludePath(frame), magnetInclude(magnets, shot_.render, frame, time));
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
