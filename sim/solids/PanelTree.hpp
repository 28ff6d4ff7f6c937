#pragma once
// A Barnes-Hut tree over the solids' panels for the charge's field and Jacobian at many
// points (the particles, every step): the far panels of a cell are one multipole expansion
// about its centre instead of a sum over each.
//
// Contract. build() takes the panels: centroid, radius (largest corner distance), the second
// moment of a unit charge spread over the panel about its centroid (its 3-point rule's, which
// is the triangle's), and two reaches: `expandReach`, nearer than which a panel must not be
// part of an expansion (the caller evaluates it in closed form), and `pointReach`, beyond
// which a leaf's panel is a point charge. setCharges() takes q_j = sigma_j A_j [A m]. Then
// evaluate(x) adds, without the 1/(4 pi), the field sum q r / |r|^3 and its Jacobian of every
// panel the tree answers for, and lists the rest (nearer than pointReach in a leaf opened).
//   - A cell is expanded (charge, dipole and second moment about its box centre, the panels'
//     own second moments included: a quadrupole of the charge as spread, not of points)
//     when three things hold, else it is opened: its extent R (centroid distance plus panel
//     radius) is under `openingAngle` times the distance d to x; no panel in it is within
//     its expandReach (d - R >= the largest); and the expansion's error bound, the cell's
//     absolute charge |q| R^3 / (d - R)^5, is under `tolerance` (an absolute field, the
//     caller's scale). The last matters: a magnetized body's charges are large and of both
//     signs, so far cells' fields cancel, and a purely geometric criterion (the opening
//     angle alone) does not bound the error relative to the total field
//     (docs/physics/magnetics.md, "Magnetizable solids"). Because a cell carries its
//     panels' spread, it may stand much nearer than a point charge could (two panel radii
//     against six): the panels between, which the sum over every panel evaluates by a
//     3-point rule each, are mostly inside expansions.
// Units: SI; double precision.
#include "sim/core/Types.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace ferro {

class PanelTree {
public:
    /// Panels a leaf holds at most.
    static constexpr int kLeafSize = 12;

    /// The tree over the panels (see the contract above; lengths [m], `second` per panel the
    /// xx yy zz xy xz yz moments [m^2] of a unit charge about its centroid). Clears the charges.
    struct Panel {
        Vec3d centroid = Vec3d::Zero();
        double radius = 0, expandReach = 0, pointReach = 0;
        double second[6] = {0, 0, 0, 0, 0, 0};
    };
    void build(const std::vector<Panel>& panels);
    /// The panels' charges q_j [A m] (one per centroid of build()); sets every cell's moments.
    void setCharges(const std::vector<double>& q);
    bool empty() const { return cells_.empty(); }

    /// Adds to h and g the point-charge field sum q r / |r|^3 and its Jacobian (no 1/(4 pi))
    /// of every panel beyond its reach from x, and appends the others' indices to `near`.
    /// No cell is expanded whose extent comes within `minGap` [m] of x: a panel whose surface
    /// is that near is in an opened leaf (listed, unless beyond its pointReach).
    void evaluate(const Vec3d& x, double openingAngle, double tolerance, double minGap, Eigen::Vector3d& h,
                  Eigen::Matrix3d& g, std::vector<uint32_t>& near) const;

private:
    struct Cell {
        Vec3d center = Vec3d::Zero();
        double radius = 0;      // largest |c_j - center| + radius_j over its panels
        double reach = 0;       // largest expandReach over its panels
        uint32_t begin = 0, end = 0; // its panels: order_[begin, end)
        int32_t child[2] = {-1, -1};
        double q = 0;                      // total charge
        double absQ = 0;                   // sum |q|: the error bound's scale
        Vec3d dipole = Vec3d::Zero();      // sum q s, s = c_j - center
        double second[6] = {0, 0, 0, 0, 0, 0}; // sum q s_a s_b: xx yy zz xy xz yz
    };
    int32_t buildCell(uint32_t begin, uint32_t end);

    std::vector<Cell> cells_;
    std::vector<uint32_t> order_;   // panel indices in tree order
    std::vector<Panel> panel_;      // in tree order
    std::vector<Vec3d> centroid_;   // in tree order
    std::vector<double> reach2_;    // pointReach^2, in tree order
    std::vector<double> q_;         // in tree order
};

} // namespace ferro
