#pragma once
// Particles as OpenVDB's ParticlesToLevelSet wants them (positions and one radius). Includes
// OpenVDB: only for .cpp files that already do (SurfaceExtractor.cpp, bench-surface).
#include "sim/core/Types.hpp"

#include <openvdb/openvdb.h>

#include <vector>

namespace ferro {

/// OpenVDB's own particle rasterizer wants this interface.
struct ParticleList {
    using PosType = openvdb::Vec3R;
    const std::vector<Vec3>& x;
    double radius;
    size_t size() const { return x.size(); }
    void getPos(size_t n, openvdb::Vec3R& p) const { p = openvdb::Vec3R(x[n].x(), x[n].y(), x[n].z()); }
    void getPosRad(size_t n, openvdb::Vec3R& p, openvdb::Real& r) const {
        getPos(n, p);
        r = radius;
    }
};

} // namespace ferro
