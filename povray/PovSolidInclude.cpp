// The solids of a frame ([[solids]] at the frame's pose) appended to magnets_NNNN.inc: one
// mesh2 each, flat-shaded (their rims and tips are creases a smoothed normal would round).
#include "povray/PovText.hpp"

#include <sstream>

namespace ferro {

std::vector<ShapeMesh> solidRenderShapes(const std::vector<SolidParams>& solids, const std::string& where)
{
    // Finer than the simulation's panels: a twelfth of the radius (a generated shape; a mesh
    // file keeps its own triangles).
    std::vector<ShapeMesh> shapes;
    for (const SolidParams& s : solids) {
        const double size = s.shape == SolidParams::Shape::Sphere ? s.radius : std::min(s.radius, s.height);
        shapes.push_back(solidShape(s, size > 0 ? size / 12 : 1.0, where));
    }
    return shapes;
}

std::string solidInclude(const std::vector<SolidParams>& solids, const std::vector<ShapeMesh>& shapes, double time)
{
    std::ostringstream out;
    out << "// The magnetizable solids ([[solids]]) at t = " << number(time)
        << " s: FerroSolidCount and, if > 0, FerroSolids (a union of one mesh2 each).\n";
    out << "#declare FerroSolidCount = " << solids.size() << ";\n";
    if (solids.empty())
        return out.str();
    out << "#declare FerroSolids = union {\n";
    for (size_t k = 0; k < solids.size(); ++k) {
        const SolidSurface s = solidSurfaceAt(solids[k], shapes[k], time);
        out << " mesh2 {\n  vertex_vectors { " << s.vertices.size();
        for (const Vec3d& v : s.vertices) out << ", " << vec(toPovPoint(v), 4);
        out << " }\n  face_indices { " << s.triangles.size();
        for (const auto& t : s.triangles) out << ", <" << t[0] << ", " << t[1] << ", " << t[2] << ">";
        out << " }\n }\n";
    }
    // A union of one object is still a union: POV-Ray accepts it.
    out << "}\n";
    return out.str();
}

} // namespace ferro
