// Tracing the hexagonal lattice of SpikeLattice.hpp.
#include "spikes/SpikeLattice.hpp"
#include "spikes/SurfaceFlow.hpp"

#include "sim/core/Constants.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <unordered_map>

namespace ferro {

namespace {

// The most a curved surface's normal turns from a pattern's origin within the pattern.
constexpr double kMaxTurnDegrees = 75.0;

Vec3d faceNormal(const TriangleMesh& mesh, uint32_t t)
{
    const auto& tri = mesh.triangles[t];
    const Vec3d a = toD(mesh.vertices[tri[0]]), b = toD(mesh.vertices[tri[1]]), c = toD(mesh.vertices[tri[2]]);
    const Vec3d n = (b - a).cross(c - a);
    const double len = n.norm();
    return len > 0 ? Vec3d(n / len) : Vec3d(0, 0, 1);
}

// Lattice axes A_k of the six trace directions in (e1, e2) coordinates, e2 = e1 rotated by 60 deg.
const int kAxis[6][2] = {{1, 0}, {0, 1}, {-1, 1}, {-1, 0}, {0, -1}, {1, -1}};

int64_t latticeKey(int i, int j) { return (int64_t(i) << 32) ^ int64_t(uint32_t(j)); }

// The surface's mean outward normal over a ball: the area-weighted normals of the free
// triangles whose centroids lie within `radius` [m] of a point, weighted (1 - d^2/r^2)^2. The
// trace steps along the tangent plane of this normal instead of the hit triangle's own: on an
// SPH surface mesh a triangle's normal tilts by degrees from one triangle to the next and from
// one frame to the next, and over four rings of steps of l that tilt moved the outer tips of a
// still magnet's pattern by 0.5-1.4 mm per frame (a tenth to a third of l).
class SmoothNormals {
public:
    SmoothNormals(const FreeSurface& surface, double radius) : radius_(radius), grid_({}, radius)
    {
        const TriangleMesh& mesh = surface.mesh;
        std::vector<Vec3d> centroids;
        for (const auto& t : mesh.triangles) {
            if (!surface.isFree(t)) continue;
            const Vec3d a = toD(mesh.vertices[t[0]]), b = toD(mesh.vertices[t[1]]), c = toD(mesh.vertices[t[2]]);
            centroids.push_back((a + b + c) / 3.0);
            areaNormals_.push_back(0.5 * (b - a).cross(c - a));
        }
        grid_ = HashGrid(centroids, radius);
    }
    /// The mean normal around x [m]; `fallback` (unit) where no free triangle is that close.
    Vec3d at(const Vec3d& x, const Vec3d& fallback) const
    {
        Vec3d sum = Vec3d::Zero();
        grid_.forEachWithin(x, radius_, [&](uint32_t i, double d2) {
            const double q = 1.0 - d2 / (radius_ * radius_);
            sum += q * q * areaNormals_[i];
        });
        return sum.norm() > 0 && sum.dot(fallback) > 0 ? Vec3d(sum.normalized()) : fallback;
    }

private:
    double radius_;
    HashGrid grid_;
    std::vector<Vec3d> areaNormals_;
};

// What tracing one pattern needs: the surface, the fields, M_c [A/m] and the pattern's frame
// (origin x0 [m], unit normal n0, unit axes e1 and e1perp = n0 x e1, spacing l [m]).
struct TraceFrame {
    const FreeSurface& surface;
    const SmoothNormals& normals;
    const SurfaceFields& fields;
    double Mc;
    Vec3d x0, n0, e1, e1perp;
    double l;
    double maxTilt;   // [deg] the drop direction's largest angle from n0 (SpikeParams::maxTilt)
    double squareness; // the planform: 0 hexagon, 1 square (SpikePattern::squareness)
    /// A line ends where the surface's normal has turned from n0 by more than the angle of
    /// this cosine (-2: never; SpikeLattice.hpp's curved surfaces).
    double minCosTurn = -2;
    /// The second lattice axis (unit): e1 turned by latticeAngle(squareness) towards e1perp.
    Vec3d e2() const
    {
        if (squareness <= 0) return 0.5 * e1 + 0.8660254037844386 * e1perp;
        if (squareness >= 1) return e1perp;
        const double theta = latticeAngle(squareness);
        return std::cos(theta) * e1 + std::sin(theta) * e1perp;
    }
};

// The tips traced so far; the first tip at lattice coordinates (i, j) wins. With a gap (a
// surface with solids: a coat round a cylinder or a cone), a tip closer than the gap to a tip
// already traced, of this pattern or of an earlier one (`occupy`), is not added: on a closed
// curved surface the lattice's lines meet again round the back, where a flat lattice has no
// such place, and there the first tip wins; where two patterns' lattices meet the seam keeps
// most of a spacing (settleSeams merges what still comes closer than 0.6 l).
struct LatticeTips {
    std::vector<Tip> tips;
    std::unordered_map<int64_t, size_t> index; // latticeKey(i, j) -> tips
    double gap = 0;                            // [m]; 0 = no test
    std::unordered_map<int64_t, std::vector<Vec3d>> occupied; // cells of size gap -> positions

    int64_t cellKey(const Vec3d& x) const
    {
        const int64_t i = int64_t(std::floor(x.x() / gap)), j = int64_t(std::floor(x.y() / gap)),
                      k = int64_t(std::floor(x.z() / gap));
        return (i * 73856093) ^ (j * 19349663) ^ (k * 83492791);
    }
    bool crowded(const Vec3d& x) const
    {
        if (!(gap > 0)) return false;
        for (int a = -1; a <= 1; ++a)
            for (int b = -1; b <= 1; ++b)
                for (int c = -1; c <= 1; ++c) {
                    const auto it = occupied.find(cellKey(x + gap * Vec3d(a, b, c)));
                    if (it == occupied.end()) continue;
                    for (const Vec3d& y : it->second)
                        if ((y - x).squaredNorm() < gap * gap) return true;
                }
        return false;
    }
    void occupy(const Vec3d& x)
    {
        if (gap > 0) occupied[cellKey(x)].push_back(x);
    }
};

void addTip(LatticeTips& lattice, int i, int j, const Vec3d& x, const Vec3d& n)
{
    if (lattice.index.count(latticeKey(i, j)) || lattice.crowded(x)) return;
    lattice.index[latticeKey(i, j)] = lattice.tips.size();
    lattice.tips.push_back({i, j, x, n, Eigen::Matrix<double, 2, 3>::Zero()});
    lattice.occupy(x);
}

bool tipPosition(const LatticeTips& lattice, int i, int j, Vec3d& x)
{
    auto it = lattice.index.find(latticeKey(i, j));
    if (it == lattice.index.end()) return false;
    x = lattice.tips[it->second].position;
    return true;
}

// The field line through x [m] meets the free surface within 0.75 l: the next mapping
// coordinate s [m] and the surface normal n there (the field at x uses the normal n0).
// The line is tilted at most maxTilt from n0, as the spikes are: towards the edge of a
// magnet's pattern the field lies almost in the surface, and a line along it met the surface
// far away or not at all, so from frame to frame a whole ring of tips came and went as the
// surface moved by micrometres. If even the tilted line misses, the line along n0.
bool dropOnSurface(const TraceFrame& f, const Vec3d& x, Vec3d& s, Vec3d& n)
{
    Vec3d H = f.fields.field(x, f.n0);
    if (!(H.norm() > 0)) H = f.n0;
    const Vec3d d = growthDirection(H, f.n0, f.maxTilt);
    if (!nearestFreeHit(f.surface, x, d, 0.75 * f.l, s, n) && !nearestFreeHit(f.surface, x, f.n0, 0.75 * f.l, s, n))
        return false;
    n = f.normals.at(s, n);
    return true;
}

// The art director's irregularity (SpikeParams::jitter, defects): three numbers in [0, 1) per
// tip, a fixed function of the seed, the pattern's magnet and the tip's lattice coordinates
// (splitmix64), so a tip keeps its offset and its fate from frame to frame however the
// pattern moves, and a frame is still made alone.
struct TipNoise {
    double radius, angle, fate;
};
TipNoise tipNoise(uint32_t seed, int magnet, int i, int j)
{
    uint64_t x = (uint64_t(seed) << 32) ^ (uint64_t(uint32_t(magnet)) * 0x9E3779B97F4A7C15ull) ^
                 (uint64_t(uint32_t(i)) << 16) ^ (uint64_t(uint32_t(j)) * 0xC2B2AE3D27D4EB4Full);
    auto next = [&x]() {
        x += 0x9E3779B97F4A7C15ull;
        uint64_t z = x;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        z ^= z >> 31;
        return double(z >> 11) * 0x1.0p-53;
    };
    TipNoise n;
    n.radius = next();
    n.angle = next();
    n.fate = next();
    return n;
}

// Jitter: each tip moved within a disc of radius jitter l in its tangent plane (uniform over
// the disc: radius sqrt(u)), along axes from the pattern's e1 (which comes from a fixed world
// direction), then dropped onto the surface along the field line as the traced tips are. The
// lattice maps are built afterwards from the moved tips, so the profile follows them.
void jitterTips(const TraceFrame& f, LatticeTips& lattice, const SpikeParams& P, int magnet)
{
    if (!(P.jitter > 0)) return;
    for (Tip& tip : lattice.tips) {
        const TipNoise noise = tipNoise(P.seed, magnet, tip.i, tip.j);
        Vec3d t1 = f.e1 - f.e1.dot(tip.normal) * tip.normal;
        if (!(t1.norm() > 1e-9)) continue;
        t1.normalize();
        const Vec3d t2 = tip.normal.cross(t1);
        const double r = P.jitter * f.l * std::sqrt(noise.radius), a = 2 * kPi * noise.angle;
        Vec3d s, n;
        if (dropOnSurface(f, tip.position + r * (std::cos(a) * t1 + std::sin(a) * t2), s, n)) {
            tip.position = s;
            tip.normal = n;
        }
    }
}

// The field's hold on a carried tip at the fluid's |M| (SurfaceFields::holdCurve).
std::function<double(double)> fieldHold(const TraceFrame& f)
{
    const SurfaceFields* fields = &f.fields;
    return [fields](double M) { return fields->holdCurve(M); };
}

// SpikeParams::responseTime, the pattern's part: its anchor rides the fluid's flow and relaxes
// towards the magnet's foot x0 (SurfaceFlowHistory::carriedOffset, d0 from x0, no bound). A
// lattice shifted by whole lattice vectors is the same lattice, so the pattern is traced from
// x0 plus the fraction of d0 within one cell, and its tips' lattice coordinates are counted
// from where the flow took them: (i, j) - the whole cells (di, dj) in d0. So the tips move with the flow as
// far as it carries them, while the pattern still covers the supercritical region around the
// magnet: a magnet sliding faster than tau leaves its tips behind, where they sink, and new
// ones rise ahead. The coordinates stay a tip's own from frame to frame (its jitter, its
// defect, its velocity from the frame before). Returns the whole cells (di, dj) and sets
// `anchor` (the shifted origin on the surface) and `d0`; (0, 0) without a flow.
std::pair<int, int> carriedAnchor(const TraceFrame& f, const SpikeParams& P, int magnet, Vec3d& anchor, Vec3d& d0)
{
    anchor = f.x0;
    d0 = Vec3d::Zero();
    const SpikeInput& in = f.fields.input();
    if (!(P.responseTime > 0) || !in.flow) return {0, 0};
    d0 = in.flow->carriedOffset(f.x0, f.n0, magnet, P.responseTime, in.time, fieldHold(f));
    // d0 in lattice coordinates: d0 = (a e1 + b e2) l along the surface at x0.
    const Vec3d e2 = f.e2();
    const double b = d0.dot(f.e1perp) / (f.l * e2.dot(f.e1perp));
    const double a = (d0.dot(f.e1) - b * f.l * e2.dot(f.e1)) / f.l;
    const int di = int(std::lround(a)), dj = int(std::lround(b));
    const Vec3d fraction = d0 - f.l * (di * f.e1 + dj * e2);
    Vec3d s, n;
    if (!dropOnSurface(f, f.x0 + fraction, s, n)) { // the anchor stays: so does every tip
        d0 = Vec3d::Zero();
        return {0, 0};
    }
    anchor = s;
    return {di, dj};
}

// SpikeParams::responseTime, each tip's own part: where the flow under a tip differs from
// the flow under the anchor (a slosh that stretches or turns the pattern), the tip moves by
// the difference of their carried offsets, at most half a spacing (a tip never strays into
// its neighbour's place), and is dropped onto the surface as the traced tips are. The lattice
// maps are built afterwards from the moved tips, so the profile follows them.
void carryTips(const TraceFrame& f, LatticeTips& lattice, const SpikeParams& P, int magnet, const Vec3d& d0)
{
    const SpikeInput& in = f.fields.input();
    if (!(P.responseTime > 0) || !in.flow) return;
    const std::function<double(double)> hold = fieldHold(f);
    for (Tip& tip : lattice.tips) {
        // The tip's site in the field's lattice is where it stands less the anchor's offset.
        Vec3d d = in.flow->carriedOffset(tip.position - d0, tip.normal, magnet, P.responseTime, in.time, hold) - d0;
        d -= d.dot(tip.normal) * tip.normal;
        if (d.norm() > 0.5 * f.l) d *= 0.5 * f.l / d.norm();
        if (!(d.norm() > 1e-9 * f.l)) continue;
        Vec3d s, n;
        if (dropOnSurface(f, tip.position + d, s, n)) {
            tip.position = s;
            tip.normal = n;
        }
    }
}

// Defects: a tip whose fate (uniform on [0, 1)) lies under d - 0.05 is left out, one between
// d - 0.05 and d is lowered (half height at d - 0.025), so a d raised over keys takes the tips
// away one by one instead of popping them: about d - 0.025 of the tips are gone. d = 0 keeps
// every tip whole.
double tipPresence(const SpikeParams& P, int magnet, int i, int j)
{
    if (!(P.defects > 0)) return 1.0;
    return smoothstep01((tipNoise(P.seed, magnet, i, j).fate - P.defects) / 0.05 + 1.0);
}

// Supercritical at surface point s with normal n: |M| > M_c (with the bifurcation curve's
// hysteresis: spikes stood there, SurfaceFields::spiky).
bool alive(const TraceFrame& f, const Vec3d& s, const Vec3d& n)
{
    return f.fields.spiky(s, f.fields.field(s, n));
}

// One line of tips from the tip at s (unit normal n, supercritical if startAlive, lattice
// coordinates (i, j)) in direction d
// with lattice step (di, dj), along the surface with step l (eq. 15: along the tangent plane of
// the mean normal at the previous tip, SmoothNormals), at most maxRings tips, until two
// subcritical tips in a row after a supercritical one (a subcritical start, the top of a heap
// less magnetized than its flanks, does not end the line). Appends the traced points to
// `points` [m].
void traceLine(const TraceFrame& f, Vec3d s, Vec3d n, bool startAlive, Vec3d d, int i, int j, int di, int dj,
               int maxRings, LatticeTips& lattice, std::vector<Vec3d>* points)
{
    int dead = 0;
    bool lived = startAlive; // a line ends two dead tips after its last live one
    for (int ring = 1; ring <= maxRings && dead < 2; ++ring) {
        d = d - d.dot(n) * n; // eq. 15: step along the tangent plane at the previous tip
        if (!(d.norm() > 1e-12)) break;
        d.normalize();
        Vec3d next, nextNormal;
        if (!dropOnSurface(f, s + f.l * d, next, nextNormal)) break;
        if (nextNormal.dot(f.n0) < f.minCosTurn) break;
        s = next;
        n = nextNormal;
        if (points) points->push_back(s);
        addTip(lattice, i + ring * di, j + ring * dj, s, n);
        const bool live = alive(f, s, n);
        lived = lived || live;
        dead = live ? 0 : lived ? dead + 1 : 0;
    }
}

// Fig. 7b: adds the origin tip and traces the six axes from x0 (traceLine). Returns per axis k
// the traced points, x0 first [m].
void traceAxes(const TraceFrame& f, int maxRings, LatticeTips& lattice, std::vector<Vec3d> (&axisTips)[6])
{
    addTip(lattice, 0, 0, f.x0, f.n0);
    for (int k = 0; k < 6; ++k) {
        const Vec3d d = std::cos(k * kPi / 3) * f.e1 + std::sin(k * kPi / 3) * f.e1perp;
        axisTips[k].push_back(f.x0);
        traceLine(f, f.x0, f.normals.at(f.x0, f.n0), alive(f, f.x0, f.n0), d, 0, 0, kAxis[k][0], kAxis[k][1],
                  maxRings, lattice, &axisTips[k]);
    }
}

// One fill of the tips in rows: an axis traced both ways from x0 along `axis` (lattice step
// (ai, aj)), then from each of its tips up to its last supercritical one a row both ways along
// `row` (step (ri, rj)), every line by traceLine. Rows do not start from the dead tips that end
// the axis: a row from there would never meet a live tip, so nothing would end it before the
// wall. Returns the most tips a line reached.
int fillRows(const TraceFrame& f, int maxRings, LatticeTips& lattice, const Vec3d& axis, int ai, int aj,
             const Vec3d& row, int ri, int rj)
{
    std::vector<Vec3d> line[2] = {{f.x0}, {f.x0}};
    const Vec3d n0 = f.normals.at(f.x0, f.n0);
    const bool live0 = alive(f, f.x0, f.n0);
    traceLine(f, f.x0, n0, live0, axis, 0, 0, ai, aj, maxRings, lattice, &line[0]);
    traceLine(f, f.x0, n0, live0, -axis, 0, 0, -ai, -aj, maxRings, lattice, &line[1]);
    int most = int(std::max(line[0].size(), line[1].size())) - 1;
    for (int side = 0; side < 2; ++side) {
        // The axis's tips before its last live one may be subcritical (the top of a heap).
        std::vector<char> live(line[side].size());
        size_t lastLive = 0;
        for (size_t r = 0; r < line[side].size(); ++r) {
            live[r] = alive(f, line[side][r], f.normals.at(line[side][r], f.n0));
            if (live[r]) lastLive = r;
        }
        const int sign = side == 0 ? 1 : -1;
        for (size_t r = side == 0 ? 0 : 1; r <= lastLive; ++r) { // the origin's rows once
            const Vec3d s = line[side][r], n = f.normals.at(s, f.n0);
            for (const int d : {1, -1}) {
                std::vector<Vec3d> tips;
                traceLine(f, s, n, live[r] != 0, double(d) * row, sign * int(r) * ai, sign * int(r) * aj, d * ri,
                          d * rj, maxRings, lattice, &tips);
                most = std::max(most, int(tips.size()));
            }
        }
    }
    return most;
}

// The tips in rows: rows along e2 from the e1 axis (the square planform's trace: rings around
// x0 would be diamonds, |i| + |j| = r between two axes, that miss the corners of a round
// supercritical region; rows reach every tip the region holds). A lattice whose e2 is not at
// 90 degrees (squareness below 1) or a shot whose hexagons morph (`bothWays`) also gets rows
// along e1 from the e2 axis, the first tip at a site winning: a point at distance R from x0
// has |i| or |j| at most R / l (with e1, e2 unit and at least 60 degrees apart, both larger
// would put it farther), so the two fills together reach every site of a round region, up to
// the fluid's edge, whatever the angle. A still square keeps the single fill it always had.
// Returns the most tips a line reached.
int traceRows(const TraceFrame& f, int maxRings, LatticeTips& lattice, bool bothWays)
{
    addTip(lattice, 0, 0, f.x0, f.n0);
    const Vec3d e2 = f.e2();
    int most = fillRows(f, maxRings, lattice, f.e1, 1, 0, e2, 0, 1);
    if (bothWays || f.squareness < 1) most = std::max(most, fillRows(f, maxRings, lattice, e2, 0, 1, f.e1, 1, 0));
    return most;
}

// Fig. 7c: the tips between axes k and k + 1 on ring r interpolate the two r-th axis tips and
// are dropped onto the surface along the field line. Returns the most rings either axis of a
// pair reached (SpikePattern::rings).
int fillRings(const TraceFrame& f, const std::vector<Vec3d> (&axisTips)[6], LatticeTips& lattice)
{
    int maxRings = 0;
    for (int k = 0; k < 6; ++k) {
        const int k1 = (k + 1) % 6;
        const int rings = int(std::min(axisTips[k].size(), axisTips[k1].size())) - 1;
        maxRings = std::max(maxRings, int(std::max(axisTips[k].size(), axisTips[k1].size())) - 1);
        for (int ring = 2; ring <= rings; ++ring)
            for (int step = 1; step < ring; ++step) {
                const double t = double(step) / ring; // Fig. 7c: between the two n-th axis tips
                const Vec3d x = (1 - t) * axisTips[k][size_t(ring)] + t * axisTips[k1][size_t(ring)];
                Vec3d s, n;
                if (!dropOnSurface(f, x, s, n)) continue;
                addTip(lattice, ring * kAxis[k][0] + step * (kAxis[k1][0] - kAxis[k][0]),
                       ring * kAxis[k][1] + step * (kAxis[k1][1] - kAxis[k][1]), s, n);
            }
    }
    return maxRings;
}

// The tip's lattice map (eq. 13's coordinates): the inverse of the basis [b1 b2 l unit(b1 x b2)]
// with b1, b2 the tip's steps to its (+1, 0) and (0, +1) neighbours (central differences where
// both neighbours exist), top two rows. Returns a 2x3 matrix from an offset [m] to lattice units.
Eigen::Matrix<double, 2, 3> tipLatticeMap(const TraceFrame& f, const LatticeTips& lattice, const Tip& tip)
{
    const double l = f.l;
    const Vec3d e1 = f.e1, n0 = f.n0;
    auto basis = [&](int di, int dj, const Vec3d& flat) {
        Vec3d plus, minus;
        const bool hasPlus = tipPosition(lattice, tip.i + di, tip.j + dj, plus);
        const bool hasMinus = tipPosition(lattice, tip.i - di, tip.j - dj, minus);
        if (hasPlus && hasMinus) return Vec3d(0.5 * (plus - minus));
        if (hasPlus) return Vec3d(plus - tip.position);
        if (hasMinus) return Vec3d(tip.position - minus);
        return Vec3d(l * (flat - flat.dot(tip.normal) * tip.normal).normalized());
    };
    const Vec3d f1 = e1, f2 = f.e2();
    auto frame = [&](const Vec3d& b1, const Vec3d& b2) {
        Eigen::Matrix3d A;
        A.col(0) = b1;
        A.col(1) = b2;
        const Vec3d c = b1.cross(b2);
        A.col(2) = c.norm() > 0 ? Vec3d(c.normalized() * l) : Vec3d::Zero();
        return A;
    };
    // Neighbours that (nearly) line up with the tip give b1 x b2 ~ 0 and no inverse:
    // that tip takes the flat basis projected on its tangent plane, and where even
    // that degenerates (a normal in the pattern's plane), the pattern's own frame.
    const double minDet = 1e-9 * l * l * l;
    Eigen::Matrix3d A = frame(basis(1, 0, f1), basis(0, 1, f2));
    if (!(std::abs(A.determinant()) >= minDet) || !A.allFinite()) {
        auto project = [&](const Vec3d& v) {
            const Vec3d t = v - v.dot(tip.normal) * tip.normal;
            return t.norm() > 1e-12 ? Vec3d(l * t.normalized()) : Vec3d::Zero();
        };
        A = frame(project(f1), project(f2));
    }
    if (!(std::abs(A.determinant()) >= minDet) || !A.allFinite()) {
        A.col(0) = l * f1;
        A.col(1) = l * f2;
        A.col(2) = l * n0;
    }
    return A.inverse().topRows<2>();
}

} // namespace

double spikeAmplitude(const SpikeParams& P, double field, double spacing)
{
    return P.heightGain * std::min(P.beta * field, P.maxAspect * spacing / 3.0);
}

bool nearestFreeHit(const FreeSurface& surface, const Vec3d& p, const Vec3d& d, double maxDistance, Vec3d& hit,
                    Vec3d& normal, bool aheadOnTie)
{
    const std::vector<SurfaceRayCaster::Hit> hits = surface.caster.lineHits(p, d);
    const SurfaceRayCaster::Hit* chosen = nullptr;
    for (const SurfaceRayCaster::Hit& h : hits) {
        if (std::abs(h.t) > maxDistance) break;
        if (!surface.isFree(surface.mesh.triangles[h.triangle])) continue;
        if (!chosen) {
            chosen = &h;
            if (!aheadOnTie) break;
        } else if (std::abs(h.t) > 1.01 * std::abs(chosen->t)) {
            break;
        } else if (h.t > 0 && chosen->t < 0) {
            chosen = &h;
        }
    }
    if (!chosen) return false;
    hit = chosen->point;
    normal = faceNormal(surface.mesh, chosen->triangle);
    return true;
}

void traceLattice(Pattern& pat, const FreeSurface& surface, const SurfaceFields& fields, const SpikeParams& P,
                  double Mc, double diagonal, const std::vector<Pattern>& earlier)
{
    const bool curved = fields.input().fluid.solids != nullptr;
    const double l = pat.info.spacing;
    const Vec3d n0 = pat.info.normal, e1 = pat.info.axis;
    const SmoothNormals normals(surface, 0.5 * l);
    const double squareness = pat.info.squareness;
    const TraceFrame foot{surface, normals, fields, Mc, pat.info.origin, n0, e1, n0.cross(e1), l, P.maxTilt, squareness};
    Vec3d anchor, d0;
    const auto [di, dj] = carriedAnchor(foot, P, pat.info.magnet, anchor, d0);
    pat.info.origin = anchor;
    TraceFrame frame{surface, normals, fields, Mc, anchor, n0, e1, n0.cross(e1), l, P.maxTilt, squareness};
    // On a curved coat a lattice traced along the surface stays one over a patch that turns
    // less than a right angle: beyond, its rows have wound round the solid and meet the rows
    // traced the other way at random offsets (a steel cylinder in a transverse field: the far
    // face's spikes came 0.5 l apart and leaned 25-40 degrees). The rest is left to patterns
    // of its own (addRegionPatterns).
    if (curved) frame.minCosTurn = std::cos(kMaxTurnDegrees * kPi / 180.0);
    LatticeTips lattice;
    if (curved) {
        lattice.gap = 0.8 * l;
        for (const Pattern& other : earlier)
            for (const Tip& tip : other.tips) lattice.occupy(tip.position);
    }
    const int maxRings = int(std::ceil(diagonal / l)) + 1;
    // On a surface with solids the tips are traced in rows (every step a local one along the
    // surface): the rings' interpolation between two axis tips (Fig. 7c) cuts across a coat's
    // curvature, through the solid.
    if (squareness > 0 || P.morphs() || curved) {
        pat.info.rings = traceRows(frame, maxRings, lattice, P.morphs() || curved);
    } else {
        std::vector<Vec3d> axisTips[6];
        traceAxes(frame, maxRings, lattice, axisTips);
        pat.info.rings = fillRings(frame, axisTips, lattice);
    }
    if (di != 0 || dj != 0) { // the tips' own coordinates: the tip traced at (i, j) is the one
        lattice.index.clear(); // the flow carried there from site (i - di, j - dj)
        for (size_t t = 0; t < lattice.tips.size(); ++t) {
            lattice.tips[t].i -= di;
            lattice.tips[t].j -= dj;
            lattice.index[latticeKey(lattice.tips[t].i, lattice.tips[t].j)] = t;
        }
    }
    jitterTips(frame, lattice, P, pat.info.noiseKey());
    carryTips(frame, lattice, P, pat.info.magnet, d0);
    for (Tip& tip : lattice.tips) tip.toLattice = tipLatticeMap(frame, lattice, tip);
    pat.tips = std::move(lattice.tips);
    // Eq. 14 at each tip: C0 = beta |H|, capped so the tip stands at most maxAspect l above
    // the mean level, faded in from M_c, times the art director's gain; the spike grows along
    // the tip's field. Its presence (defects) scales its profile in the displacement instead.
    for (Tip& tip : pat.tips) {
        const Vec3d H = fields.field(tip.position, tip.normal);
        tip.presence = tipPresence(P, pat.info.noiseKey(), tip.i, tip.j);
        tip.amplitude = spikeAmplitude(P, H.norm(), l) * fields.heightFade(tip.position, H);
        tip.direction = growthDirection(H, tip.normal, P.maxTilt);
    }
    std::vector<Vec3d> positions;
    for (const Tip& tip : pat.tips) positions.push_back(tip.position);
    pat.grid = std::make_unique<HashGrid>(positions, l);
}

void settleSeams(std::vector<Pattern>& patterns, const std::vector<Magnet>& magnets)
{
    if (patterns.size() < 2) return;
    // Each tip's share of the field dominance at its own position.
    std::vector<std::vector<double>> share(patterns.size());
    for (size_t p = 0; p < patterns.size(); ++p)
        for (const Tip& tip : patterns[p].tips)
            share[p].push_back(patternDominance(patterns, magnets, tip.position).share(p));
    // A tip's ownership starts from its pattern's share: smoothstep((share - 0.2) / 0.2), so
    // a pattern's lattice where another magnet dominates (share under 0.2) leaves nothing.
    // Then every pair of tips of two patterns closer than 0.6 l merges by
    // m = 1 - smoothstep((d / l - 0.3) / 0.3) (fully from 0.3 l in). Each tip yields by
    // y = smoothstep(0.5 + (other's share - own share) / 0.2): it moves m y of the way to the
    // other tip and keeps 1 - m y of its ownership. The tip of the dominating pattern stays,
    // the other vanishes into it; at a tie both meet at the midpoint with half each, and two
    // half spikes on one point are one spike. Pairs 0.6 l apart or more both stay: closer
    // than the lattice's l, but no hole. Everything is read from the traced tips and written
    // afterwards: the result does not depend on the order of the pairs.
    std::vector<std::vector<double>> merged(patterns.size());
    std::vector<std::vector<Vec3d>> shift(patterns.size());
    for (size_t p = 0; p < patterns.size(); ++p) {
        for (size_t t = 0; t < patterns[p].tips.size(); ++t)
            merged[p].push_back(smoothstep01((share[p][t] - 0.2) / 0.2));
        shift[p].assign(patterns[p].tips.size(), Vec3d::Zero());
    }
    for (size_t p = 0; p < patterns.size(); ++p) {
        for (size_t t = 0; t < patterns[p].tips.size(); ++t) {
            const Tip& tip = patterns[p].tips[t];
            for (size_t q = 0; q < patterns.size(); ++q) {
                if (q == p) continue;
                const double l = std::min(patterns[p].info.spacing, patterns[q].info.spacing);
                patterns[q].grid->forEachWithin(tip.position, 0.6 * l, [&](uint32_t u, double d2) {
                    if (!(share[q][u] > 0.2)) return;   // an owned tip only
                    const double m = 1.0 - smoothstep01((std::sqrt(d2) / l - 0.3) / 0.3);
                    const double yields = smoothstep01(0.5 + (share[q][u] - share[p][t]) / 0.2);
                    merged[p][t] *= 1.0 - m * yields;
                    shift[p][t] += m * yields * (patterns[q].tips[u].position - tip.position);
                });
            }
        }
    }
    for (size_t p = 0; p < patterns.size(); ++p) {
        std::vector<Vec3d> positions;
        for (size_t t = 0; t < patterns[p].tips.size(); ++t) {
            Tip& tip = patterns[p].tips[t];
            tip.ownership = merged[p][t];
            tip.position += shift[p][t];
            positions.push_back(tip.position);
        }
        patterns[p].grid = std::make_unique<HashGrid>(positions, patterns[p].info.spacing);
    }
}

Dominance patternDominance(const std::vector<Pattern>& patterns, const std::vector<Magnet>& magnets, const Vec3d& x)
{
    Dominance d;
    d.dominance.resize(patterns.size());
    std::vector<char> counted(magnets.size(), 0);
    for (size_t p = 0; p < patterns.size(); ++p) {
        const size_t m = size_t(patterns[p].info.magnet);
        d.dominance[p] = fieldDominance(magnetField(magnets[m], x));
        // One magnet's patterns (SpikePattern::region) lie apart and do not compete: the
        // magnet counts once in the sum, and each of them has its whole share.
        if (!counted[m]) d.sum += d.dominance[p];
        counted[m] = 1;
    }
    return d;
}

} // namespace ferro
