#include "sim/sph/FluidSeed.hpp"
#include "sim/sph/MagnetObstacles.hpp"
#include "sim/magnets/MagnetKinds.hpp"

#include "sim/core/MachineMemory.hpp"
#include "sim/core/Constants.hpp"
#include "sim/core/SceneDocument.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

namespace ferro {

namespace {

std::string fmtVec(const Vec3d& p) {
    std::ostringstream s;
    s.precision(5);
    s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
    return s.str();
}

/// Lattice points of a block at spacing s, offset s/2 from its faces.
void latticeOfBlock(const FluidBlock& b, double s, std::vector<Vec3d>& out) {
    out.clear();
    Vec3d lo, hi;
    if (b.shape == FluidBlock::Shape::Box) {
        lo = b.min;
        hi = b.max;
    } else {
        lo = b.center - Vec3d(b.radius, b.radius, 0);
        hi = b.center + Vec3d(b.radius, b.radius, b.height);
    }
    int n[3];
    for (int a = 0; a < 3; ++a) n[a] = std::max(0, int(std::floor((hi[a] - lo[a]) / s + 1e-9)));
    // Centre the lattice in the block so the leftover gap is split on both sides.
    Vec3d start;
    for (int a = 0; a < 3; ++a) start[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * (n[a] - 1) * s;
    const double r2 = (b.radius - 0.5 * s) * (b.radius - 0.5 * s);
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
                const Vec3d p = start + s * Vec3d(i, j, k);
                if (b.shape == FluidBlock::Shape::Cylinder) {
                    const double dx = p.x() - b.center.x(), dy = p.y() - b.center.y();
                    if (dx * dx + dy * dy > r2) continue;
                }
                out.push_back(p);
            }
}

double blockVolume(const FluidBlock& b) {
    if (b.shape == FluidBlock::Shape::Box) return (b.max - b.min).prod();
    return kPi * b.radius * b.radius * b.height;
}

} // namespace

RunSize estimateRunSize(const SimScene& scene) {
    RunSize size;
    const auto& blocks = scene.fluid.blocks;
    double s = scene.fluid.spacing;
    if (!(s > 0))
        for (size_t bi = 0; bi < blocks.size(); ++bi)
            if (blocks[bi].count > 0) {
                s = std::cbrt(blockVolume(blocks[bi]) / double(blocks[bi].count));
                size.key = "fluid.block[" + std::to_string(bi) + "].count";
                break;
            }
    if (!(s > 0)) return size;
    if (size.key.empty()) size.key = "fluid.spacing";
    size.spacing = s;
    for (const FluidBlock& b : blocks) size.fluidParticles += b.count > 0 ? double(b.count) : blockVolume(b) / (s * s * s);
    // Walls sampled at the spacing: their area over s^2 (a mesh's safety box stands in for
    // its area, an overestimate of about the right size).
    const ContainerParams& c = scene.container;
    double area = 0;
    switch (c.type) {
    case ContainerParams::Type::None: break;
    case ContainerParams::Type::Dish: area = kPi * c.radius * c.radius + 2 * kPi * c.radius * c.height; break;
    case ContainerParams::Type::Box: {
        // The floor, a lid if closed, the sides unless they are periodic (no walls).
        const Vec3d e = c.max - c.min;
        area = (c.closedTop ? 2 : 1) * e.x() * e.y() + (c.periodicSides ? 0 : 2 * (e.y() * e.z() + e.z() * e.x()));
        break;
    }
    case ContainerParams::Type::Mesh:
        if (c.hasBounds) {
            const Vec3d e = c.boundsMax - c.boundsMin;
            area = 2 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
        }
        break;
    }
    size.boundaryParticles = area / (s * s);
    size.bytes = size.fluidParticles * RunSize::kBytesPerFluidParticle +
                 size.boundaryParticles * RunSize::kBytesPerBoundaryParticle;
    return size;
}

void checkRunSize(const SimScene& scene) {
    const RunSize size = estimateRunSize(scene);
    const double available = availableMemoryBytes();
    if (!(size.bytes > 0) || !(available > 0) || size.bytes <= available) return;
    std::ostringstream msg;
    msg.precision(3);
    msg << scene.path << ": " << size.key << ": the run needs about " << formatBytes(size.bytes) << " ("
        << size.fluidParticles << " fluid and " << size.boundaryParticles << " boundary particles at spacing "
        << size.spacing << " m), more than the " << formatBytes(available) << " this machine has available";
    throw SceneError(msg.str());
}

std::vector<SolidWall> solidWalls(const SimScene& scene) {
    std::vector<SolidWall> walls;
    for (const SolidParams& s : scene.solids) {
        const double edge = s.panelSize > 0 ? s.panelSize
                          : scene.fluid.spacing > 0 ? 2 * scene.fluid.spacing : s.radius / 8;
        const SolidSurface surface = solidSurfaceAt(s, solidShape(s, edge, scene.path), 0.0);
        walls.push_back({surface.vertices, surface.triangles});
    }
    return walls;
}

void checkSolids(const SimScene& scene, const std::vector<SolidWall>& walls) {
    if (walls.empty()) return;
    const std::unique_ptr<Container> vessel = makeContainer(scene.container, scene.path);
    for (size_t k = 0; k < walls.size(); ++k) {
        const std::string key = scene.path + ": solids[" + std::to_string(k) + "]";
        const SolidWall& w = walls[k];
        // Inside the vessel (a sculpture) or outside it (a core under the dish), not across
        // its wall: vertices on the wall itself (a base on the floor) count as either.
        size_t in = 0, out = 0;
        for (const Vec3d& v : w.vertices) {
            if (vessel->contains(v, 1e-9)) ++in;
            else if (!vessel->contains(v, -1e-6)) ++out;
        }
        if (in > 0 && out > 0)
            throw SceneError(key + ": the solid crosses the container's wall (" + std::to_string(in) + " of its " +
                             std::to_string(w.vertices.size()) + " vertices inside, " + std::to_string(out) +
                             " outside): move it into the vessel or out of it");
        // No magnet's body inside the solid.
        const std::unique_ptr<Container> solid = makeContainerWithSolids(ContainerParams{}, {w}, scene.path);
        for (size_t m = 0; m < scene.magnets.size(); ++m) {
            const Magnet mag = scene.magnets[m].at(0.0);
            const MagnetKindInfo& info = magnetKindInfo(mag.kind);
            if (!info.positioned) continue;
            std::vector<Vec3d> body{mag.position};
            const Vec3d axis = mag.direction.norm() > 0 ? Vec3d(mag.direction.normalized()) : Vec3d::UnitZ();
            if (info.usesLength && !info.usesRadius) {
                body.push_back(mag.position + 0.5 * mag.length * axis);
                body.push_back(mag.position - 0.5 * mag.length * axis);
            }
            if (info.usesRadius) { // a loop's wire, a coil's winding: points round it
                body.clear();
                const Vec3d u = axis.unitOrthogonal(), v = axis.cross(u);
                const int rows = info.usesLength ? 5 : 1;
                for (int r = 0; r < rows; ++r)
                    for (int a = 0; a < 24; ++a) {
                        const double phi = 2 * kPi * a / 24;
                        const double z = rows > 1 ? mag.length * (double(r) / (rows - 1) - 0.5) : 0.0;
                        body.push_back(mag.position + z * axis + mag.radius * (std::cos(phi) * u + std::sin(phi) * v));
                    }
            }
            for (const Vec3d& p : body)
                if (!solid->contains(p, 0))
                    throw SceneError(key + ": magnets[" + std::to_string(m) + "] (" + info.name +
                                     ") lies inside the solid: a magnet and a solid cannot share space; move one of them");
        }
        // Some magnet must reach it: the strongest applied field at its vertices over the shot
        // (a sample a frame, at most 256) of at least 1 A/m (the Earth's field is ~40 A/m).
        double strongest = 0;
        const int frames = std::clamp(scene.shot.frameCount(), 1, 256);
        for (int f = 0; f <= frames && !scene.magnets.empty(); ++f) {
            const double t = scene.shot.duration * f / frames;
            std::vector<Magnet> mags;
            for (const MagnetTrack& tr : scene.magnets) mags.push_back(tr.at(t));
            for (size_t v = 0; v < w.vertices.size(); v += std::max<size_t>(1, w.vertices.size() / 64))
                strongest = std::max(strongest, magnetField(mags, w.vertices[v]).norm());
        }
        if (!(strongest >= 1.0))
            throw SceneError(key + ": no magnet reaches the solid (" +
                             (scene.magnets.empty() ? std::string("the scene has no [[magnets]]")
                                                    : "the strongest field at it over the shot is " + formatNumber(strongest) + " A/m") +
                             "): an unmagnetized solid is only a wall; add a magnet or use a mesh container");
    }
}

FluidSeed seedFluid(const SimScene& scene, const Container& container, const std::vector<SolidWall>& walls) {
    // Before anything is allocated: a typo in a count or spacing must not run for a minute
    // and end in std::bad_alloc.
    checkRunSize(scene);
    FluidSeed seed;
    const auto& blocks = scene.fluid.blocks;
    seed.spacing = scene.fluid.spacing;
    std::vector<Vec3d> pts;
    // A magnet is a solid (MagnetObstacles.hpp): a block is filled around the magnets'
    // bodies at the start, each point at least half a spacing off a body, as the step's
    // constraint keeps it; the count is the fluid's (a magnet placed in a dish of a given
    // amount of fluid raises its level), so the spacing is found around the bodies too.
    size_t displaced = 0;      // lattice points the bodies took in the last fill
    bool displacedAny = false; // ... in any fill (the bisection's too)
    // The solids displace the fluid too: a block is filled around them, at least a quarter
    // spacing off their walls, where the first layer of fluid at a wall sampled on its surface sits.
    std::unique_ptr<Container> solids;
    if (!walls.empty()) solids = makeContainerWithSolids(ContainerParams{}, walls, scene.path);
    auto fill = [&](const FluidBlock& b, double spacing) {
        latticeOfBlock(b, spacing, pts);
        if (solids)
            pts.erase(std::remove_if(pts.begin(), pts.end(), [&](const Vec3d& p) { return !solids->contains(p, 0.5 * spacing); }),
                      pts.end());
        if (scene.magnets.empty()) return;
        const std::vector<MagnetObstacle> bodies = magnetObstacles(scene.magnets, 0.0, 0.0, 0.5 * spacing, 0.0);
        if (bodies.empty()) return;
        const size_t before = pts.size();
        pts.erase(std::remove_if(pts.begin(), pts.end(),
                                 [&](const Vec3d& p) {
                                     for (const MagnetObstacle& o : bodies)
                                         if (isInside(o, p)) return true;
                                     return false;
                                 }),
                  pts.end());
        displaced = before - pts.size();
        displacedAny = displacedAny || displaced > 0;
    };
    if (seed.spacing <= 0) {
        // Derive the spacing from the first block with a count: the largest spacing
        // whose lattice still holds that many particles (found by bisection).
        const FluidBlock* first = nullptr;
        for (const auto& b : blocks)
            if (b.count > 0) { first = &b; break; }
        if (!first) throw SceneError(scene.path + ": fluid.spacing: set a spacing or a block count");
        const double guess = std::cbrt(blockVolume(*first) / double(first->count));
        double lo = 0.5 * guess, hi = 1.5 * guess;
        for (int it = 0; it < 60; ++it) {
            const double mid = 0.5 * (lo + hi);
            fill(*first, mid);
            (long(pts.size()) >= first->count ? lo : hi) = mid;
        }
        seed.spacing = lo;
    }
    const double s = seed.spacing;
    for (size_t bi = 0; bi < blocks.size(); ++bi) {
        const FluidBlock& b = blocks[bi];
        const std::string key = "fluid.block[" + std::to_string(bi) + "]";
        fill(b, s);
        if (displacedAny && (pts.empty() || (b.count > 0 && long(pts.size()) < b.count))) {
            // The magnets' bodies took the fluid's place: name the one that took most.
            latticeOfBlock(b, s, pts);
            const std::vector<MagnetObstacle> bodies = magnetObstacles(scene.magnets, 0.0, 0.0, 0.5 * s, 0.0);
            size_t worst = size_t(-1), most = 0, k = 0;
            for (size_t m = 0; m < scene.magnets.size(); ++m) {
                const Magnet mag = scene.magnets[m].at(0.0);
                if (!(magnetBodyRadius(mag.kind, mag.strength) > 0)) continue;
                if (worst == size_t(-1)) worst = m;
                const size_t in = size_t(std::count_if(pts.begin(), pts.end(), [&](const Vec3d& p) { return isInside(bodies[k], p); }));
                if (in > most) { most = in; worst = m; }
                ++k;
            }
            const Magnet mag = scene.magnets[worst].at(0.0);
            std::ostringstream msg;
            msg.precision(3);
            msg << b.where << ": magnets[" << worst << "]: the magnet's body (" << magnetKindInfo(mag.kind).name
                << ", the smallest NdFeB body that carries it: radius " << magnetBodyRadius(mag.kind, mag.strength)
                << " m) takes the place of " << key << "'s fluid";
            if (most > 0) msg << " (" << most << " of its " << pts.size() << " lattice points)";
            msg << (b.count > 0 ? ": the rest cannot hold its count" : "")
                << "; magnets are solid: move the magnet out of the fluid or weaken it";
            throw SceneError(msg.str());
        }
        if (b.count > 0) {
            if (long(pts.size()) < b.count)
                throw SceneError(b.where + ": " + key + ".count: the block holds only " +
                                 std::to_string(pts.size()) + " particles at spacing " +
                                 std::to_string(s) + " m (asked " + std::to_string(b.count) + ")");
            // Keep the lowest particles: the trimmed layer is the free surface.
            std::stable_sort(pts.begin(), pts.end(), [](const Vec3d& a, const Vec3d& c) { return a.z() < c.z(); });
            pts.resize(size_t(b.count));
        }
        if (pts.empty())
            throw SceneError(b.where + ": " + key + ": block is smaller than one particle spacing");
        for (const Vec3d& p : pts) {
            if (!container.contains(p, 0.25 * s))
                throw SceneError(b.where + ": " + key + ": fluid outside the container (particle at " +
                                 fmtVec(p) + ")");
            seed.positions.push_back(p.cast<Real>());
            seed.velocities.push_back(b.velocity.cast<Real>());
        }
    }
    if (seed.positions.size() >= (size_t(1) << 32) - 1) throw SceneError(scene.path + ": too many particles");
    return seed;
}

} // namespace ferro
