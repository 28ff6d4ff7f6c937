// Our binary PLY: the writer, and a reader for its layout with the count and list checks that
// keep a corrupt file from reaching assimp (see MeshFormats.hpp).
#include "sim/core/MeshFormats.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

namespace ferro {
namespace mesh_detail {

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

} // namespace mesh_detail
} // namespace ferro
