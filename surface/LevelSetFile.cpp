// The level set's .vdb file of OpenVdbSurface.hpp.
#include "surface/OpenVdbSurface.hpp"

#include "sim/core/AtomicFile.hpp"
#include "sim/core/MeshFormats.hpp"

#include <openvdb/tools/MeshToVolume.h>

namespace ferro {

using openvdb::FloatGrid;

void writeLevelSet(const std::string& path, const TriangleMesh& mesh, double voxelSize,
                   const std::function<std::vector<Vec3>(const std::vector<Vec3>&)>& velocity) {
    initOpenVdb();
    auto xform = openvdb::math::Transform::createLinearTransform(voxelSize);
    std::vector<openvdb::Vec3s> points(mesh.vertices.size());
    for (size_t i = 0; i < points.size(); ++i)
        points[i] = openvdb::Vec3s(mesh.vertices[i].x(), mesh.vertices[i].y(), mesh.vertices[i].z());
    std::vector<openvdb::Vec3I> tris(mesh.triangles.size());
    for (size_t t = 0; t < tris.size(); ++t)
        tris[t] = openvdb::Vec3I(mesh.triangles[t][0], mesh.triangles[t][1], mesh.triangles[t][2]);
    FloatGrid::Ptr sdf = openvdb::tools::meshToLevelSet<FloatGrid>(*xform, points, tris, 3.0f);
    sdf->setName("surface");
    sdf->setGridClass(openvdb::GRID_LEVEL_SET);
    openvdb::GridPtrVec grids{sdf};
    if (velocity) {
        // The velocity at every active voxel of the band, in the band's own topology.
        std::vector<openvdb::Coord> coords;
        coords.reserve(size_t(sdf->activeVoxelCount()));
        for (auto it = sdf->cbeginValueOn(); it; ++it) coords.push_back(it.getCoord());
        std::vector<Vec3> centres(coords.size());
        for (size_t i = 0; i < coords.size(); ++i) {
            const openvdb::Vec3d w = xform->indexToWorld(coords[i]);
            centres[i] = Vec3(Real(w.x()), Real(w.y()), Real(w.z()));
        }
        const std::vector<Vec3> v = velocity(centres);
        openvdb::Vec3fGrid::Ptr vg = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
        vg->setTransform(xform->copy());
        vg->setName("v");
        vg->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
        auto acc = vg->getAccessor();
        for (size_t i = 0; i < coords.size(); ++i) acc.setValue(coords[i], openvdb::Vec3f(v[i].x(), v[i].y(), v[i].z()));
        grids.push_back(vg);
    }
    try {
        writeFileAtomicallyByPath(path, [&](const std::string& tmp) {
            try {
                openvdb::io::File file(tmp);
                file.write(grids);
                file.close();
            } catch (const std::exception& e) {
                throw MeshFileError(path + ": cannot write the level set: " + e.what(), kExitIoError);
            }
        });
    } catch (const AtomicFileError&) {
        throw MeshFileError(path + ": cannot rename the temporary file", kExitIoError);
    }
}

} // namespace ferro
