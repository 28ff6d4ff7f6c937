// bench-spikes: seconds per frame and output triangles of ferro-spikes on a Fig. 9-like frame:
// the dish of examples/paper_fig9_approach.toml at its strongest field (magnet held 2 cm under
// the floor, t = 2 s), a 40,960-particle fluid body heaped 3 mm over the magnet, its surface
// triangulated like a Yu-Turk mesh at half the particle spacing (about 0.6 mm edges), particles
// magnetized by the fluid's law in the magnet's field. The whole frame is timed as the command
// runs it: read mesh and particles, build the particle-field tree, trace, remesh, displace,
// conserve volume, write.
//     bench-spikes [threads=2] [repeats=3] [scene=examples/paper_fig9_approach.toml]
#include "tests/spikes/SpikeTestMeshes.hpp"
#include "sim/core/Constants.hpp"

#include "sim/magnets/MagnetState.hpp"
#include "sim/magnetics/MagnetizationSolver.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/core/SceneDocument.hpp"
#include "spikes/SpikeFrames.hpp"
#include "spikes/SurfaceGeometry.hpp"

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>

using namespace ferro;

int main(int argc, char** argv)
{
    const int threads = argc > 1 ? std::atoi(argv[1]) : 2;
    const int repeats = argc > 2 ? std::atoi(argv[2]) : 3;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(std::max(1, threads)));
    // Benchmarks get no FERRO_SOURCE_DIR: the repository is three levels above this file.
    const std::string scenePath =
        argc > 3 ? std::string(argv[3])
                 : (std::filesystem::path(__FILE__).parent_path().parent_path().parent_path() / "examples" /
                    "paper_fig9_approach.toml")
                       .string();
    SpikeScene scene = parseSpikeScene(SceneDocument::load(scenePath));
    const double time = 2.0;
    std::vector<Magnet> magnets;
    for (const MagnetTrack& t : scene.magnets) magnets.push_back(t.at(time));

    const double R = 0.0495, depth = 0.01, mound = 0.003, width = 0.015;
    auto height = [&](double r, double) { return depth + mound * std::exp(-r * r / (2 * width * width)); };
    TriangleMesh surface = spiketest::makePool(R, 80, height);
    surface.comments = {{"frame", "60"}, {"time", "2"}};

    // 40,960 particles filling the heaped body, jittered lattice.
    const double volume = enclosedVolume(surface);
    const double h = std::cbrt(volume / 40960.0);
    ParticleTable particles;
    particles.names = {"x", "y", "z", "vx", "vy", "vz", "density", "hx", "hy", "hz", "mx", "my", "mz"};
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> jitter(-0.1 * h, 0.1 * h);
    for (double x = -R + h / 2; x < R; x += h)
        for (double y = -R + h / 2; y < R; y += h) {
            const double r = std::hypot(x, y);
            if (r > R - h / 2) continue;
            for (double z = h / 2; z < height(r, 0) - h / 4; z += h) {
                const Vec3d p(x + jitter(rng), y + jitter(rng), z + jitter(rng));
                const Vec3d H = magnetField(magnets, p);
                const Vec3d M = H.normalized() * langevinMagnetization(H.norm(), scene.fluid.law.susceptibility, scene.fluid.law.saturation);
                for (double v : {p.x(), p.y(), p.z(), 0.0, 0.0, 0.0, 1200.0, H.x(), H.y(), H.z(), M.x(), M.y(), M.z()})
                    particles.values.push_back(float(v));
            }
        }
    particles.comments = {{"frame", "60"}, {"time", "2"}};
    particles.setComment("spacing", std::to_string(h));
    writeMagnetComments(particles, magnets, &scene.fluid.law);

    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "ferro_bench_spikes";
    std::filesystem::create_directories(dir);
    const std::string meshPath = (dir / "surface.ply").string(), particlePath = (dir / "particles.ply").string(),
                      outPath = (dir / "spiky.ply").string();
    writeMesh(meshPath, surface);
    writeParticleFile(particlePath, particles);

    std::printf("bench-spikes: Fig. 9-like frame, %zu particles, input %zu triangles, %d thread(s)\n",
                particles.rows(), surface.triangles.size(), threads);
    for (bool particleField : {true, false}) {
        scene.params.particleField = particleField;
        double total = 0;
        SpikeResult res;
        for (int i = 0; i < repeats; ++i) {
            const auto start = std::chrono::steady_clock::now();
            res = spikeFrame(scene, meshPath, particlePath, outPath, 60);
            total += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
        std::printf("  particle field %-3s: %.3f s/frame, %zu output triangles, %zu tips, spacing %.2f mm, "
                    "|H(x0)| %.0f A/m, |M(x0)| %.0f A/m (M_c %.0f), max tip %.2f mm, volume change %+.4f %%\n",
                    particleField ? "on" : "off", total / repeats, res.mesh.triangles.size(), res.tips.size(),
                    res.patterns.empty() ? 0.0 : res.patterns[0].spacing * 1e3,
                    res.patterns.empty() ? 0.0 : res.patterns[0].field,
                    res.patterns.empty() ? 0.0 : res.patterns[0].magnetization, res.critical.magnetization,
                    res.maxHeight * 1e3, 100 * (res.volumeOut - res.volumeIn) / res.volumeIn);
        double tilt = 0;
        for (const SpikeTip& t : res.tips)
            tilt = std::max(tilt, std::acos(std::min(1.0, t.direction.z())) * 180 / kPi);
        std::printf("    largest tip tilt from vertical %.1f deg\n", tilt);
        const MeshHealth health = checkMeshHealth(res.mesh);
        std::printf("    output mesh: %s, %s, %s\n", health.loadable ? "manifold" : "NOT manifold",
                    health.closed ? "closed" : "NOT closed",
                    health.selfIntersecting ? "SELF-INTERSECTING" : "no self-intersections");
    }
    std::printf("reproduce: cmake --build build-spikes --target bench-spikes && build-spikes/bin/bench-spikes %d %d\n",
                threads, repeats);
    std::printf("output mesh: %s\n", outPath.c_str());
    return 0;
}
