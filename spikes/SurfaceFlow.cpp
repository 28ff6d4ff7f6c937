// The flow history of SurfaceFlow.hpp: earlier frames' particles and the tips they carry.
#include "spikes/SurfaceFlow.hpp"

#include "sim/core/ParticleFile.hpp"
#include "sim/magnets/MagnetState.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

namespace ferro {

namespace {

bool fileExists(const std::string& path)
{
    std::ifstream f(path);
    return f.good();
}

// The sample of one particle file; false when it has no velocity columns (such a file ends
// the history: the flow before it is unknown).
bool readSample(const std::string& path, double fallbackTime, FlowSample& s)
{
    const ParticleTable table = readParticleFile(path);
    if (table.column("vx") < 0 || table.column("vy") < 0 || table.column("vz") < 0) return false;
    const std::vector<Vec3> x = table.vec3("x", "y", "z"), v = table.vec3("vx", "vy", "vz");
    if (table.column("mx") >= 0 && table.column("my") >= 0 && table.column("mz") >= 0) {
        const std::vector<Vec3> m = table.vec3("mx", "my", "mz");
        s.magnetization.reserve(m.size());
        for (size_t i = 0; i < m.size(); ++i) {
            if (!m[i].allFinite())
                throw ParticleFileError(path + ": particle " + std::to_string(i) + " has a non-finite magnetization");
            s.magnetization.push_back(double(m[i].norm()));
        }
    }
    s.time = table.commentNumber("time", fallbackTime);
    if (!std::isfinite(s.time)) throw ParticleFileError(path + ": its time is not a finite number");
    std::vector<Vec3d> positions;
    positions.reserve(x.size());
    s.velocity.reserve(v.size());
    for (size_t i = 0; i < x.size(); ++i) {
        if (!x[i].allFinite() || !v[i].allFinite())
            throw ParticleFileError(path + ": particle " + std::to_string(i) + " has a non-finite position or velocity");
        positions.push_back(x[i].cast<double>());
        s.velocity.push_back(v[i].cast<double>());
    }
    double spacing = table.commentNumber("spacing", 0.0);
    if (!std::isfinite(spacing)) throw ParticleFileError(path + ": its spacing is not a finite number");
    if (!(spacing > 0) && !positions.empty()) { // no header: the mean spacing of the bounding box
        Vec3d lo = positions[0], hi = positions[0];
        for (const Vec3d& p : positions) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
        const Vec3d e = (hi - lo).cwiseMax(1e-6);
        spacing = std::cbrt(e.x() * e.y() * e.z() / double(positions.size()));
    }
    s.radius = 2.0 * spacing;
    s.grid = std::make_unique<HashGrid>(positions, s.radius > 0 ? s.radius : 1e-3);
    try {
        if (table.comment("magnet_count").size()) s.magnets = readMagnetComments(table);
    } catch (const ParticleFileError& e) {
        throw ParticleFileError(path + ": " + e.what());
    }
    return true;
}

// The component of v along the surface of unit normal n.
Vec3d alongSurface(const Vec3d& v, const Vec3d& n) { return v - v.dot(n) * n; }

} // namespace

std::shared_ptr<const SurfaceFlowHistory> SurfaceFlowHistory::load(const std::string& pattern, int frame, double tau,
                                                                   double fps, double window)
{
    std::vector<FlowSample> samples;
    if (!(tau > 0) || !(fps > 0) || frame < 0) return std::make_shared<SurfaceFlowHistory>(std::move(samples));
    // Samples over four response times (the tail beyond weighs e^-4), at most 0.05 s apart
    // (between them the velocity is interpolated: a slosh of 0.4 s period gets 8 a period) and
    // at most kMaxSamples of them (longer response times space them wider).
    constexpr int kMaxSamples = 64; // the frame itself and at most 63 before it
    const int span = int(std::ceil(std::max(4.0 * tau, std::isfinite(window) ? window : 0.0) * fps));
    const int stride = std::max({1, int(std::floor(std::min(0.5 * tau, 0.05) * fps + 1e-9)),
                                 (span + kMaxSamples - 2) / (kMaxSamples - 1)});
    const int oldest = std::max(0, frame - span);
    // The frame itself, then the multiples of the stride before it: consecutive frames share
    // their samples (each its own latest), so the velocity noise of one sample grid does not
    // alternate with another's from frame to frame and make the tips flicker.
    std::vector<int> frames{frame};
    for (int f = (frame / stride) * stride; f >= oldest; f -= stride)
        if (f < frame) frames.push_back(f);
    for (int f : frames) {
        const std::string path = framePath(pattern, f);
        if (!fileExists(path)) break;
        FlowSample s;
        if (!readSample(path, f / fps, s)) break;
        samples.push_back(std::move(s));
    }
    return std::make_shared<SurfaceFlowHistory>(std::move(samples));
}

SurfaceFlowHistory::SurfaceFlowHistory(std::vector<FlowSample> samples) : samples_(std::move(samples))
{
    std::sort(samples_.begin(), samples_.end(), [](const FlowSample& a, const FlowSample& b) { return a.time < b.time; });
}

namespace {

// The Shepard average (weight (1 - d^2/r^2)^3) of a per-particle value of sample s near x,
// over the particles within r = s.radius; where none is that close, the nearest particle's.
// s has a non-empty grid.
template <class T> T shepardAverage(const FlowSample& s, const std::vector<T>& value, const Vec3d& x, T zero)
{
    T sum = zero;
    double weight = 0;
    const double r2 = s.radius * s.radius;
    s.grid->forEachWithin(x, s.radius, [&](uint32_t i, double d2) {
        const double q = 1.0 - d2 / r2;
        const double w = q * q * q;
        sum += w * value[i];
        weight += w;
    });
    if (weight > 0) return sum / weight;
    return value[s.grid->nearest(x)];
}

} // namespace

Vec3d SurfaceFlowHistory::velocityAt(size_t k, const Vec3d& x) const
{
    const FlowSample& s = samples_[k];
    if (!s.grid || s.grid->empty()) return Vec3d::Zero();
    return shepardAverage<Vec3d>(s, s.velocity, x, Vec3d::Zero());
}

double SurfaceFlowHistory::magnetizationAt(size_t k, const Vec3d& x) const
{
    const FlowSample& s = samples_[k];
    if (!s.grid || s.grid->empty() || s.magnetization.size() != s.velocity.size())
        return std::numeric_limits<double>::quiet_NaN();
    return shepardAverage<double>(s, s.magnetization, x, 0.0);
}

Vec3d SurfaceFlowHistory::carriedOffset(const Vec3d& site, const Vec3d& n, int magnet, double tau, double t,
                                        const std::function<double(double)>& hold) const
{
    // The samples up to t (a little slack for times written as floats).
    size_t count = 0;
    while (count < samples_.size() && samples_[count].time <= t + 1e-6) ++count;
    if (count == 0 || !(tau > 0)) return Vec3d::Zero();
    const FlowSample& latest = samples_[count - 1];
    // Where the site stood at sample k: moved back by the pattern's magnet's move since then.
    auto siteAt = [&](size_t k) -> Vec3d {
        const std::vector<Magnet>& then = samples_[k].magnets;
        const std::vector<Magnet>& now = latest.magnets;
        if (magnet < 0 || size_t(magnet) >= then.size() || size_t(magnet) >= now.size() ||
            !magnetKindInfo(now[size_t(magnet)].kind).positioned) // a field the same everywhere
            return site;
        // The pattern hangs on the magnet's foot, where its axis meets the surface: a move
        // along the axis (a magnet pulled straight down) leaves it where it is.
        const Magnet& m = now[size_t(magnet)];
        const Vec3d axis = m.direction.norm() > 0 ? Vec3d(m.direction.normalized()) : Vec3d::Zero();
        Vec3d move = m.position - then[size_t(magnet)].position;
        move -= move.dot(axis) * axis;
        return site - alongSurface(move, n);
    };
    // The field's hold on the tip at sample k, where the tip stands then.
    auto holdAt = [&](size_t k, const Vec3d& x) {
        if (!hold) return 1.0;
        const double M = magnetizationAt(k, x);
        if (!std::isfinite(M)) return 1.0;
        return std::clamp(hold(M), 0.0, 1.0);
    };
    Vec3d d = Vec3d::Zero();
    bool held = false;
    for (size_t k = 0; k < count; ++k) {
        const double a = samples_[k].time;
        const double b = k + 1 < count ? samples_[k + 1].time : t;
        const double dt = b - a;
        if (!(dt > 0)) continue;
        const Vec3d La = siteAt(k), Lb = k + 1 < count ? siteAt(k + 1) : La;
        const Vec3d siteVelocity = (Lb - La) / dt;
        // The forcing u - dL/dt at both ends, the far end's velocity where the tip would be
        // with the offset it has now; the last interval (past the last sample) holds it.
        const Vec3d fa = alongSurface(velocityAt(k, La + d), n) - siteVelocity;
        const Vec3d fb = k + 1 < count ? Vec3d(alongSurface(velocityAt(k + 1, Lb + d), n) - siteVelocity) : fa;
        const double sa = holdAt(k, La + d), sb = k + 1 < count ? holdAt(k + 1, Lb + d) : sa;
        if (!held && !(sa > 0) && !(sb > 0)) continue; // no spike here yet: nothing to carry
        held = true;
        // dd/dt = f(s) - kappa d with f linear over [a, b] and kappa = the mean hold / tau,
        // integrated exactly: d E + fa I0 + (fb - fa) I1, E = e^(-kappa dt),
        // I0 = (1 - E) / kappa, I1 = (1 - I0 / dt) / kappa (dt and dt / 2 as kappa -> 0).
        const double kappa = 0.5 * (sa + sb) / tau, x = kappa * dt;
        const double E = std::exp(-x);
        double I0, I1;
        if (x > 1e-4) {
            I0 = -std::expm1(-x) / kappa;
            I1 = (1 - I0 / dt) / kappa;
        } else { // the series, where the quotients above lose their digits
            I0 = dt * (1 - x / 2 + x * x / 6);
            I1 = dt * (0.5 - x / 6 + x * x / 24);
        }
        d = d * E + fa * I0 + (fb - fa) * I1;
    }
    return d;
}

} // namespace ferro
