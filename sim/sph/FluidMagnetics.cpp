#include "sim/sph/FluidMagnetics.hpp"

#include "sim/magnetics/MagnetizationSolver.hpp"
#include "sim/magnetics/SolidCoupling.hpp"
#include "sim/core/ParticleLoops.hpp"
#include "sim/sph/Kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ferro {

namespace {


const char* solverName(MagnetizationParams::Solver s) {
    switch (s) {
    case MagnetizationParams::Solver::External: return "external";
    case MagnetizationParams::Solver::Direct: return "direct";
    case MagnetizationParams::Solver::Tree: return "tree";
    case MagnetizationParams::Solver::Auto: return "auto";
    }
    return "?";
}

} // namespace

FluidMagnetics::FluidMagnetics(const SimScene& scene, double particleVolume, double spacing)
    : tracks_(scene.magnets), law_(scene.magnetization), volume_(particleVolume), spacing_(spacing),
      rho0_(scene.fluid.restDensity), gravity_(scene.solver.gravity.norm()),
      curve_(scene.magnetization.susceptibility, scene.magnetization.saturation), flat_(spacing, particleVolume) {
    if (active() && !scene.solids.empty())
        solids_ = std::make_unique<SolidCoupling>(scene.solids, spacing, scene.path);
    if (active() && magnetic()) {
        solver_ = std::make_unique<MagnetizationSolver>(law_);
        const ContainerParams& c = scene.container;
        if (c.type == ContainerParams::Type::Box && c.periodicSides) // the layer's periodic copies
            solver_->setPeriodic(c.max.x() - c.min.x(), c.max.y() - c.min.y());
    }
}

double FluidMagnetics::surfaceWeight(double gradient) const { return flat_.weight(gradient); }

FluidMagnetics::~FluidMagnetics() = default;

std::vector<Magnet> FluidMagnetics::magnetsAt(double t) const {
    std::vector<Magnet> out;
    out.reserve(tracks_.size());
    for (const MagnetTrack& track : tracks_) out.push_back(track.at(t));
    return out;
}

std::vector<Magnet> FluidMagnetics::softenedMagnetsAt(double t) const {
    std::vector<Magnet> out = magnetsAt(t);
    // SPH cannot resolve a field that varies over less than a particle spacing, and a
    // 1/r^3 field with its 1/r^4 gradient near a pole would otherwise blow a particle that
    // touches it out of the simulation: soften every source over at least one spacing.
    for (Magnet& m : out) m.softening = std::max(m.softening, spacing_);
    return out;
}

bool FluidMagnetics::solveIsStale() const {
    if (!solved_ || HextSolved_.size() != Hext_.size()) return true;
    if (law_.resolveEvery > 0) return stepsSinceSolve_ >= size_t(law_.resolveEvery);
    // Between solves the induced field rides along with the particles. Its error grows with
    // the fluid's deformation and the magnets' motion; each solve measures the error the
    // cache had reached (see solve()), which sets how many steps the next cache may live.
    if (stepsSinceSolve_ >= interval_) return true;
    // A magnet that moves or changes faster than it did while the interval was measured
    // (a keyframe jump, a fast fade). The cache follows the applied field's overall
    // strength (inducedScale_); what that misses is the change of its pattern, which
    // changes M, and so the Kelvin force, by about the induced share of it.
    const size_t n = Hext_.size();
    const Real scale = Real(inducedScale_);
    const double change2 = deterministicSum(n, [&](size_t i) { return double((Hext_[i] - scale * HextSolved_[i]).squaredNorm()); });
    const double relChange = extNow2_ > 0 ? std::sqrt(change2 / extNow2_) : 0.0;
    return inducedShare_ * kelvinShare_ * relChange > 0.5 * law_.tolerance;
}

void FluidMagnetics::applyLaw() {
    const double chi0 = law_.susceptibility, Ms = law_.saturation;
    forEachParticle(H_.size(), [&](size_t i) {
        const double h = H_[i].cast<double>().norm();
        M_[i] = h > 0 ? Vec3((H_[i].cast<double>() * (langevinMagnetization(h, chi0, Ms) / h)).cast<Real>())
                      : Vec3::Zero();
    });
}

void FluidMagnetics::solve(const std::vector<Vec3>& x, const std::function<SurfaceView()>& surface, bool forced) {
    const size_t n = x.size();
    // A forced solve (frame start) measures nothing: a resumed run, which has no cache to
    // measure, then continues with exactly the interval the file recorded.
    const bool measure = !forced && solved_ && HextSolved_.size() == n && law_.resolveEvery == 0;
    std::vector<Vec3> predicted;
    if (measure) {
        // What the cache would have said now: applied field plus the carried induced field.
        predicted.resize(n);
        const Real scale = Real(inducedScale_);
        forEachParticle(n, [&](size_t i) { predicted[i] = Hext_[i] + scale * Hind_[i]; });
    }
    std::vector<Real> volume(n, Real(volume_));
    if (solids_) {
        // The solids first, in the magnets' field and the fluid's of the last solve
        // (SolidCoupling.hpp); the fluid then sees theirs as applied field.
        updateSolids(x, M_.size() == n ? M_ : std::vector<Vec3>{}, forced); // M_: the last solve's, or a resumed file's
        forEachParticle(n, [&](size_t i) { Hext_[i] = magnetField(magnets_, x[i].cast<double>()).cast<Real>() + Hsol_[i]; });
    }
    const MagnetizationSolver::Stats st = solver_->solve(x, volume, magnets_, H_, M_, nullptr, solids_ ? &Hsol_ : nullptr);
    forEachParticle(n, [&](size_t i) { Hind_[i] = H_[i] - Hext_[i]; });
    const double ind2 = deterministicSum(n, [&](size_t i) { return double(Hind_[i].squaredNorm()); });
    const double tot2 = deterministicSum(n, [&](size_t i) { return double(H_[i].squaredNorm()); });
    inducedShare_ = tot2 > 0 ? std::sqrt(ind2 / tot2) : 0.0;
    if (measure && tot2 > 0) {
        // What the cache's drift would have done to the motion: the error of the Kelvin
        // acceleration, mu0 J_ext (chi dH) / rho0 with the secant susceptibility chi = M / H,
        // relative to the accelerations that drive this fluid (gravity, the Kelvin force).
        // A weak field may drift by many percent without changing anything that moves; a
        // strong one is re-solved as often as its force needs. The error is assumed to grow
        // linearly with the steps since the last solve; the next cache lives until it would
        // reach half the tolerance, and the interval at most doubles per solve, so one
        // lucky measurement cannot stretch it.
        const double accErr2 = deterministicSum(n, [&](size_t i) {
            const double h = H_[i].cast<double>().norm();
            const double chi = h > 0 ? M_[i].cast<double>().norm() / h : 0.0;
            const Vec3d dM = chi * (H_[i] - predicted[i]).cast<double>();
            return (appliedGradient(i, x[i]) * dM).squaredNorm();
        });
        const double kelvin2 = kelvin_.size() == n ? deterministicSum(n, [&](size_t i) { return double(kelvin_[i].squaredNorm()); }) : 0.0;
        const double aRef = std::max(gravity_, std::sqrt(kelvin2 / double(n)));
        const double err = aRef > 0 ? kMu0 / rho0_ * std::sqrt(accErr2 / double(n)) / aRef : 0.0;
        // Part of that difference is no drift at all: both solves carry the solver's own
        // error (the tree's approximation, which changes as particles cross cells, and the
        // stopping residual), a floor that does not grow with the interval. Only what
        // exceeds it counts as drift (at least a tenth of the difference, so the interval
        // still grows step by step towards where real drift shows).
        const double floor = kelvinShare_ * (st.fieldError + lastFieldError_);
        const double drift = std::max(err - floor, 0.1 * err);
        const double rate = drift / double(std::max<size_t>(stepsSinceSolve_, 1));
        const double target = rate > 0 ? 0.5 * law_.tolerance / rate : 1e9;
        interval_ = size_t(std::clamp(std::floor(target), 1.0, double(std::min<size_t>(2 * interval_, kMaxInterval))));
        stats_.cacheError = err;
    }
    lastFieldError_ = st.fieldError;
    traction_ = st.solver != MagnetizationParams::Solver::External;
    if (traction_) {
        // The body force's M: the solve's M along the applied field against its strength.
        std::vector<double> h(n), along(n);
        forEachParticle(n, [&](size_t i) {
            const Vec3d he = Hext_[i].cast<double>();
            h[i] = he.norm();
            along[i] = h[i] > 0 ? M_[i].cast<double>().dot(he) / h[i] : 0.0;
        });
        // The curve's potential is fitted to the magnetic pressure of free-surface samples, so
        // that a surface at rest obeys the ferrohydrostatic Bernoulli law
        // (DemagnetizationCurve.hpp). The curve's memory (kCurveMemory): each fit moves the
        // last curve towards this solve's surface by 1 - exp(-dt / kCurveMemory), dt the time
        // since the last fit.
        const double memory = curveFitTime_ <= time_ ? std::exp(-(time_ - curveFitTime_) / kCurveMemory) : 0.0;
        curve_.fit(h, along, surfaceSamples(x, surface()), DemagnetizationCurve::Fit::FreeSurface, memory);
        curveFitTime_ = time_;
    }
    HextSolved_ = Hext_;
    extSolved2_ = deterministicSum(n, [&](size_t i) { return double(Hext_[i].squaredNorm()); });
    inducedScale_ = 1;
    stepsSinceSolve_ = 1; // steps that use this solve, this one included
    solved_ = true;
    ++stats_.solves;
    stats_.solver = solverName(st.solver);
    stats_.iterations = st.iterations;
    stats_.estimatedError = st.fieldError;
    stats_.converged = stats_.converged && st.converged;
    unconvergedInRow_ = st.converged ? 0 : unconvergedInRow_ + 1;
    stats_.residual = std::max(stats_.residual, st.residual);
}

FluidMagnetics::SurfacePoint FluidMagnetics::surfacePoint(size_t i, const Vec3& x, const Vec3d& outward) const {
    // At the fluid's surface, half a spacing outside the particle centre (a particle stands
    // for the cube of fluid around it; the surface mesh is placed there too): the applied
    // field there plus the particle's own induced field, and M from the law.
    const double chi0 = law_.susceptibility, Ms = law_.saturation;
    const Vec3d xs = x.cast<double>() + 0.5 * spacing_ * outward;
    const Vec3d applied = magnetField(magnets_, xs) + (Hsol_.size() > i ? Vec3d(Hsol_[i].cast<double>()) : Vec3d::Zero());
    const Vec3d Hs = applied + (H_[i] - Hext_[i]).cast<double>();
    const double h = Hs.norm();
    const double Mn = h > 0 ? langevinMagnetization(h, chi0, Ms) * Hs.dot(outward) / h : 0.0;
    return {applied.norm(), langevinEnergy(h, chi0, Ms), 0.5 * Mn * Mn};
}

std::vector<DemagnetizationCurve::SurfaceSample> FluidMagnetics::surfaceSamples(const std::vector<Vec3>& x,
                                                                               const SurfaceView& view) const {
    // The free surface: particles whose colour gradient is at least half a flat surface's
    // and with no fluid in their outward cone (surface weight w >= 1/2, as the surface model's
    // C). Each sample sits half a spacing out along -grad c, where the fluid the particle
    // stands for ends and its pressure is zero: there the applied field (analytic: it changes
    // by up to 20 % per spacing near a magnet) plus the particle's own induced field (which
    // changes by 2-5 % per spacing near the top), M from the Langevin law of that field, and
    // P = F(H) + M_n^2 / 2 (the same surface and field tests/sim/sph/test_FluidMagnetics.cpp
    // checks the law on). Tried and dropped: a kernel-smoothed normal (25 % of the rise off
    // the law instead of 15 % on the suite's pool at chi0 1.5), samples from w >= 0.8 only
    // (37 %), from w >= 0.25 (the still-magnet tips no steadier).
    std::vector<DemagnetizationCurve::SurfaceSample> out;
    const size_t n = x.size();
    if (!view.colorGradient || !view.exposure || view.colorGradient->size() != n || view.exposure->size() != n) return out;
    for (size_t i = 0; i < n; ++i) {
        const Vec3d g = (*view.colorGradient)[i].cast<double>();
        const double gn = g.norm();
        if (!(gn > 0)) continue;
        const double weight = surfaceWeight(gn) * double((*view.exposure)[i]);
        if (!(weight >= 0.5)) continue;
        const SurfacePoint p = surfacePoint(i, x[i], -g / gn);
        out.push_back({p.applied, p.energy + p.traction, weight});
    }
    return out;
}

void FluidMagnetics::update(double t, const std::vector<Vec3>& x, const SurfaceProbe& surface, bool forceSolve) {
    if (!active()) return;
    // The surface costs a neighbour sweep: asked for at most once, and only when used.
    SurfaceView view;
    bool probed = false;
    const std::function<SurfaceView()> surfaceOnce = [&]() {
        if (!probed && surface) view = surface();
        probed = true;
        return view;
    };
    const size_t n = x.size();
    time_ = t;
    magnets_ = softenedMagnetsAt(t);
    Hext_.resize(n);
    H_.resize(n, Vec3::Zero());
    M_.resize(n, Vec3::Zero());
    Hind_.resize(n, Vec3::Zero());
    // The solids' field (SolidCoupling; none before the first solve, which a resumed run's
    // first step always is) is evaluated once a step at the positions now: by the solve when
    // there is one (it solves the charge first), else below. Whether to solve is decided
    // with the last step's values, one step's motion old (Hsol_ follows the particle order):
    // evaluating it twice on a solve step was a third of the step at a coil's held current.
    const bool solids = solids_ && Hsol_.size() == n;
    auto applied = [&] {
        forEachParticle(n, [&](size_t i) {
            Hext_[i] = magnetField(magnets_, x[i].cast<double>()).cast<Real>();
            if (Hsol_.size() == n) Hext_[i] += Hsol_[i];
        });
    };
    if (solids && !magnetic()) solids_->fieldAt(x, Hsol_, Jsol_);
    applied();
    ++stats_.steps;
    auto largest = [&](const std::vector<Vec3>& field) {
        return std::sqrt(double(largestOf(field.size(), Real(0), [&](size_t i) { return field[i].squaredNorm(); })));
    };
    if (!magnetic()) {
        maxFieldSeen_ = std::max(maxFieldSeen_, largest(Hext_));
        H_ = Hext_;
        std::fill(M_.begin(), M_.end(), Vec3::Zero());
        kelvin_.clear();
        maxAcceleration_ = 0;
        return;
    }
    if (!(forceSolve || !solved_)) {
        extNow2_ = deterministicSum(n, [&](size_t i) { return double(Hext_[i].squaredNorm()); });
        inducedScale_ = extSolved2_ > 0 ? std::sqrt(extNow2_ / extSolved2_) : 1.0;
    }
    const bool solving = forceSolve || solveIsStale();
    if (solving) {
        solve(x, surfaceOnce, forceSolve);
    } else if (solids) {
        solids_->fieldAt(x, Hsol_, Jsol_);
        applied();
        extNow2_ = deterministicSum(n, [&](size_t i) { return double(Hext_[i].squaredNorm()); });
        inducedScale_ = extSolved2_ > 0 ? std::sqrt(extNow2_ / extSolved2_) : 1.0;
    }
    // After the solve, which refreshes the solids' part of the applied field: a resumed run,
    // which has no solids' field before its first solve, then sees the same largest field.
    maxFieldSeen_ = std::max(maxFieldSeen_, largest(Hext_));
    if (!solving) {
        // Between solves: the cached induced field, the current applied field, the law.
        // The induced field is proportional to M, which follows the applied field: the
        // cache is scaled with the applied field's RMS strength (inducedScale_, exact for
        // a fading magnet in the linear regime); the drift measurement catches the rest.
        const Real scale = Real(inducedScale_);
        forEachParticle(n, [&](size_t i) { H_[i] = Hext_[i] + scale * Hind_[i]; });
        applyLaw();
        ++stepsSinceSolve_;
    }
    maxFieldSeen_ = std::max(maxFieldSeen_, largest(H_));
    computeKelvin(x, surfaceOnce);
    if (solving) {
        // How much the Kelvin force matters beside gravity (see solveIsStale()).
        const double kelvin2 = deterministicSum(n, [&](size_t i) { return double(kelvin_[i].squaredNorm()); });
        const double rms = std::sqrt(kelvin2 / double(std::max<size_t>(n, 1)));
        const double aRef = std::max(gravity_, rms);
        kelvinShare_ = aRef > 0 ? rms / aRef : 1.0;
    }
}

void FluidMagnetics::computeKelvin(const std::vector<Vec3>& x, const std::function<SurfaceView()>& surface) {
    const size_t n = x.size();
    kelvin_.resize(n);
    const SurfaceView view = law_.force == MagnetizationParams::Force::Surface ? surface() : SurfaceView{};
    if (view.colorGradient && view.exposure && view.colorGradient->size() == n && view.exposure->size() == n)
        computeSurfacePressure(x, *view.colorGradient, *view.exposure);
    else
        computeBodyForce(x);
    maxAcceleration_ = std::sqrt(double(largestOf(n, Real(0), [&](size_t i) { return kelvin_[i].squaredNorm(); })));
}

void FluidMagnetics::computeBodyForce(const std::vector<Vec3>& x) {
    // mu0 (J_magnets M) / rho0 per unit mass (see the header).
    const Real scale = Real(kMu0 / rho0_);
    if (traction_ && curve_.fitted()) {
        // Self-consistent solve: mu0 M_f(h) grad h / rho0, h = |H_magnets|, grad h =
        // J_magnets H_magnets / h (J is symmetric: the magnets' field is curl-free in the
        // fluid). A gradient, unlike J M_i with each particle's own M_i (see the header).
        forEachParticle(x.size(), [&](size_t i) {
            const Vec3d he = Hext_[i].cast<double>();
            const double h = he.norm();
            if (!(h > 0)) {
                kelvin_[i] = Vec3::Zero();
                return;
            }
            const Vec3d gradH = appliedGradient(i, x[i]) * (he / h);
            kelvin_[i] = (kMu0 / rho0_ * curve_.magnetization(h) * gradH).cast<Real>();
        });
        return;
    }
    forEachParticle(x.size(), [&](size_t i) {
        const Eigen::Matrix3f J = appliedGradient(i, x[i]).cast<Real>();
        kelvin_[i] = scale * (J * M_[i]);
    });
}

void FluidMagnetics::computeSurfacePressure(const std::vector<Vec3>& x, const std::vector<Vec3>& gradC,
                                            const std::vector<Real>& exposure) {
    // p_s = C - mu0 (F(H) + M_n^2 / 2) pushed along grad c on surface particles (header).
    const size_t n = gradC.size();
    std::vector<double> psi(n, 0.0), weight(n, 0.0);
    forEachParticle(n, [&](size_t i) {
        const Vec3d g = gradC[i].cast<double>();
        const double gn = g.norm();
        weight[i] = surfaceWeight(gn) * double(exposure[i]);
        if (weight[i] <= 0) return;
        const SurfacePoint p = surfacePoint(i, x[i], -g / gn);
        psi[i] = kMu0 * (p.energy + (traction_ ? p.traction : 0.0));
    });
    // C from the particles that are surely surface (w >= 1/2): a particle that only just
    // counts (a gap opening inside a moving fluid) would otherwise set the pressure level
    // of the whole surface from deep in the field. Below C the push is clamped at zero.
    double C = 0;
    for (size_t i = 0; i < n; ++i)
        if (weight[i] >= 0.5) C = std::max(C, psi[i]);
    const double scale = 1.0 / (rho0_ * flat_.layerFactor());
    forEachParticle(n, [&](size_t i) {
        kelvin_[i] = weight[i] > 0 ? Vec3((scale * weight[i] * std::max(C - psi[i], 0.0) * gradC[i].cast<double>()).cast<Real>())
                                   : Vec3::Zero();
    });
}

void FluidMagnetics::addKelvinAcceleration(std::vector<Vec3>& a) const {
    if (kelvin_.size() != a.size()) return;
    forEachParticle(a.size(), [&](size_t i) { a[i] += kelvin_[i]; });
}

void FluidMagnetics::permute(const std::vector<uint32_t>& order) {
    ferro::permute(Hext_, order);
    ferro::permute(Hind_, order);
    ferro::permute(H_, order);
    ferro::permute(M_, order);
    ferro::permute(kelvin_, order);
    ferro::permute(HextSolved_, order);
    if (Hsol_.size() == order.size()) {
        ferro::permute(Hsol_, order);
        ferro::permute(Jsol_, order);
    }
}

Mat3d FluidMagnetics::appliedGradient(size_t i, const Vec3& x) const {
    Mat3d g = fieldGradient(magnets_, x.cast<double>());
    if (Jsol_.size() > i) g += Jsol_[i].cast<double>();
    return g;
}

void FluidMagnetics::updateSolids(const std::vector<Vec3>& x, const std::vector<Vec3>& M, bool cold) {
    const std::vector<Real> volume(x.size(), Real(volume_));
    const SolidCoupling::Stats st = solids_->update(time_, magnets_, x, volume, M, law_, cold, Hsol_, Jsol_);
    stats_.solidPanels = st.panels;
    stats_.solidIterations = st.iterations;
    stats_.solidSeconds += st.seconds;
    stats_.solidConverged = stats_.solidConverged && st.converged;
}

std::optional<FluidMagnetics::CurveMemory> FluidMagnetics::curveMemory() const {
    // A curve whose memory setState() dropped is nothing to carry: the next fit starts
    // afresh, in this run and in one resumed from its file alike.
    const std::optional<DemagnetizationCurve::SurfaceFit> f = curve_.surfaceFit();
    if (!f || !std::isfinite(curveFitTime_)) return std::nullopt;
    return CurveMemory{*f, curveFitTime_};
}

void FluidMagnetics::setCurveMemory(const CurveMemory& c) {
    if (std::isfinite(c.time) && curve_.restoreSurfaceFit(c.fit)) curveFitTime_ = c.time;
}

void FluidMagnetics::setState(const std::vector<Vec3>& H, const std::vector<Vec3>& M) {
    H_ = H;
    M_ = M;
    Hsol_.clear(); // the solids are solved again from this state
    Jsol_.clear();
    solved_ = false;
    // The curve was fitted to another state's surface: the next fit starts afresh unless
    // setCurveMemory() brings back the curve that belongs to this state.
    curveFitTime_ = -std::numeric_limits<double>::infinity();
}

} // namespace ferro
