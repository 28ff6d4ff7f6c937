// Mesh files: our own binary PLY writer and reader, everything else through assimp
// (see TriangleMesh.hpp).
#include "surface/TriangleMesh.hpp"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>

#include <unistd.h>

namespace ferro {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
    throw MeshFileError(path + ": " + reason);
}

bool hostIsLittleEndian() {
    const uint32_t one = 1;
    unsigned char first = 0;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

bool isSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

std::string trim(const std::string& s) {
    size_t b = 0, e = s.size();
    while (b < e && isSpace(s[b])) ++b;
    while (e > b && isSpace(s[e - 1])) --e;
    return s.substr(b, e - b);
}

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && isSpace(s[i])) ++i;
        size_t j = i;
        while (j < s.size() && !isSpace(s[j])) ++j;
        if (j > i) out.push_back(s.substr(i, j - i));
        i = j;
    }
    return out;
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

/// Writes `bytes` to `path` atomically: a temporary file in the same directory, renamed
/// over the target only once complete, so readers never see a half-written mesh.
void writeFileAtomically(const std::string& path, const std::vector<std::pair<const void*, size_t>>& parts) {
    const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) fail(path, "cannot create " + tmp + ": " + std::strerror(errno));
    auto abandon = [&](const char* what) {
        const int err = errno;
        if (f) std::fclose(f);
        std::remove(tmp.c_str());
        fail(path, std::string(what) + ": " + std::strerror(err));
    };
    for (const auto& [data, size] : parts)
        if (size > 0 && std::fwrite(data, 1, size, f) != size) abandon("write failed");
    const int closed = std::fclose(f);
    f = nullptr;
    if (closed != 0) abandon("write failed");
    if (std::rename(tmp.c_str(), path.c_str()) != 0) abandon("cannot rename the temporary file");
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
    std::string header = "ply\nformat binary_little_endian 1.0\n";
    for (const auto& [key, value] : mesh.comments) {
        if (key.empty() || std::any_of(key.begin(), key.end(), isSpace))
            fail(path, "bad comment key '" + key + "'");
        if (value.find_first_of("\r\n") != std::string::npos)
            fail(path, "comment '" + key + "' has a line break in its value");
        header += "comment " + key + (value.empty() ? "" : " " + value) + "\n";
    }
    header += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
    header += "property float x\nproperty float y\nproperty float z\n";
    if (withNormals) header += "property float nx\nproperty float ny\nproperty float nz\n";
    header += "element face " + std::to_string(mesh.triangles.size()) + "\n";
    header += "property list uchar uint vertex_indices\nend_header\n";

    const size_t stride = withNormals ? 6 : 3;
    std::vector<float> vertexData(mesh.vertices.size() * stride);
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        float* row = &vertexData[i * stride];
        for (int k = 0; k < 3; ++k) row[k] = mesh.vertices[i][k];
        if (withNormals)
            for (int k = 0; k < 3; ++k) row[3 + k] = mesh.normals[i][k];
    }
    constexpr size_t faceBytes = 1 + 3 * sizeof(uint32_t);
    std::vector<unsigned char> faceData(mesh.triangles.size() * faceBytes);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        unsigned char* p = &faceData[t * faceBytes];
        p[0] = 3;
        std::memcpy(p + 1, mesh.triangles[t].data(), 3 * sizeof(uint32_t));
    }
    writeFileAtomically(path, {{header.data(), header.size()},
                               {vertexData.data(), vertexData.size() * sizeof(float)},
                               {faceData.data(), faceData.size()}});
}

/// What a PLY header says, as far as our reader needs it.
struct PlyHeader {
    bool binaryLE = false;
    std::vector<std::pair<std::string, std::string>> comments;
    struct Element {
        std::string name;
        uint64_t count = 0;
        std::vector<std::vector<std::string>> properties; ///< tokens after "property"
    };
    std::vector<Element> elements;
    size_t dataOffset = 0;
};

/// Parses the header of a PLY file; false when it is not one (then assimp gets to try).
bool readPlyHeader(std::istream& in, PlyHeader& h) {
    std::string line;
    size_t bytes = 0;
    constexpr size_t maxHeaderBytes = 1 << 20;
    bool first = true;
    while (std::getline(in, line)) {
        bytes += line.size() + 1;
        if (bytes > maxHeaderBytes) return false;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (first) {
            if (trim(line) != "ply") return false;
            first = false;
            continue;
        }
        const std::vector<std::string> tok = split(line);
        if (tok.empty()) continue;
        if (tok[0] == "end_header") {
            h.dataOffset = bytes;
            return true;
        }
        if (tok[0] == "comment") {
            const std::string text = trim(line.substr(line.find("comment") + 7));
            if (text.empty()) continue;
            size_t k = 0;
            while (k < text.size() && !isSpace(text[k])) ++k;
            h.comments.emplace_back(text.substr(0, k), trim(text.substr(k)));
        } else if (tok[0] == "format") {
            h.binaryLE = tok.size() >= 2 && tok[1] == "binary_little_endian";
        } else if (tok[0] == "element" && tok.size() == 3) {
            PlyHeader::Element e;
            e.name = tok[1];
            const std::string& n = tok[2];
            auto r = std::from_chars(n.data(), n.data() + n.size(), e.count);
            if (r.ec != std::errc() || r.ptr != n.data() + n.size()) return false;
            h.elements.push_back(std::move(e));
        } else if (tok[0] == "property" && !h.elements.empty()) {
            h.elements.back().properties.emplace_back(tok.begin() + 1, tok.end());
        }
    }
    return false;
}

/// Every element item with properties takes at least one byte (binary) or two characters
/// (ascii), so counts beyond the bytes after the header are a corrupt or truncated file. Checked
/// for every PLY before anything is allocated, by our reader or by assimp's.
void checkPlyCounts(const std::string& path, const PlyHeader& h, std::istream& in) {
    in.seekg(0, std::ios::end);
    const auto end = in.tellg();
    if (end < 0 || !in) fail(path, "cannot determine the file size");
    if (static_cast<uint64_t>(end) < h.dataOffset) fail(path, "truncated (the header ends without a line break)");
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

/// Fast path for the files we write ourselves (and any binary little-endian PLY with float
/// vertex properties and a uchar/uint face list): one read, no assimp scene.
/// False when the file has another layout; throws when it has ours but is broken.
bool readOwnPly(const std::string& path, const PlyHeader& h, std::istream& in, TriangleMesh& mesh) {
    if (!h.binaryLE || h.elements.size() != 2) return false;
    const auto& ve = h.elements[0];
    const auto& fe = h.elements[1];
    if (ve.name != "vertex" || fe.name != "face") return false;
    int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1;
    for (size_t i = 0; i < ve.properties.size(); ++i) {
        const auto& p = ve.properties[i];
        if (p.size() != 2 || (p[0] != "float" && p[0] != "float32")) return false;
        const int k = static_cast<int>(i);
        if (p[1] == "x") ix = k;
        else if (p[1] == "y") iy = k;
        else if (p[1] == "z") iz = k;
        else if (p[1] == "nx") inx = k;
        else if (p[1] == "ny") iny = k;
        else if (p[1] == "nz") inz = k;
    }
    if (ix < 0 || iy < 0 || iz < 0) return false;
    if (fe.properties.size() != 1) return false;
    const auto& fp = fe.properties[0];
    if (fp.size() != 4 || fp[0] != "list" || (fp[1] != "uchar" && fp[1] != "uint8") ||
        (fp[2] != "uint" && fp[2] != "uint32" && fp[2] != "int" && fp[2] != "int32"))
        return false;
    if (!hostIsLittleEndian()) return false;

    in.seekg(0, std::ios::end);
    const auto end = in.tellg();
    if (end < 0 || !in) fail(path, "cannot determine the file size");
    // `end_header` without its line break counts one byte past the end of the file.
    if (static_cast<uint64_t>(end) < h.dataOffset) fail(path, "truncated (the header ends without a line break)");
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
    mesh.vertices.resize(nv);
    if (normals) mesh.normals.resize(nv);
    for (size_t i = 0; i < nv; ++i) {
        const float* r = &rows[i * cols];
        mesh.vertices[i] = Vec3(r[ix], r[iy], r[iz]);
        if (normals) mesh.normals[i] = Vec3(r[inx], r[iny], r[inz]);
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
    writeFileAtomically(path, {{blob->data, blob->size}});
}

TriangleMesh readWithAssimp(const std::string& path) {
    Assimp::Importer importer;
    // Points and lines are dropped; only triangles describe a surface.
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* scene = importer.ReadFile(
        path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                  aiProcess_PreTransformVertices);
    if (!scene) fail(path, std::string("cannot read mesh: ") + importer.GetErrorString());
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
    if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
    PlyHeader header;
    const bool isPly = readPlyHeader(in, header);
    if (isPly) {
        in.clear();
        checkPlyCounts(path, header, in);
        TriangleMesh mesh;
        if (readOwnPly(path, header, in, mesh)) {
            mesh.comments = std::move(header.comments);
            return mesh;
        }
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
