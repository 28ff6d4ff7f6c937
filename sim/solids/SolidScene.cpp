#include "sim/solids/SolidParams.hpp"

#include "sim/core/SceneDocument.hpp"
#include "sim/core/TriangleMesh.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace ferro {

namespace {

// The magnets' track interpolates a position and an axis; a solid's pose is the same.
MagnetTrack poseTrack(const SolidParams& s) {
    MagnetTrack t;
    t.base.position = s.position;
    t.base.direction = s.axis;
    for (const SolidKeyframe& k : s.keys) {
        MagnetKeyframe m;
        m.time = k.time;
        m.position = k.position;
        m.direction = k.axis;
        t.keys.push_back(m);
    }
    return t;
}

SolidParams parseSolid(const TableReader& r, const SceneDocument& doc) {
    SolidParams s;
    const std::string shape = r.choice("shape", {"sphere", "cylinder", "cone", "mesh"}, "cylinder");
    s.shape = shape == "sphere" ? SolidParams::Shape::Sphere
            : shape == "cylinder" ? SolidParams::Shape::Cylinder
            : shape == "cone" ? SolidParams::Shape::Cone : SolidParams::Shape::Mesh;
    if (s.shape == SolidParams::Shape::Mesh) {
        s.meshFile = r.path("file");
        s.meshScale = r.positive("scale", 1.0);
    } else {
        s.radius = r.positive("radius");
        if (s.shape != SolidParams::Shape::Sphere) s.height = r.positive("height");
        if (s.shape == SolidParams::Shape::Cone) {
            s.tipRadius = r.nonNegative("tip_radius", 0.0);
            if (!(s.tipRadius < s.radius))
                r.fail("tip_radius", "must be smaller than radius (got " + formatNumber(s.tipRadius) + ")");
        }
    }
    s.permeability = r.number("permeability", s.permeability);
    if (!(s.permeability > 1 && s.permeability <= 1e5))
        r.fail("permeability", "must be > 1 and <= 1e5 (relative permeability mu_r; soft iron 1000-5000; got " +
                                   formatNumber(s.permeability) + ")");
    s.saturation = r.nonNegative("saturation", s.saturation);
    s.panelSize = r.nonNegative("panel_size", s.panelSize);
    s.position = r.vec3("position", s.position);
    s.axis = r.unitVector("axis", s.axis);
    for (const TableReader& k : r.keyframes("keys", "solids.keys")) {
        SolidKeyframe key;
        key.time = k.nonNegative("time", 0.0);
        key.position = k.vec3("position", s.position);
        key.axis = k.unitVector("axis", s.axis);
        k.finish();
        s.keys.push_back(key);
    }
    r.finish();
    (void)doc;
    return s;
}

} // namespace

SolidKeyframe SolidParams::at(double t) const {
    const Magnet m = poseTrack(*this).at(t);
    SolidKeyframe k;
    k.time = t;
    k.position = m.position;
    const double n = m.direction.norm();
    k.axis = n > 0 ? Vec3d(m.direction / n) : Vec3d::UnitZ();
    return k;
}

bool SolidParams::moves() const {
    for (const SolidKeyframe& k : keys)
        if (k.position != position || k.axis != axis) return true;
    return false;
}

ShapeMesh solidShape(const SolidParams& solid, double edge, const std::string& where) {
    ShapeMesh m;
    switch (solid.shape) {
    case SolidParams::Shape::Sphere: return makeSphere(solid.radius, edge);
    case SolidParams::Shape::Cylinder: return makeCylinder(solid.radius, solid.height, edge);
    case SolidParams::Shape::Cone: return makeCone(solid.radius, solid.tipRadius, solid.height, edge);
    case SolidParams::Shape::Mesh: break;
    }
    const std::string ctx = where + ": solids.file: '" + solid.meshFile + "': ";
    TriangleMesh file;
    try {
        file = readMesh(solid.meshFile);
    } catch (const MeshFileError& e) {
        throw SceneError(ctx + "cannot load: " + e.what());
    }
    for (const Vec3& v : file.vertices) {
        const Vec3d q = solid.meshScale * v.cast<double>();
        if (!q.allFinite()) throw SceneError(ctx + "non-finite vertex coordinates");
        m.vertices.push_back(q);
    }
    m.triangles = file.triangles;
    weldVertices(m);
    if (m.triangles.empty()) throw SceneError(ctx + "mesh has no triangles");
    const ClosedCheck c = checkClosed(m);
    if (c.openEdges > 0 || c.crowdedEdges > 0)
        throw SceneError(ctx + "mesh is not closed (" + std::to_string(c.openEdges) + " boundary edges, " +
                         std::to_string(c.crowdedEdges) + " edges shared by more than two triangles): a solid needs a closed surface");
    if (c.flippedEdges > 0)
        throw SceneError(ctx + "mesh is not consistently oriented (" + std::to_string(c.flippedEdges) +
                         " edges run the same way in both their triangles)");
    if (!(signedVolume(m) > 0))
        throw SceneError(ctx + "mesh is inside out (its triangles face inward; flip their winding)");
    return m;
}

SolidSurface solidSurfaceAt(const SolidParams& solid, const ShapeMesh& shape, double t) {
    const SolidKeyframe pose = solid.at(t);
    const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Vec3d::UnitZ(), pose.axis);
    SolidSurface s;
    s.vertices.reserve(shape.vertices.size());
    for (const Vec3d& v : shape.vertices) s.vertices.push_back(pose.position + q * v);
    s.triangles = shape.triangles;
    s.permeability = solid.permeability;
    s.saturation = solid.saturation;
    return s;
}

std::vector<SolidParams> parseSolids(const SceneDocument& doc) {
    std::vector<SolidParams> out;
    for (const TableReader& r : TableReader(doc, doc.root(), "").tables("solids")) out.push_back(parseSolid(r, doc));
    return out;
}

} // namespace ferro
