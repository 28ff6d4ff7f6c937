#pragma once
// The fluid's flow over the spikes' recent past, and the tips it carries
// (SpikeParams::responseTime, issue 32's "carried by the flow").
//
// The paper lays the tips out anew from the field in every frame, so they stand where the
// field puts them however the fluid under them moves. Here a tip is a marker on the surface
// that the flow carries and the field pulls back to its lattice site L with a response
// time tau:
//     dX/dt = u(X, t) + (L(t) - X) / tau,
// u the fluid's velocity along the surface at the tip. Its offset d = X - L from the site
// then obeys dd/dt = u - dL/dt - d / tau: a sloshing layer rocks the tips with it, and a
// magnet that slides faster than tau lets them follow leaves them trailing.
//
// The field holds a tip to its site only as firmly as it holds the spike up: the pull's rate
// is s / tau with s in [0, 1] the stationary height the field supports there (the spikes'
// height curve at the fluid's |M|). A strong field pins its tips to the lattice; where it has
// fallen away (a magnet pulled off) nothing pulls, and the sinking spikes drift with the
// fluid, as any other bump on the surface does. The velocities
// come from the particle files of earlier frames (a frame is still made alone, from the
// simulation's cache), the sites' motion from the pattern's magnet in those files' headers.
// Internal to ferro_spikes; depends on sim/core (particle files) and sim/spatial.
#include "sim/magnets/MagnetField.hpp"
#include "sim/spatial/HashGrid.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ferro {

/// One earlier frame's particles: where the fluid was and how it moved.
struct FlowSample {
    double time = 0;                   ///< [s]
    std::vector<Vec3d> velocity;       ///< per particle [m/s]
    std::vector<double> magnetization; ///< per particle |M| [A/m]; empty when the file had none
    std::unique_ptr<HashGrid> grid;    ///< over the particles' positions [m]
    double radius = 0;                 ///< Shepard radius: two particle spacings [m]
    std::vector<Magnet> magnets;       ///< the magnets in the file's header (may be empty)
};

/// The flow at a few times before (and at) a frame, oldest first.
class SurfaceFlowHistory {
public:
    /// Reads the particle files of the frame and of the multiples of a stride before it, back
    /// over max(4 tau, window) [s] (stride = the frames in min(tau / 2, 0.05 s), at least one,
    /// at most 64 files), stopping at frame 0 or at the first
    /// file that is missing; `pattern` has a {:04} / %04d placeholder, fps gives a file
    /// without a `time` header its time. Files without velocity columns (vx, vy, vz) end the
    /// history there too. Throws ParticleFileError on a malformed file.
    /// `window`: a tip that the field no longer holds keeps the whole drift of the history,
    /// so the history must reach back past the time its spikes took to sink (ferro-spikes
    /// passes 4 growth times, the spikes' own memory).
    static std::shared_ptr<const SurfaceFlowHistory> load(const std::string& pattern, int frame, double tau,
                                                          double fps, double window = 0);
    /// A history from samples already in memory (tests), sorted by time here.
    explicit SurfaceFlowHistory(std::vector<FlowSample> samples);

    const std::vector<FlowSample>& samples() const { return samples_; }

    /// The fluid's velocity [m/s] near x at sample k: a Shepard average (weight
    /// (1 - d^2/r^2)^3) of the particles within r = sample.radius; where none is that close
    /// (the surface was elsewhere then), the nearest particle's.
    Vec3d velocityAt(size_t k, const Vec3d& x) const;
    /// The fluid's |M| [A/m] near x at sample k, averaged as velocityAt; NaN when the sample
    /// has no magnetization.
    double magnetizationAt(size_t k, const Vec3d& x) const;

    /// The tip's offset d(t) [m] from its site at time t [s]: the equation above integrated
    /// from d = 0 at the oldest sample to t (samples after t ignored; between samples the
    /// velocity is interpolated linearly in time and the integration is exact for it), with
    /// only the components along the surface (normal n, unit). The site now is `site` [m];
    /// earlier it stood where the magnet `magnet` (an index into each sample's header
    /// magnets; -1, a uniform field or a sample without it: the site stands still) had moved
    /// it from: site - (the magnet's move since then across its axis, along the surface: the
    /// pattern hangs on the magnet's foot). tau > 0 [s].
    /// `hold` maps the fluid's |M| at the tip to the field's hold s in [0, 1] on it: the pull
    /// back to the site has the rate s / tau (linear in time between samples, exact for a
    /// constant rate over each interval: the mean of its ends). Without it, or at a sample
    /// without magnetization, s = 1. The offset starts at 0 at the first interval the field
    /// holds at either end: before a field held it there was no spike there to carry.
    Vec3d carriedOffset(const Vec3d& site, const Vec3d& n, int magnet, double tau, double t,
                        const std::function<double(double)>& hold = {}) const;

private:
    std::vector<FlowSample> samples_;
};

} // namespace ferro
