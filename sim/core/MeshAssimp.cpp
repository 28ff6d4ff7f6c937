// Mesh files through assimp: every format but our PLY (see MeshFormats.hpp).
#include "sim/core/MeshFormats.hpp"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <memory>

namespace ferro {
namespace mesh_detail {

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

} // namespace mesh_detail
} // namespace ferro
