#include "spikes/SpikeFrames.hpp"
#include "spikes/SpikeSolids.hpp"
#include "spikes/SurfaceFlow.hpp"

#include "sim/core/FrameRunner.hpp"

#include "sim/magnets/MagnetState.hpp"
#include "sim/magnets/LangevinLaw.hpp"
#include "sim/particlefield/ParticleField.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimSceneFile.hpp"
#include "sim/spatial/HashGrid.hpp"

#include <tbb/parallel_for.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>

namespace ferro {

SpikeScene parseSpikeScene(const SceneDocument& doc)
{
    const SimScene sim = parseSimScene(doc, SceneUse::PerFrame);
    SpikeScene scene;
    scene.params = parseSpikeParams(doc);
    scene.magnets = sim.magnets;
    for (const auto& [magnet, lattice] : scene.params.magnetLattice)
        if (size_t(magnet) >= scene.magnets.size())
            throw SceneError(doc.path() + ": [[spikes.magnets]] magnet = " + std::to_string(magnet) +
                             ": the scene has " + std::to_string(scene.magnets.size()) +
                             " magnet(s), numbered from 0");
    scene.fps = sim.shot.fps;
    scene.solids = sim.solids;
    scene.path = doc.path();
    SpikeFluid& fluid = scene.fluid;
    fluid.density = sim.fluid.restDensity;
    fluid.surfaceTension = sim.fluid.surfaceTension;
    fluid.viscosity = sim.fluid.viscosity;
    fluid.gravity = sim.solver.gravity;
    fluid.law = sim.magnetization;
    fluid.particleSpacing = sim.fluid.spacing;
    const ContainerParams& c = sim.container;
    if (c.type != ContainerParams::Type::None)
        fluid.container = std::shared_ptr<const Container>(makeContainer(c, doc.path() + ": [container]"));
    if (c.type == ContainerParams::Type::Dish) {
        fluid.hasCenter = true;
        fluid.center = c.center;
    } else if (c.type == ContainerParams::Type::Box) {
        fluid.hasCenter = true;
        fluid.center = 0.5 * (c.min + c.max);
        if (c.periodicSides) {
            fluid.period[0] = c.max.x() - c.min.x();
            fluid.period[1] = c.max.y() - c.min.y();
        }
    }
    return scene;
}

namespace {

bool hasComment(const std::vector<std::pair<std::string, std::string>>& comments, const std::string& key)
{
    for (const auto& kv : comments)
        if (kv.first == key) return true;
    return false;
}

std::string formatDouble(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

} // namespace

namespace {

// The frame's time [s]: header `time`, else `frame` / fps (particle file first, then the
// mesh), else frameHint / fps, else 0.

// The frame's magnets, in order of preference: the particle file's header (when there is a
// particle file), the mesh's header, the scene's tracks at the frame's time (header `time`,
// else `frame` / fps, else frameHint / fps, else 0 s). Throws ParticleFileError on a
// malformed magnet header.
double frameTime(const SpikeScene& scene, const ParticleTable& particles, const ParticleTable& meshHeader,
                 int frameHint)
{
    double time = std::nan("");
    for (const ParticleTable* t : {&particles, &meshHeader}) {
        if (!std::isnan(time)) break;
        time = t->commentNumber("time", std::nan(""));
        if (std::isnan(time)) {
            const double frame = t->commentNumber("frame", std::nan(""));
            if (!std::isnan(frame)) time = frame / scene.fps;
        }
    }
    if (std::isnan(time)) time = frameHint >= 0 ? frameHint / scene.fps : 0.0;
    return time;
}

std::vector<Magnet> frameMagnets(const SpikeScene& scene, const ParticleTable& particles, bool haveParticles,
                                 const ParticleTable& meshHeader, int frameHint)
{
    if (haveParticles && hasComment(particles.comments, "magnet_count")) return readMagnetComments(particles);
    if (hasComment(meshHeader.comments, "magnet_count")) return readMagnetComments(meshHeader);
    const double time = frameTime(scene, particles, meshHeader, frameHint);
    std::vector<Magnet> magnets;
    for (const MagnetTrack& track : scene.magnets) magnets.push_back(track.at(time));
    return magnets;
}

// SpikeParams::growthTime: the magnets at kHistorySteps earlier times a quarter growth time
// apart (4 growth times back, the tail beyond weighs e^-4), from the scene's tracks, with
// exponential weights summing to 1. Only when the tracks are the frame's magnets (same
// count): a frame whose magnets come from a file the scene does not describe has no past.
void addMagnetHistory(const SpikeScene& scene, double time, SpikeInput& in)
{
    constexpr int kHistorySteps = 16;
    const double tau = scene.params.growthTime;
    if (scene.magnets.empty() || scene.magnets.size() != in.magnets.size()) return;
    in.tracks = std::make_shared<const std::vector<MagnetTrack>>(scene.magnets);
    in.lookbackStep = tau > 0 ? tau / 4 : 1.0 / scene.fps;
    if (!(tau > 0)) return;
    const double step = tau / 4;
    double total = 0;
    for (int k = 0; k <= kHistorySteps; ++k) {
        const double w = std::exp(-k * step / tau);
        in.pastWeights.push_back(w);
        total += w;
        std::vector<Magnet> past; // k = 0: the tracks now, the reference the past is scaled by
        for (const MagnetTrack& track : scene.magnets) past.push_back(track.at(time - k * step));
        in.pastMagnets.push_back(std::move(past));
    }
    for (double& w : in.pastWeights) w /= total;
}

// The field [A/m] of the magnetized particles (positions x [m], magnetization M [A/m]) at a
// point: each particle of volume m / rho = rho0 h^3 / rho (h = spacing [m], rho0 the fluid's
// rest density, rho the file's `density` column where present) a smoothed dipole of the
// scene's magnetization.smoothing (the simulator's model, sim/particlefield/DipoleTree.hpp),
// summed by a tree (opening angle 0.6), with the periodic copies of a box with periodic sides
// (fluid.period).
std::shared_ptr<const ParticleFieldEvaluator> particleFieldOf(const ParticleTable& particles, const std::vector<Vec3>& x,
                                                              const std::vector<Vec3>& M, double spacing, const SpikeFluid& fluid)
{
    const double restDensity = fluid.density, smoothing = fluid.law.smoothing;
    const int rho = particles.column("density");
    const double h3 = std::pow(spacing, 3);
    std::vector<Real> volume(x.size(), Real(h3));
    if (rho >= 0)
        for (size_t i = 0; i < x.size(); ++i) {
            const double r = particles.at(i, rho);
            if (r > 0) volume[i] = Real(h3 * restDensity / r);
        }
    auto evaluator = std::make_shared<ParticleFieldEvaluator>();
    evaluator->setPeriodic(fluid.period[0], fluid.period[1]);
    evaluator->build(x, volume, M, 0.6, smoothing);
    return evaluator;
}

// The x, y, z columns of a particle table read from `path`, every one finite. Throws
// SpikeInputError naming the file (a missing column, a non-finite position).
std::vector<Vec3> finitePositions(const ParticleTable& table, const std::string& path)
{
    std::vector<Vec3> x;
    try {
        x = table.vec3("x", "y", "z");
    } catch (const ParticleFileError& e) {
        throw SpikeInputError(path + ": " + e.what());
    }
    for (size_t i = 0; i < x.size(); ++i)
        if (!x[i].allFinite())
            throw SpikeInputError(path + ": particle " + std::to_string(i) + " has a non-finite position");
    return x;
}

// The frame's particles (a non-empty table read from particlePath) into in.particles:
// positions [m], spacing (header, else the fluid's) [m] and |M| [A/m] per particle (the mx,
// my, mz columns, else the fluid's law in the magnets' field), and with those columns (and
// [spikes] particle_field) in.particleField. Sets in.fluid.particleSpacing to a known
// spacing. Throws SpikeInputError on a malformed table, non-finite positions or |M|.
void loadParticles(const SpikeScene& scene, const ParticleTable& particles, const std::string& particlePath,
                   SpikeInput& in)
{
    const std::vector<Vec3> x = finitePositions(particles, particlePath);
    try {
        in.particles.positions.reserve(x.size());
        for (const Vec3& p : x) in.particles.positions.push_back(p.cast<double>());
        in.particles.spacing = particles.commentNumber("spacing", in.fluid.particleSpacing);
        in.particles.magnetization.resize(x.size());
        if (particles.column("mx") >= 0 && particles.column("my") >= 0 && particles.column("mz") >= 0) {
            const std::vector<Vec3> M = particles.vec3("mx", "my", "mz");
            for (size_t i = 0; i < M.size(); ++i) in.particles.magnetization[i] = double(M[i].norm());
            if (scene.params.particleField && in.particles.spacing > 0)
                in.particleField = particleFieldOf(particles, x, M, in.particles.spacing, in.fluid);
        } else {
            // Older files: the fluid's law in the magnets' field at the particle.
            for (size_t i = 0; i < x.size(); ++i)
                in.particles.magnetization[i] =
                    langevinMagnetization(magnetField(in.magnets, in.particles.positions[i]).norm(),
                                          in.fluid.law.susceptibility, in.fluid.law.saturation);
        }
    } catch (const ParticleFileError& e) {
        throw SpikeInputError(particlePath + ": " + e.what());
    }
    for (double m : in.particles.magnetization)
        if (!std::isfinite(m)) throw SpikeInputError(particlePath + ": non-finite magnetization");
    if (in.particles.spacing > 0) in.fluid.particleSpacing = in.particles.spacing;
}

} // namespace

SpikeInput loadSpikeInput(const SpikeScene& scene, const std::string& surfacePath, const std::string& particlePath,
                          int frameHint)
{
    SpikeInput in;
    requireReadable(surfacePath);
    if (!particlePath.empty()) requireReadable(particlePath);
    try {
        in.surface = readMesh(surfacePath);
    } catch (const MeshFileError& e) {
        throw SpikeInputError(e.what());
    }
    // An empty surface (a frame without fluid) is valid: addSpikes returns it unchanged.
    for (const Vec3& v : in.surface.vertices)
        if (!v.allFinite()) throw SpikeInputError(surfacePath + ": mesh has a non-finite vertex");
    in.fluid = scene.fluid;

    ParticleTable meshHeader;
    meshHeader.comments = in.surface.comments;
    ParticleTable particles;
    const bool haveParticles = !particlePath.empty();
    try {
        if (haveParticles) particles = readParticleFile(particlePath);
        in.magnets = frameMagnets(scene, particles, haveParticles, meshHeader, frameHint);
    } catch (const ParticleFileError& e) {
        throw SpikeInputError(e.what());
    }
    for (const ParticleTable* t : {&meshHeader, &particles}) { // the particle file wins
        in.fluid.law.susceptibility = t->commentNumber("susceptibility", in.fluid.law.susceptibility);
        in.fluid.law.saturation = t->commentNumber("saturation", in.fluid.law.saturation);
    }
    if (!(in.fluid.law.susceptibility >= 0) || !(in.fluid.law.saturation >= 0))
        throw SpikeInputError(surfacePath + ": negative susceptibility or saturation in the header");

    if (haveParticles && particles.rows() > 0) loadParticles(scene, particles, particlePath, in);
    in.time = frameTime(scene, particles, meshHeader, frameHint);
    addSolids(scene.solids, in.fluid.particleSpacing, scene.path, in);
    addMagnetHistory(scene, in.time, in);
    return in;
}

bool earlierSpikeInput(const SpikeScene& scene, const SpikeInput& in, double interval, SpikeInput& earlier)
{
    if (!(interval > 0) || scene.magnets.empty() || scene.magnets.size() != in.magnets.size()) return false;
    // The frame's magnets moved as their tracks did over the interval (the header's own
    // softening and sizes kept, so a still magnet is exactly the same magnet).
    std::vector<Magnet> magnets = in.magnets;
    bool moved = false;
    for (size_t k = 0; k < magnets.size(); ++k) {
        const Magnet now = scene.magnets[k].at(in.time), then = scene.magnets[k].at(in.time - interval);
        magnets[k].position += then.position - now.position;
        if (then.direction != now.direction) magnets[k].direction = then.direction;
        magnets[k].strength = now.strength != 0 ? magnets[k].strength * (then.strength / now.strength) : then.strength;
        moved = moved || then.position != now.position || then.direction != now.direction || then.strength != now.strength;
    }
    // The spikes' past reaches 4 growth times back: a field that has been still over all of
    // it and the interval gives the same spikes (their own velocity is zero).
    const double tau = scene.params.growthTime;
    if (!moved && !in.pastMagnets.empty() && tau > 0) {
        for (double back = 0; back <= 4 * tau + interval && !moved; back += tau / 4)
            for (const MagnetTrack& track : scene.magnets) {
                const Magnet a = track.at(in.time - back), b = track.at(in.time - back - interval);
                moved = moved || a.position != b.position || a.direction != b.direction || a.strength != b.strength;
            }
    }
    // A gain, a jitter or a squareness keyed by [[spikes.keys]] that changed over the interval
    // moves the spikes too: the tips' amplitude grows, their positions drift or slide to the
    // morphed lattice, and the spikes carry that as velocity (tipMotions). Keyed sharpness and
    // defects change the profile, which the velocity model does not follow: they change the
    // shape without motion blur.
    const SpikeParams lookNow = spikeParamsAt(scene.params, in.time),
                      lookThen = spikeParamsAt(scene.params, in.time - interval);
    moved = moved || lookNow.heightGain != lookThen.heightGain || lookNow.jitter != lookThen.jitter ||
            lookNow.squareness != lookThen.squareness;
    // Tips carried by the flow (response_time) move with it even under a still field.
    moved = moved || (scene.params.responseTime > 0 && in.flow && in.flow->samples().size() > 1);
    if (!moved) return false;
    earlier = in;
    earlier.time = in.time - interval;
    earlier.magnets = std::move(magnets);
    // The particles' |M| as it was: each scaled by the law at the magnets' field then and now
    // (the particles' own share of the field taken as fixed over the interval).
    const MagnetizationParams& law = in.fluid.law;
    tbb::parallel_for(size_t(0), earlier.particles.magnetization.size(), [&](size_t i) {
        const Vec3d& x = earlier.particles.positions[i];
        const double now = langevinMagnetization(magnetField(in.magnets, x).norm(), law.susceptibility, law.saturation);
        const double then =
            langevinMagnetization(magnetField(earlier.magnets, x).norm(), law.susceptibility, law.saturation);
        if (now > 0) earlier.particles.magnetization[i] *= then / now;
    });
    earlier.pastMagnets.clear();
    earlier.pastWeights.clear();
    addMagnetHistory(scene, earlier.time, earlier);
    return true;
}

namespace {

// SpikeInput::pastParticles from the particle files of `pattern`: the file of the frame
// nearest a time, read once (positions only); null where the file does not exist (before the
// shot, a range simulated only in part). A file that exists but cannot be read is an error
// (SpikeInputError naming it).
class ShotParticleHistory final : public ParticleHistory {
public:
    ShotParticleHistory(std::string pattern, double fps) : pattern_(std::move(pattern)), fps_(fps) {}

    std::shared_ptr<const std::vector<Vec3d>> positionsAt(double time) const override {
        if (!(fps_ > 0) || !std::isfinite(time)) return nullptr;
        const int frame = std::max(0, int(std::lround(time * fps_)));
        std::lock_guard<std::mutex> guard(lock_);
        const auto found = cache_.find(frame);
        if (found != cache_.end()) return found->second;
        std::shared_ptr<const std::vector<Vec3d>> result;
        const std::string path = framePath(pattern_, frame);
        if (std::filesystem::exists(path)) {
            ParticleTable table;
            try {
                table = readParticleFile(path);
            } catch (const ParticleFileError& e) {
                throw SpikeInputError(e.what());
            }
            const std::vector<Vec3> x = finitePositions(table, path);
            auto positions = std::make_shared<std::vector<Vec3d>>();
            positions->reserve(x.size());
            for (const Vec3& p : x) positions->push_back(p.cast<double>());
            result = std::move(positions);
        }
        cache_[frame] = result;
        return result;
    }

private:
    std::string pattern_;
    double fps_;
    mutable std::mutex lock_;
    mutable std::map<int, std::shared_ptr<const std::vector<Vec3d>>> cache_;
};

} // namespace

SpikeResult spikeFrame(const SpikeScene& scene, const std::string& surfacePath, const std::string& particlePath,
                       const std::string& outPath, int frameHint, const std::string& historyPattern)
{
    refuseToOverwriteInputs("--out", outPath, {surfacePath, particlePath});
    SpikeInput in = loadSpikeInput(scene, surfacePath, particlePath, frameHint);
    if (!historyPattern.empty()) in.pastParticles = std::make_shared<ShotParticleHistory>(historyPattern, scene.fps);
    if (scene.params.responseTime > 0 && !historyPattern.empty()) {
        // The frame's number: the range's, else the frame's time (header) at the shot's rate.
        const int frame = frameHint >= 0 ? frameHint : int(std::lround(in.time * scene.fps));
        try {
            in.flow = SurfaceFlowHistory::load(historyPattern, frame, scene.params.responseTime, scene.fps,
                                               4.0 * scene.params.growthTime);
        } catch (const ParticleFileError& e) {
            throw SpikeInputError(e.what());
        }
    }
    // A mesh with velocities gets the spikes' own motion too: how their tips moved since a
    // frame interval earlier (the motion a frame's renders blur over).
    const double interval = 1.0 / scene.fps;
    SpikeInput earlier;
    const bool motion = !in.surface.velocities.empty() && earlierSpikeInput(scene, in, interval, earlier);
    SpikeResult res = addSpikes(in, scene.params, motion ? &earlier : nullptr, interval);
    TriangleMesh& out = res.mesh;
    if (!hasComment(out.comments, "magnet_count")) {
        ParticleTable header;
        header.comments = out.comments;
        writeMagnetComments(header, in.magnets, &in.fluid.law);
        out.comments = header.comments;
    }
    setComment(out, "spike_tips", std::to_string(res.tips.size()));
    setComment(out, "spike_spacing", formatDouble(res.patterns.empty() ? 0.0 : res.patterns.front().spacing));
    setComment(out, "critical_magnetization", formatDouble(res.critical.magnetization));
    // Never write a broken mesh: renderers would show garbage or silently drop it.
    for (size_t i = 0; i < out.vertices.size(); ++i)
        if (!out.vertices[i].allFinite())
            throw std::runtime_error(surfacePath + ": spiky mesh vertex " + std::to_string(i) +
                                     " is not finite (please report this input)");
    writeMesh(outPath, out);
    return res;
}

void spikeFrames(const SpikeScene& scene, const std::string& surfacePattern, const std::string& particlePattern,
                 const std::string& outPattern, int first, int last, bool quiet)
{
    if (first < 0 || last < first || last > kMaxFrame)
        throw SpikeInputError("--frames " + std::to_string(first) + ":" + std::to_string(last) +
                              ": need 0 <= FIRST <= LAST <= " + std::to_string(kMaxFrame));
    const std::vector<FramePattern> patterns = {
        {"--out", outPattern}, {"surface pattern", surfacePattern}, {"--particles", particlePattern}};
    std::mutex mutex;
    runFrames({first, last}, patterns, [&](int frame) {
        const auto start = std::chrono::steady_clock::now();
        const SpikeResult res = spikeFrame(scene, framePath(surfacePattern, frame),
                                           particlePattern.empty() ? std::string() : framePath(particlePattern, frame),
                                           framePath(outPattern, frame), frame, particlePattern);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (!quiet) {
            std::ostringstream line;
            line << "ferro-spikes: frame " << frame << ": " << res.tips.size() << " tips";
            if (!res.patterns.empty()) line << ", spacing " << res.patterns.front().spacing * 1e3 << " mm";
            line << ", " << res.mesh.triangles.size() << " triangles, volume "
                 << (res.volumeIn > 0 ? 100.0 * (res.volumeOut - res.volumeIn) / res.volumeIn : 0.0) << " %, "
                 << seconds << " s\n";
            std::lock_guard<std::mutex> lock(mutex);
            std::cerr << line.str();
        }
    });
}

} // namespace ferro
