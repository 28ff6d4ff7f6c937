#include "sim/app/FrameTable.hpp"

#include "sim/magnets/MagnetState.hpp"
#include "sim/sph/FluidSimulation.hpp"

#include <cmath>
#include <sstream>

namespace ferro {

namespace {

/// The compact cache's columns (ParticleCache::Compact): positions as floats, the rest quantized.
ParticleTable compactTable(const ParticleTable& full) {
    ParticleTable t;
    t.names = {"x", "y", "z", "vx", "vy", "vz", "density", "mx", "my", "mz"};
    t.quantized = {"vx", "vy", "vz", "density", "mx", "my", "mz"};
    std::vector<int> from;
    for (const std::string& n : t.names) from.push_back(full.column(n));
    const size_t n = full.rows(), cols = t.names.size();
    t.values.resize(n * cols);
    for (size_t i = 0; i < n; ++i)
        for (size_t c = 0; c < cols; ++c) t.values[i * cols + c] = full.at(i, from[c]);
    t.comments = full.comments;
    t.setComment("cache", "compact");
    return t;
}

} // namespace

ParticleTable frameTable(const FluidSimulation& sim, int frame, const std::string& fingerprint, bool compact) {
    ParticleTable t;
    t.names = {"x", "y", "z", "vx", "vy", "vz", "density", "pressure", "hx", "hy", "hz", "mx", "my", "mz"};
    const auto x = sim.positionsById();
    const auto v = sim.velocitiesById();
    const auto rho = sim.densitiesById();
    const auto p = sim.pressuresById();
    const auto H = sim.fieldById();
    const auto M = sim.magnetizationById();
    const size_t n = x.size();
    t.values.resize(n * t.names.size());
    for (size_t i = 0; i < n; ++i) {
        float* row = &t.values[i * t.names.size()];
        row[0] = x[i].x(); row[1] = x[i].y(); row[2] = x[i].z();
        row[3] = v[i].x(); row[4] = v[i].y(); row[5] = v[i].z();
        row[6] = rho[i];
        row[7] = p[i];
        row[8] = H[i].x(); row[9] = H[i].y(); row[10] = H[i].z();
        row[11] = M[i].x(); row[12] = M[i].y(); row[13] = M[i].z();
    }
    auto num = [](double d) {
        std::ostringstream o;
        o.precision(17);
        o << d;
        return o.str();
    };
    t.setComment("ferro", "particles 1");
    t.setComment("frame", std::to_string(frame));
    t.setComment("time", num(sim.time()));
    t.setComment("fps", num(sim.scene().shot.fps));
    t.setComment("spacing", num(sim.spacing()));
    t.setComment("support_radius", num(sim.supportRadius()));
    t.setComment("particle_mass", num(sim.particleMass()));
    t.setComment("rest_density", num(sim.restDensity()));
    t.setComment("scene", sim.scene().path);
    t.setComment("scene_fingerprint", fingerprint);
    // The pressure solver over the steps that made this frame: steps, and per solve the
    // steps that stopped at the iteration cap with the largest mean compression they left
    // (DFSPH; zero for WCSPH, which has no iterations).
    const SolverCapCount& caps = sim.frameSolverCaps();
    t.setComment("solver_steps", std::to_string(caps.steps));
    t.setComment("density_solve_at_cap", std::to_string(caps.densityAtCap) + " " + num(caps.densityError));
    t.setComment("divergence_solve_at_cap", std::to_string(caps.divergenceAtCap) + " " + num(caps.divergenceError));
    // The magnets at this frame's time and the fluid's law: later stages evaluate the same
    // field anywhere from the file alone.
    writeMagnetComments(t, sim.magnetsNow(), &sim.scene().magnetization);
    if (sim.magnetizationInterval() > 0)
        t.setComment("magnetization_interval", std::to_string(sim.magnetizationInterval()));
    if (const auto c = sim.magnetizationCurve()) {
        std::string line;
        for (double d : {c->fit.hLo, c->fit.hHi, c->fit.c[0], c->fit.c[1], c->fit.c[2], c->fit.C, c->time})
            line += (line.empty() ? "" : " ") + num(d);
        t.setComment("magnetization_curve", line);
    }
    return compact ? compactTable(t) : t;
}

FrameState frameState(const ParticleTable& t) {
    FrameState s;
    s.x = t.vec3("x", "y", "z");
    s.v = t.vec3("vx", "vy", "vz");
    if (const int col = t.column("pressure"); col >= 0)
        for (size_t i = 0; i < t.rows(); ++i) s.p.push_back(t.at(i, col));
    if (t.column("hx") >= 0 && t.column("mx") >= 0) {
        s.H = t.vec3("hx", "hy", "hz");
        s.M = t.vec3("mx", "my", "mz");
    }
    if (const std::string line = t.comment("magnetization_curve"); !line.empty()) {
        std::istringstream in(line);
        double d[7];
        for (double& v : d)
            if (!(in >> v) || !std::isfinite(v))
                throw ParticleFileError("magnetization_curve comment '" + line + "': expected seven finite numbers");
        DemagnetizationCurve::SurfaceFit f;
        f.hLo = d[0];
        f.hHi = d[1];
        for (int k = 0; k < 3; ++k) f.c[k] = d[2 + k];
        f.C = d[5];
        s.curve = f;
        s.curveTime = d[6];
    }
    return s;
}

} // namespace ferro
