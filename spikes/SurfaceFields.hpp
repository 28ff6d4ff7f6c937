#pragma once
// What addSpikes evaluates at a point of the fluid surface: the field H, the magnetization |M|,
// the fades from the critical magnetization, the wetted wall, and the direction a spike grows.
// Internal to ferro_spikes (SpikeMapper.cpp and the phase files beside it).
#include "sim/spatial/HashGrid.hpp"
#include "spikes/SpikeTypes.hpp"

#include <algorithm>
#include <memory>
#include <vector>

namespace ferro {

/// A float vertex as double.
inline Vec3d toD(const Vec3& v) { return v.cast<double>(); }

/// 0 below 0, 1 above 1, 3 x^2 - 2 x^3 between.
inline double smoothstep01(double x)
{
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

/// The unit direction a spike grows in at a surface point with outward unit normal n: along the
/// field H [A/m], turned outward, tilted at most maxTilt [deg] from n (n itself where H = 0).
Vec3d growthDirection(const Vec3d& H, const Vec3d& n, double maxTilt);

/// Everything evaluated per point of the surface; shared by the phases of addSpikes. Holds
/// references to the input and parameters (they must outlive it); queries are thread-safe.
class SurfaceFields {
public:
    /// Mc: the critical magnetization M_c of eq. 16 [A/m]. The particle spacing (from the
    /// particles, else the fluid) sets the averaging radius of |M| (two spacings) and the
    /// default wall margin (1.5 spacings, 2 mm if unknown).
    SurfaceFields(const SpikeInput& in, const SpikeParams& p, double Mc);

    /// H [A/m] at a surface point x with outward normal n: the magnets and the solids at x, the
    /// particles' field a little above x (two particle spacings out along n), where the discrete particles
    /// blur into the continuum they stand for (right at the surface a single particle's near
    /// field would turn the spikes every which way).
    Vec3d field(const Vec3d& x, const Vec3d& n) const;

    /// |M| [A/m] at a surface point: the particles' M around it (a Shepard average with weight
    /// (1 - d^2/r^2)^3, r = two particle spacings), else the fluid's law at the local field H.
    double currentMagnetization(const Vec3d& x, const Vec3d& H) const;
    /// |M| at x now and at the input's past times (SpikeInput::pastMagnets): now first, the
    /// past ones scaled by the law at the magnets' past field there.
    std::vector<double> magnetizationHistory(const Vec3d& x, const Vec3d& H) const;
    /// The strongest |H| [A/m] at the surface point x (outward normal n) over the history
    /// (SpikeInput::pastMagnets): |H| now times the magnets' largest past |H| over their |H|
    /// now (|H| itself in a still or a growing field). The paper's spacing l = alpha / |H|
    /// takes it: a pattern crowds as its field grows, as in the paper, but when the field
    /// falls away it sinks on the lattice it stood on instead of jumping to the widest spacing
    /// in a frame, and widens only as the strong past leaves the history (4 growth times).
    /// The past field is taken where the surface stood then: a heap that collapses after its
    /// magnet is pulled sinks towards where the magnet was, and the old magnet at the new,
    /// lower surface overstated the peak by a third (the lattice contracted as the spikes
    /// sank). With SpikeInput::pastParticles, x is moved along n by the change of the fluid's
    /// height along that line (its highest particle within 1.5 spacings) since the peak.
    double fieldHistoryPeak(const Vec3d& x, const Vec3d& n, const Vec3d& H) const;
    /// The largest |M| of the history: where spikes stand, grow or still fade out (the
    /// mapping area, the pattern, the lattice's extent). currentMagnetization in a still field.
    double magnetization(const Vec3d& x, const Vec3d& H) const;
    /// Where spikes stand, grow or still sink at x: the fade curve, magnetization > M_c; the
    /// bifurcation curve, spikes stood at some time of the history (spikesStood).
    bool spiky(const Vec3d& x, const Vec3d& H) const;
    /// The bifurcation curve's relay, per sample of magnetizationHistory (k = 0 now): spikes
    /// stand once |M| has reached M_c and until it falls below the lower threshold M_s. The
    /// state before the history's oldest sample, when that one lies between M_s and M_c, is
    /// found by looking further back along the magnet tracks (SpikeInput::tracks) for the
    /// last time |M| left that band (none: no spikes, a layer never made supercritical).
    std::vector<char> spikesStood(const Vec3d& x, const Vec3d& H, const std::vector<double>& history) const;
    /// magnetizationFade and magnetizationGate averaged over the history with
    /// SpikeInput::pastWeights (SpikeParams::growthTime): a spike's height follows its past
    /// heights, so a field that jumps on grows the spikes over a few growth times.
    double heightFade(const Vec3d& x, const Vec3d& H) const;
    double surfaceGate(const Vec3d& x, const Vec3d& H) const;

    /// 0 at M_c, 1 from (1 + fade) M_c on, smooth: scales each spike's height (taken at its tip,
    /// so a spike at the area's edge is lower but still a symmetric cone).
    double magnetizationFade(double M) const;
    /// The field's hold on a standing spike at |M| [A/m], 0 to 1: the stationary height it
    /// supports there (magnetizationFade, or the bifurcation's upper branch capped at 1 from
    /// M_s on: a spike that stands is held down to the lower threshold). SurfaceFlow's pull of
    /// a carried tip back to its site has the rate hold / response_time.
    double holdCurve(double M) const;
    /// 0 at M_c, 1 from 1.05 M_c on, smooth: cuts the surface exactly where |M| drops below M_c.
    double magnetizationGate(double M) const;

    /// The input these fields are evaluated on.
    const SpikeInput& input() const { return in_; }

    /// True where x is closer than the wall margin to the container's walls, or closer than
    /// the film thickness to a solid (its bare wall, a wetting film): never spiky.
    bool wetted(const Vec3d& x) const;

private:
    /// The pastWeights-weighted mean of `fade` over magnetizationHistory(x, H), each sample
    /// with its relay state (always true for the fade curve).
    double historyMean(const Vec3d& x, const Vec3d& H, double (SurfaceFields::*fade)(double, bool) const) const;
    /// The curves per sample: height (magnetizationFade, or the bifurcation's upper branch
    /// capped at 1 where spikes stand) and gate (magnetizationGate, or 0 to 1 over 0.05 M_c
    /// above M_s where spikes stand).
    double heightCurve(double M, bool stood) const;
    double gateCurve(double M, bool stood) const;
    /// |M| at x under past magnets, scaled from the frame's |M| now (see magnetizationHistory).
    double pastMagnetization(const Vec3d& x, double Mnow, double scale, double lawNow,
                             const std::vector<Magnet>& past) const;
    bool bifurcation() const { return p_.heightCurve == SpikeParams::HeightCurve::Bifurcation; }
    SpikeBifurcation branch_;

    const SpikeInput& in_;
    const SpikeParams& p_;
    double Mc_;
    double spacing_ = 0, radius_ = 0, wallMargin_ = 0, filmThickness_ = 0;
    std::unique_ptr<HashGrid> particleGrid_;
};

} // namespace ferro
