// Mesh files: our own binary PLY writer and reader, everything else through assimp
// (see TriangleMesh.hpp).
#include "sim/core/TriangleMesh.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/core/ErrorText.hpp"
#include "sim/core/PlyHeader.hpp"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>

namespace ferro {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& reason, int code = kExitBadInput) {
    throw MeshFileError(path + ": " + reason, code);
}

std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string extensionOf(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    const size_t dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
    return lower(path.substr(dot + 1));
}

/// Checks that every index names a vertex: a bad index would crash whoever reads the file.
void checkIndices(const std::string& path, const TriangleMesh& mesh) {
    const size_t n = mesh.vertices.size();
    for (const auto& t : mesh.triangles)
        for (uint32_t i : t)
            if (i >= n)
                fail(path, "triangle index " + std::to_string(i) + " out of range (" +
                               std::to_string(n) + " vertices)");
}

/// Writes the byte ranges `parts` one after another to `path` atomically (see
/// sim/core/AtomicFile.hpp), so readers never see a half-written mesh.
void writeParts(const std::string& path, const std::vector<std::pair<const void*, size_t>>& parts) {
    try {
        writeFileAtomically(path, [&](std::ostream& out) {
            for (const auto& [data, size] : parts)
                out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
        });
    } catch (const AtomicFileError& e) {
        fail(path, e.what(), kExitIoError);
    }
}

// ---------------------------------------------------------------------------------------
// Our binary PLY
// ---------------------------------------------------------------------------------------

void writePly(const std::string& path, const TriangleMesh& mesh) {
    if (!hostIsLittleEndian()) fail(path, "binary PLY writing needs a little-endian host");
    const bool withNormals = !mesh.normals.empty();
    if (withNormals && mesh.normals.size() != mesh.vertices.size())
        fail(path, std::to_string(mesh.normals.size()) + " normals for " +
                       std::to_string(mesh.vertices.size()) + " vertices");
    const bool withVelocities = !mesh.velocities.empty();
    if (withVelocities && mesh.velocities.size() != mesh.vertices.size())
        fail(path, std::to_string(mesh.velocities.size()) + " velocities for " +
                       std::to_string(mesh.vertices.size()) + " vertices");
    std::string header;
    try {
        header = binaryPlyHeaderStart(mesh.comments);
    } catch (const std::invalid_argument& e) {
        fail(path, e.what());
    }
    header += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
    header += "property float x\nproperty float y\nproperty float z\n";
    if (withNormals) header += "property float nx\nproperty float ny\nproperty float nz\n";
    if (withVelocities) header += "property float vx\nproperty float vy\nproperty float vz\n";
    header += "element face " + std::to_string(mesh.triangles.size()) + "\n";
    header += "property list uchar uint vertex_indices\nend_header\n";

    const size_t velocityAt = withNormals ? 6 : 3;
    const size_t stride = velocityAt + (withVelocities ? 3 : 0);
    std::vector<float> vertexData(mesh.vertices.size() * stride);
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        float* row = &vertexData[i * stride];
        for (int k = 0; k < 3; ++k) row[k] = mesh.vertices[i][k];
        if (withNormals)
            for (int k = 0; k < 3; ++k) row[3 + k] = mesh.normals[i][k];
        if (withVelocities)
            for (int k = 0; k < 3; ++k) row[velocityAt + size_t(k)] = mesh.velocities[i][k];
    }
    constexpr size_t faceBytes = 1 + 3 * sizeof(uint32_t);
    std::vector<unsigned char> faceData(mesh.triangles.size() * faceBytes);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        unsigned char* p = &faceData[t * faceBytes];
        p[0] = 3;
        std::memcpy(p + 1, mesh.triangles[t].data(), 3 * sizeof(uint32_t));
    }
    writeParts(path, {{header.data(), header.size()},
                      {vertexData.data(), vertexData.size() * sizeof(float)},
                      {faceData.data(), faceData.size()}});
}

/// Every element item with properties takes at least one byte (binary) or two characters
/// (ascii), so counts beyond the bytes after the header are a corrupt or truncated file. Checked
/// for every PLY before anything is allocated, by our reader or by assimp's.
void checkPlyCounts(const std::string& path, const PlyHeader& h, std::istream& in) {
    in.seekg(0, std::ios::end);
    const auto end = in.tellg();
    if (end < 0 || !in) fail(path, "cannot determine the file size");
    const uint64_t available = static_cast<uint64_t>(end) - h.dataOffset;
    uint64_t items = 0;
    for (const auto& e : h.elements) {
        if (e.properties.empty()) continue;
        if (e.count > available - std::min(items, available))
            fail(path, "truncated (the header declares " + std::to_string(e.count) + " " + e.name + " items in " +
                           std::to_string(available) + " bytes)");
        items += e.count;
    }
}

/// assimp's PLY importer sizes a list by its declared length before reading it, so a length
/// of 4294967280 (or a float length) asked for 34 GB (fuzz finding). Walks the data of every
/// element with properties once (their counts are bounded by checkPlyCounts) and checks each
/// list length against the data that follows; called only for files that go to assimp.
void checkPlyLists(const std::string& path, const PlyHeader& h, std::istream& in) {
    bool anyList = false;
    for (const auto& e : h.elements)
        for (const auto& p : e.properties) {
            if (!p.isList) continue;
            anyList = true;
            if (p.countType == PlyScalar::Float32 || p.countType == PlyScalar::Float64)
                fail(path, "bad PLY header: list '" + escapeControl(p.name) + "' has a floating-point length");
        }
    if (!anyList) return;
    in.clear();
    in.seekg(static_cast<std::streamoff>(h.dataOffset));
    const std::string data{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    auto tooLong = [&](const PlyElement& e, const PlyProperty& p, uint64_t item) {
        fail(path, "truncated (" + e.name + " " + std::to_string(item) + ": list '" + escapeControl(p.name) +
                       "' is longer than the rest of the file)");
    };
    if (h.format == PlyFormat::Ascii) {
        size_t pos = 0;
        auto token = [&](std::string& out) {
            while (pos < data.size() && std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
            const size_t b = pos;
            while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos]))) ++pos;
            out.assign(data, b, pos - b);
            return pos > b;
        };
        std::string t;
        for (const auto& e : h.elements) {
            if (e.properties.empty()) continue;
            for (uint64_t i = 0; i < e.count; ++i)
                for (const auto& p : e.properties) {
                    if (!token(t)) return; // truncated: assimp's own error
                    if (!p.isList) continue;
                    // Each item takes at least two characters (digit and separator).
                    char* end = nullptr;
                    const double n = std::strtod(t.c_str(), &end);
                    if (!(n >= 0) || n > double(data.size() - pos) / 2 + 1) tooLong(e, p, i);
                    for (uint64_t k = 0; k < static_cast<uint64_t>(n); ++k)
                        if (!token(t)) return;
                }
        }
        return;
    }
    const bool swap = (h.format == PlyFormat::BinaryLittleEndian) != hostIsLittleEndian();
    size_t pos = 0;
    for (const auto& e : h.elements) {
        if (e.properties.empty()) continue;
        for (uint64_t i = 0; i < e.count; ++i)
            for (const auto& p : e.properties) {
                if (!p.isList) {
                    pos += plyScalarBytes(p.type);
                    // Truncated binary data is ours to refuse: assimp read a list's count from
                    // past the end and allocated 1.35 GB for it (fuzz finding).
                    if (pos > data.size()) fail(path, "truncated: the data ends inside element '" + escapeControl(e.name) + "'");
                    continue;
                }
                const size_t cb = plyScalarBytes(p.countType);
                if (pos + cb > data.size()) fail(path, "truncated: the data ends inside element '" + escapeControl(e.name) + "'");
                unsigned char bytes[4] = {};
                std::memcpy(bytes, data.data() + pos, cb);
                if (swap) std::reverse(bytes, bytes + cb);
                pos += cb;
                uint64_t n = 0;
                switch (p.countType) {
                case PlyScalar::Int8: { int8_t v; std::memcpy(&v, bytes, 1); if (v < 0) tooLong(e, p, i); n = uint64_t(v); break; }
                case PlyScalar::Int16: { int16_t v; std::memcpy(&v, bytes, 2); if (v < 0) tooLong(e, p, i); n = uint64_t(v); break; }
                case PlyScalar::Int32: { int32_t v; std::memcpy(&v, bytes, 4); if (v < 0) tooLong(e, p, i); n = uint64_t(v); break; }
                case PlyScalar::UInt8: { uint8_t v; std::memcpy(&v, bytes, 1); n = v; break; }
                case PlyScalar::UInt16: { uint16_t v; std::memcpy(&v, bytes, 2); n = v; break; }
                default: { uint32_t v; std::memcpy(&v, bytes, 4); n = v; break; }
                }
                const size_t ib = plyScalarBytes(p.type);
                if (n > (data.size() - pos) / ib) tooLong(e, p, i);
                pos += static_cast<size_t>(n) * ib;
            }
    }
}

/// Fast path for the files we write ourselves (and any binary little-endian PLY with float
/// vertex properties and a uchar/uint face list): one read, no assimp scene.
/// False when the file has another layout; throws when it has ours but is broken.
bool readOwnPly(const std::string& path, const PlyHeader& h, std::istream& in, TriangleMesh& mesh) {
    if (h.format != PlyFormat::BinaryLittleEndian || h.elements.size() != 2) return false;
    const auto& ve = h.elements[0];
    const auto& fe = h.elements[1];
    if (ve.name != "vertex" || fe.name != "face") return false;
    int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1, ivx = -1, ivy = -1, ivz = -1;
    for (size_t i = 0; i < ve.properties.size(); ++i) {
        const PlyProperty& p = ve.properties[i];
        if (p.isList || p.type != PlyScalar::Float32) return false;
        const int k = static_cast<int>(i);
        if (p.name == "x") ix = k;
        else if (p.name == "y") iy = k;
        else if (p.name == "z") iz = k;
        else if (p.name == "nx") inx = k;
        else if (p.name == "ny") iny = k;
        else if (p.name == "nz") inz = k;
        else if (p.name == "vx") ivx = k;
        else if (p.name == "vy") ivy = k;
        else if (p.name == "vz") ivz = k;
    }
    if (ix < 0 || iy < 0 || iz < 0) return false;
    if (fe.properties.size() != 1) return false;
    const PlyProperty& fp = fe.properties[0];
    if (!fp.isList || fp.countType != PlyScalar::UInt8 ||
        (fp.type != PlyScalar::UInt32 && fp.type != PlyScalar::Int32))
        return false;
    if (!hostIsLittleEndian()) return false;

    in.seekg(0, std::ios::end);
    const auto end = in.tellg();
    if (end < 0 || !in) fail(path, "cannot determine the file size");
    in.seekg(static_cast<std::streamoff>(h.dataOffset));
    if (!in) fail(path, "cannot seek to the data");
    const uint64_t available = static_cast<uint64_t>(end) - h.dataOffset;
    const size_t cols = ve.properties.size();
    if (ve.count > available / (cols * sizeof(float))) fail(path, "truncated (expected " + std::to_string(ve.count) + " vertices)");
    const size_t nv = static_cast<size_t>(ve.count);
    std::vector<float> rows(nv * cols);
    in.read(reinterpret_cast<char*>(rows.data()), static_cast<std::streamsize>(rows.size() * sizeof(float)));
    if (static_cast<size_t>(in.gcount()) != rows.size() * sizeof(float))
        fail(path, "truncated (expected " + std::to_string(ve.count) + " vertices)");
    const bool normals = inx >= 0 && iny >= 0 && inz >= 0;
    const bool velocities = ivx >= 0 && ivy >= 0 && ivz >= 0;
    mesh.vertices.resize(nv);
    if (normals) mesh.normals.resize(nv);
    if (velocities) mesh.velocities.resize(nv);
    for (size_t i = 0; i < nv; ++i) {
        const float* r = &rows[i * cols];
        mesh.vertices[i] = Vec3(r[ix], r[iy], r[iz]);
        if (normals) mesh.normals[i] = Vec3(r[inx], r[iny], r[inz]);
        if (velocities) mesh.velocities[i] = Vec3(r[ivx], r[ivy], r[ivz]);
    }

    const uint64_t rest = available - nv * cols * sizeof(float);
    // Every face takes at least one count byte; checked before reserving.
    if (fe.count > rest) fail(path, "truncated (expected " + std::to_string(fe.count) + " faces)");
    std::vector<unsigned char> bytes(static_cast<size_t>(rest));
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    const unsigned char* p = bytes.data();
    const unsigned char* e = p + in.gcount();
    mesh.triangles.reserve(static_cast<size_t>(fe.count));
    uint32_t poly[256];
    for (uint64_t f = 0; f < fe.count; ++f) {
        if (p >= e) fail(path, "truncated (expected " + std::to_string(fe.count) + " faces)");
        const unsigned n = *p++;
        if (size_t(e - p) < n * sizeof(uint32_t))
            fail(path, "truncated (expected " + std::to_string(fe.count) + " faces)");
        std::memcpy(poly, p, n * sizeof(uint32_t));
        p += n * sizeof(uint32_t);
        for (unsigned k = 0; k < n; ++k)
            if (poly[k] >= nv) fail(path, "face " + std::to_string(f) + " has index " +
                                              std::to_string(poly[k]) + " out of range");
        // Polygons become triangle fans (our own files only hold triangles).
        for (unsigned k = 2; k < n; ++k) mesh.triangles.push_back({poly[0], poly[k - 1], poly[k]});
    }
    return true;
}

// ---------------------------------------------------------------------------------------
// assimp
// ---------------------------------------------------------------------------------------

/// The assimp export id for `format` (an id or a file extension), or empty.
std::string assimpFormatId(const std::string& format) {
    const std::string f = lower(format);
    // OBJ without the .mtl side file: a mesh file stays one file, written atomically.
    if (f == "obj") return "objnomtl";
    Assimp::Exporter exporter;
    const size_t n = exporter.GetExportFormatCount();
    for (size_t i = 0; i < n; ++i)
        if (lower(exporter.GetExportFormatDescription(i)->id) == f) return exporter.GetExportFormatDescription(i)->id;
    for (size_t i = 0; i < n; ++i)
        if (lower(exporter.GetExportFormatDescription(i)->fileExtension) == f)
            return exporter.GetExportFormatDescription(i)->id;
    return {};
}

/// A one-mesh assimp scene holding `mesh` (the scene owns copies of the arrays).
std::unique_ptr<aiScene> toAssimpScene(const TriangleMesh& mesh) {
    auto scene = std::make_unique<aiScene>();
    scene->mRootNode = new aiNode();
    scene->mMaterials = new aiMaterial*[1]{new aiMaterial()};
    scene->mNumMaterials = 1;
    auto* m = new aiMesh();
    scene->mMeshes = new aiMesh*[1]{m};
    scene->mNumMeshes = 1;
    scene->mRootNode->mMeshes = new unsigned int[1]{0};
    scene->mRootNode->mNumMeshes = 1;
    m->mMaterialIndex = 0;
    m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    m->mNumVertices = static_cast<unsigned>(mesh.vertices.size());
    m->mVertices = new aiVector3D[m->mNumVertices];
    for (size_t i = 0; i < mesh.vertices.size(); ++i)
        m->mVertices[i] = aiVector3D(mesh.vertices[i].x(), mesh.vertices[i].y(), mesh.vertices[i].z());
    if (!mesh.normals.empty()) {
        m->mNormals = new aiVector3D[m->mNumVertices];
        for (size_t i = 0; i < mesh.normals.size(); ++i)
            m->mNormals[i] = aiVector3D(mesh.normals[i].x(), mesh.normals[i].y(), mesh.normals[i].z());
    }
    m->mNumFaces = static_cast<unsigned>(mesh.triangles.size());
    m->mFaces = new aiFace[m->mNumFaces];
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        aiFace& f = m->mFaces[t];
        f.mNumIndices = 3;
        f.mIndices = new unsigned int[3]{mesh.triangles[t][0], mesh.triangles[t][1], mesh.triangles[t][2]};
    }
    return scene;
}

void writeWithAssimp(const std::string& path, const TriangleMesh& mesh, const std::string& id) {
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.vertices.size())
        fail(path, std::to_string(mesh.normals.size()) + " normals for " +
                       std::to_string(mesh.vertices.size()) + " vertices");
    const std::unique_ptr<aiScene> scene = toAssimpScene(mesh);
    Assimp::Exporter exporter;
    // Exported to memory and written by us, so the file appears atomically.
    const aiExportDataBlob* blob = exporter.ExportToBlob(scene.get(), id);
    if (!blob) fail(path, "assimp export as '" + id + "' failed: " + exporter.GetErrorString());
    writeParts(path, {{blob->data, blob->size}});
}

TriangleMesh readWithAssimp(const std::string& path) {
    Assimp::Importer importer;
    // Points and lines are dropped; only triangles describe a surface.
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    // Imported and validated first, post-processed after: the steps index the vertices with
    // the faces' indices as the importer left them (a PLY face index -5 crashed assimp), and
    // Triangulate aborts the process on a face without indices or when a mesh's primitive
    // types, which importers set from the declared face sizes, disagree with its faces (PLY
    // faces of 0 indices did both); they are refused and recomputed here.
    const aiScene* read = importer.ReadFile(path, aiProcess_ValidateDataStructure);
    if (!read) fail(path, "cannot read mesh: " + oneLine(importer.GetErrorString()));
    for (unsigned k = 0; k < read->mNumMeshes; ++k) {
        aiMesh* m = read->mMeshes[k];
        m->mPrimitiveTypes = 0;
        for (unsigned f = 0; f < m->mNumFaces; ++f) {
            const unsigned n = m->mFaces[f].mNumIndices;
            if (n == 0) fail(path, "face " + std::to_string(f) + " has no vertex indices");
            m->mPrimitiveTypes |= n == 1 ? aiPrimitiveType_POINT : n == 2 ? aiPrimitiveType_LINE
                                : n == 3 ? aiPrimitiveType_TRIANGLE : aiPrimitiveType_POLYGON;
        }
    }
    const aiScene* scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                        aiProcess_SortByPType | aiProcess_PreTransformVertices);
    if (!scene) fail(path, "cannot read mesh: " + oneLine(importer.GetErrorString()));
    TriangleMesh mesh;
    bool allNormals = true;
    for (unsigned k = 0; k < scene->mNumMeshes; ++k) allNormals = allNormals && scene->mMeshes[k]->HasNormals();
    for (unsigned k = 0; k < scene->mNumMeshes; ++k) {
        const aiMesh* m = scene->mMeshes[k];
        const auto base = static_cast<uint32_t>(mesh.vertices.size());
        for (unsigned i = 0; i < m->mNumVertices; ++i) {
            const aiVector3D& v = m->mVertices[i];
            mesh.vertices.emplace_back(v.x, v.y, v.z);
            if (allNormals) {
                const aiVector3D& n = m->mNormals[i];
                mesh.normals.emplace_back(n.x, n.y, n.z);
            }
        }
        for (unsigned f = 0; f < m->mNumFaces; ++f) {
            const aiFace& face = m->mFaces[f];
            if (face.mNumIndices != 3) continue;
            mesh.triangles.push_back({base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
        }
    }
    checkIndices(path, mesh);
    return mesh;
}

} // namespace

// ---------------------------------------------------------------------------------------

void writeMesh(const std::string& path, const TriangleMesh& mesh, const std::string& format) {
    const std::string requested = format.empty() ? extensionOf(path) : lower(format);
    checkIndices(path, mesh);
    if (requested.empty()) fail(path, "no mesh format given and the file name has no extension");
    if (requested == "ply" || requested == "plyb") {
        writePly(path, mesh);
        return;
    }
    const std::string id = assimpFormatId(requested);
    if (id.empty()) fail(path, "unknown mesh format '" + requested + "'");
    writeWithAssimp(path, mesh, id);
}

TriangleMesh readMesh(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno), kExitIoError);
    // A PLY header is read by us (comments, count checks); any other format goes to assimp.
    PlyHeader header;
    bool isPly = true;
    try {
        header = readPlyHeader(in);
    } catch (const PlyHeaderError& e) {
        if (e.kind() == PlyHeaderError::Kind::EndWithoutLineBreak)
            fail(path, "truncated (the header ends without a line break)");
        if (e.kind() == PlyHeaderError::Kind::Malformed) fail(path, e.what());
        // Not PLY by its first line, but a file named .ply or starting with "ply" would still
        // reach assimp's PLY importer, without the count checks below (a face count of
        // 4294967295 after "ply@" crashed it).
        in.clear();
        in.seekg(0);
        char magic[3] = {};
        in.read(magic, 3);
        if (extensionOf(path) == "ply" || lower(std::string(magic, static_cast<size_t>(in.gcount()))) == "ply")
            fail(path, e.what());
        isPly = false;
    }
    if (isPly) {
        // assimp's PLY importer takes positions and normals from different elements of the same
        // name (`vertex 4` with nx, then `vertex 6` with x) and frees an invalid pointer.
        // It also reads a name that starts with digits as the element's count
        // (`element 2222222222222222222face 1` asked for 35 GB).
        for (const PlyElement& e : header.elements)
            if (!e.name.empty() && std::isdigit(static_cast<unsigned char>(e.name[0])))
                fail(path, "bad PLY header: element name '" + escapeControl(e.name) + "' starts with a digit");
        for (size_t i = 0; i < header.elements.size(); ++i)
            for (size_t j = 0; j < i; ++j)
                if (header.elements[j].name == header.elements[i].name)
                    fail(path, "bad PLY header: element '" + escapeControl(header.elements[i].name) + "' appears twice");
        // assimp reads a vertex without x (or y, z) as 0 there: a mesh flattened without a word.
        for (const PlyElement& e : header.elements) {
            if (e.name != "vertex" || e.count == 0) continue;
            for (const char* axis : {"x", "y", "z"})
                if (std::none_of(e.properties.begin(), e.properties.end(),
                                 [&](const PlyProperty& p) { return p.name == axis && !p.isList; }))
                    fail(path, std::string("bad PLY header: the vertex element has no '") + axis + "' property");
        }
        in.clear();
        checkPlyCounts(path, header, in);
        TriangleMesh mesh;
        if (readOwnPly(path, header, in, mesh)) {
            mesh.comments = std::move(header.comments);
            return mesh;
        }
        checkPlyLists(path, header, in);
        // assimp splits header lines at blanks and tabs only: a vertical tab, form feed, NUL or
        // lone carriage return, blank to us, made it read the data from another offset than
        // the one checked above (`end_header` + vertical tab: SEGV).
        in.clear();
        in.seekg(0);
        std::string head(static_cast<size_t>(header.dataOffset), '\0');
        in.read(head.data(), static_cast<std::streamsize>(head.size()));
        for (size_t i = 0; i < head.size(); ++i)
            if (head[i] == '\v' || head[i] == '\f' || head[i] == '\0' ||
                (head[i] == '\r' && (i + 1 >= head.size() || head[i + 1] != '\n')))
                fail(path, "bad PLY header: a control character other than a line break, blank or tab");
    }
    in.close();
    TriangleMesh mesh = readWithAssimp(path);
    if (isPly) mesh.comments = std::move(header.comments);
    return mesh;
}

double enclosedVolume(const TriangleMesh& mesh) {
    if (mesh.triangles.empty()) return 0.0;
    // Tetrahedra against a point near the mesh rather than the origin: the sum of large
    // signed terms would otherwise cancel away digits for a mesh far from the origin.
    const Vec3d origin = mesh.vertices[mesh.triangles[0][0]].cast<double>();
    double sixTimes = 0.0;
    for (const auto& t : mesh.triangles) {
        const Vec3d a = mesh.vertices[t[0]].cast<double>() - origin;
        const Vec3d b = mesh.vertices[t[1]].cast<double>() - origin;
        const Vec3d c = mesh.vertices[t[2]].cast<double>() - origin;
        sixTimes += a.dot(b.cross(c));
    }
    return sixTimes / 6.0;
}

std::vector<Vec3d> areaWeightedNormals(const TriangleMesh& mesh) {
    std::vector<Vec3d> sum(mesh.vertices.size(), Vec3d::Zero());
    for (const auto& t : mesh.triangles) {
        const Vec3d a = mesh.vertices[t[0]].cast<double>();
        const Vec3d b = mesh.vertices[t[1]].cast<double>();
        const Vec3d c = mesh.vertices[t[2]].cast<double>();
        const Vec3d n = (b - a).cross(c - a); // length = twice the area: area weighting
        for (uint32_t i : t) sum[i] += n;
    }
    for (Vec3d& n : sum) {
        const double len = n.norm();
        // A vertex in no triangle (or only degenerate ones) has no direction; +z keeps the
        // normal unit length for renderers that expect one.
        n = len > 0 ? Vec3d(n / len) : Vec3d(0, 0, 1);
    }
    return sum;
}

void computeVertexNormals(TriangleMesh& mesh) {
    const std::vector<Vec3d> n = areaWeightedNormals(mesh);
    mesh.normals.resize(n.size());
    for (size_t i = 0; i < n.size(); ++i) mesh.normals[i] = n[i].cast<Real>();
}

void setComment(TriangleMesh& mesh, const std::string& key, const std::string& value) {
    for (auto& c : mesh.comments)
        if (c.first == key) {
            c.second = value;
            return;
        }
    mesh.comments.emplace_back(key, value);
}

} // namespace ferro
