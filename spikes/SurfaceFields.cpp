// The per-point evaluations of SurfaceFields.hpp.
#include "spikes/SurfaceFields.hpp"

#include "sim/core/Constants.hpp"
#include "sim/magnets/LangevinLaw.hpp"

#include <cmath>

namespace ferro {

Vec3d growthDirection(const Vec3d& H, const Vec3d& n, double maxTilt)
{
    Vec3d dir = H.norm() > 0 ? Vec3d(H.normalized()) : n;
    if (dir.dot(n) < 0) dir = -dir;
    const double cosMax = std::cos(maxTilt * kPi / 180.0);
    if (dir.dot(n) < cosMax) {
        Vec3d tangent = dir - dir.dot(n) * n;
        tangent = tangent.norm() > 0 ? Vec3d(tangent.normalized()) : Vec3d::Zero();
        dir = cosMax * n + std::sqrt(std::max(0.0, 1 - cosMax * cosMax)) * tangent;
    }
    return dir;
}

SurfaceFields::SurfaceFields(const SpikeInput& in, const SpikeParams& p, double Mc) : in_(in), p_(p), Mc_(Mc)
{
    const SpikeParticles& particles = in.particles;
    spacing_ = particles.spacing > 0 ? particles.spacing : in.fluid.particleSpacing;
    if (!particles.magnetization.empty() && particles.magnetization.size() == particles.positions.size() &&
        spacing_ > 0) {
        radius_ = 2.0 * spacing_;
        particleGrid_ = std::make_unique<HashGrid>(particles.positions, radius_);
    }
    wallMargin_ = p.wallMargin > 0 ? p.wallMargin : (spacing_ > 0 ? 1.5 * spacing_ : 2e-3);
    filmThickness_ = p.filmThickness > 0 ? p.filmThickness : (spacing_ > 0 ? 3.0 * spacing_ : 4e-3);
    branch_ = SpikeBifurcation::fromThresholds(p.lowerThreshold, p.magnetizationFade);
}

Vec3d SurfaceFields::field(const Vec3d& x, const Vec3d& n) const
{
    Vec3d H = magnetField(in_.magnets, x);
    if (in_.particleField) H += particleFieldAt(in_, x + 2.0 * spacing_ * n);
    if (in_.solids) H += solidFieldAt(in_, x);
    return H;
}

double SurfaceFields::currentMagnetization(const Vec3d& x, const Vec3d& H) const
{
    if (particleGrid_) {
        double sum = 0, weight = 0;
        const double r2 = radius_ * radius_;
        particleGrid_->forEachWithin(x, radius_, [&](uint32_t i, double d2) {
            const double q = 1.0 - d2 / r2;
            const double w = q * q * q;
            sum += w * in_.particles.magnetization[i];
            weight += w;
        });
        if (weight > 0) return sum / weight;
    }
    return langevinMagnetization(H.norm(), in_.fluid.law.susceptibility, in_.fluid.law.saturation);
}

double SurfaceFields::pastMagnetization(const Vec3d& x, double Mnow, double scale, double lawNow,
                                        const std::vector<Magnet>& past) const
{
    const MagnetizationParams& law = in_.fluid.law;
    const double then =
        langevinMagnetization(scale * magnetField(past, x).norm(), law.susceptibility, law.saturation);
    // No field now (a magnet just switched off): the law's past value, unscaled.
    return lawNow > 0 ? Mnow * then / lawNow : then;
}

std::vector<double> SurfaceFields::magnetizationHistory(const Vec3d& x, const Vec3d& H) const
{
    const double M = currentMagnetization(x, H);
    std::vector<double> history{M};
    if (in_.pastMagnets.empty()) return history;
    // The past magnetization at x scales with the law at the magnets' past field there
    // (the particles' share of the field, |H| / |H_magnets| now, taken as fixed over the
    // short history).
    const double Hm = magnetField(in_.magnets, x).norm();
    const double scale = Hm > 0 ? H.norm() / Hm : 1.0;
    const MagnetizationParams& law = in_.fluid.law;
    const double now = langevinMagnetization(scale * magnetField(in_.pastMagnets[0], x).norm(), law.susceptibility,
                                             law.saturation);
    for (size_t k = 1; k < in_.pastMagnets.size(); ++k)
        history.push_back(pastMagnetization(x, M, scale, now, in_.pastMagnets[k]));
    return history;
}

std::vector<char> SurfaceFields::spikesStood(const Vec3d& x, const Vec3d& H, const std::vector<double>& history) const
{
    std::vector<char> stood(history.size(), 0);
    if (!std::isfinite(Mc_)) return stood;
    const double Ms = (1 + branch_.lower) * Mc_;
    // The state before the oldest sample: decided there unless it lies in the band [M_s, M_c).
    bool state = history.back() >= Mc_;
    if (history.back() >= Ms && history.back() < Mc_ && in_.tracks && in_.lookbackStep > 0) {
        const double Hm = magnetField(in_.magnets, x).norm();
        const double scale = Hm > 0 ? H.norm() / Hm : 1.0;
        const MagnetizationParams& law = in_.fluid.law;
        auto magnetsAt = [&](double t) {
            std::vector<Magnet> m;
            for (const MagnetTrack& track : *in_.tracks) m.push_back(track.at(t));
            return m;
        };
        const double lawNow =
            langevinMagnetization(scale * magnetField(magnetsAt(in_.time), x).norm(), law.susceptibility, law.saturation);
        double t = in_.time - double(history.size() - 1) * (in_.pastMagnets.empty() ? 0.0 : in_.lookbackStep);
        // Back to the shot's start (the tracks hold their first keys before it: a layer that
        // sat in the band from the start never had spikes), in at most 4096 steps: a long hold
        // in the band is looked through in coarser steps rather than cut short.
        const double step = std::max(in_.lookbackStep, t / 4096);
        for (int k = 0; k < 4097 && t > 0; ++k) {
            t -= step;
            const double M = pastMagnetization(x, history.front(), scale, lawNow, magnetsAt(t));
            if (M >= Mc_) { state = true; break; }
            if (M < Ms) break;
        }
    }
    for (size_t k = history.size(); k-- > 0;) {
        if (history[k] >= Mc_) state = true;
        else if (history[k] < Ms) state = false;
        stood[k] = state;
    }
    return stood;
}

namespace {

// The fluid's height [m] along the line through x with unit direction n: the top of the
// particles within `radius` of the line that hang together with the one nearest x (walking up
// from it while the next is less than two spacings higher), so a droplet above the heap does
// not count (-inf when no particle is that close). Only its change between two frames is
// used. Measured on the slosh bench's collapse (frames 45-56), the pattern's spacing keeps
// within 4.51-4.75 mm with it; twice the mean over the whole column (all its particles, not
// the top one) gave 4.51-4.82 mm, and the mean of the top layer 4.56-4.92 mm.
double heightAlong(const std::vector<Vec3d>& particles, const Vec3d& x, const Vec3d& n, double radius, double spacing)
{
    std::vector<double> along;
    const double r2 = radius * radius;
    for (const Vec3d& p : particles) {
        const Vec3d d = p - x;
        const double s = d.dot(n);
        if ((d - s * n).squaredNorm() < r2) along.push_back(s);
    }
    if (along.empty()) return -std::numeric_limits<double>::infinity();
    std::sort(along.begin(), along.end());
    size_t i = 0;
    for (size_t k = 1; k < along.size(); ++k)
        if (std::abs(along[k]) < std::abs(along[i])) i = k;
    while (i + 1 < along.size() && along[i + 1] - along[i] < 2 * spacing) ++i;
    return along[i];
}

} // namespace

double SurfaceFields::fieldHistoryPeak(const Vec3d& x, const Vec3d& n, const Vec3d& H) const
{
    if (in_.pastMagnets.size() < 2) return H.norm();
    const double now = magnetField(in_.pastMagnets[0], x).norm();
    size_t strongest = 0;
    double peak = now;
    for (size_t k = 1; k < in_.pastMagnets.size(); ++k) {
        const double h = magnetField(in_.pastMagnets[k], x).norm();
        if (h > peak) {
            peak = h;
            strongest = k;
        }
    }
    if (strongest > 0 && in_.pastParticles && spacing_ > 0 && !in_.particles.positions.empty()) {
        // Where the surface stood at the peak: x moved by the fluid's height change since.
        const auto then = in_.pastParticles->positionsAt(in_.time - double(strongest) * in_.lookbackStep);
        if (then && !then->empty()) {
            const double radius = 1.5 * spacing_;
            const double hNow = heightAlong(in_.particles.positions, x, n, radius, spacing_);
            const double hThen = heightAlong(*then, x, n, radius, spacing_);
            if (std::isfinite(hNow) && std::isfinite(hThen))
                peak = std::max(now, magnetField(in_.pastMagnets[strongest], x + (hThen - hNow) * n).norm());
        }
    }
    return now > 0 ? H.norm() * peak / now : peak;
}

double SurfaceFields::magnetization(const Vec3d& x, const Vec3d& H) const
{
    const std::vector<double> h = magnetizationHistory(x, H);
    return *std::max_element(h.begin(), h.end());
}

bool SurfaceFields::spiky(const Vec3d& x, const Vec3d& H) const
{
    if (!bifurcation()) return magnetization(x, H) > Mc_;
    const std::vector<double> h = magnetizationHistory(x, H);
    const std::vector<char> stood = spikesStood(x, H, h);
    return std::find(stood.begin(), stood.end(), 1) != stood.end();
}

double SurfaceFields::historyMean(const Vec3d& x, const Vec3d& H, double (SurfaceFields::*curve)(double, bool) const) const
{
    const std::vector<double> h = magnetizationHistory(x, H);
    std::vector<char> stood(h.size(), 1);
    if (bifurcation()) stood = spikesStood(x, H, h);
    if (h.size() == 1) return (this->*curve)(h[0], stood[0]);
    double f = 0;
    for (size_t k = 0; k < h.size(); ++k) f += in_.pastWeights[k] * (this->*curve)(h[k], stood[k]);
    return f;
}

double SurfaceFields::heightFade(const Vec3d& x, const Vec3d& H) const
{
    return historyMean(x, H, &SurfaceFields::heightCurve);
}

double SurfaceFields::surfaceGate(const Vec3d& x, const Vec3d& H) const
{
    return historyMean(x, H, &SurfaceFields::gateCurve);
}

double SurfaceFields::heightCurve(double M, bool stood) const
{
    if (!bifurcation()) return magnetizationFade(M);
    if (!stood || !std::isfinite(Mc_)) return 0.0;
    return std::min(1.0, branch_.upperBranch(M / Mc_ - 1.0));
}

double SurfaceFields::gateCurve(double M, bool stood) const
{
    if (!bifurcation()) return magnetizationGate(M);
    if (!stood || !std::isfinite(Mc_)) return 0.0;
    const double Ms = (1 + branch_.lower) * Mc_;
    return smoothstep01((M - Ms) / (0.05 * std::max(Mc_, 1e-30)));
}

double SurfaceFields::holdCurve(double M) const
{
    if (!bifurcation()) return magnetizationFade(M);
    return heightCurve(M, M >= (1 + branch_.lower) * Mc_);
}

double SurfaceFields::magnetizationFade(double M) const
{
    if (!(M > Mc_) || !std::isfinite(Mc_)) return 0.0;
    return smoothstep01((M - Mc_) / (p_.magnetizationFade * std::max(Mc_, 1e-30)));
}

double SurfaceFields::magnetizationGate(double M) const
{
    if (!(M > Mc_) || !std::isfinite(Mc_)) return 0.0;
    return smoothstep01((M - Mc_) / (0.05 * std::max(Mc_, 1e-30)));
}

bool SurfaceFields::wetted(const Vec3d& x) const
{
    if (in_.fluid.container && !in_.fluid.container->contains(x, wallMargin_)) return true;
    return in_.fluid.solids && !in_.fluid.solids->contains(x, filmThickness_);
}

} // namespace ferro
