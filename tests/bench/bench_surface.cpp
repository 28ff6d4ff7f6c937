// bench-surface: seconds per frame of ferro-surface's methods beside OpenVDB's own
// ParticlesToLevelSet + volumeToMesh, on jittered slabs of 40,960 and 1,048,576 particles,
// voxel = half the particle spacing, 2 threads (change with --threads N).
//
//   build-surface/bin/bench-surface [--threads N] [--small-only]
#include "tests/surface/SurfaceTestShapes.hpp"

#include "surface/OpenVdbParticles.hpp"
#include "surface/SurfaceExtractor.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/global_control.h>
#include <tbb/tick_count.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>

using namespace ferro;

namespace {


double best(int repeats, const std::function<void()>& f) {
    double t = 1e30;
    for (int i = 0; i < repeats; ++i) {
        const tbb::tick_count t0 = tbb::tick_count::now();
        f();
        t = std::min(t, (tbb::tick_count::now() - t0).seconds());
    }
    return t;
}

} // namespace

int main(int argc, char** argv) {
    int threads = 2;
    bool smallOnly = false;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--threads") && i + 1 < argc) threads = std::atoi(argv[++i]);
        else if (!std::strcmp(argv[i], "--small-only")) smallOnly = true;
        else {
            std::fprintf(stderr, "usage: bench-surface [--threads N] [--small-only]\n");
            return 2;
        }
    }
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(std::max(1, threads)));
    openvdb::initialize();
    const double spacing = 1.24e-3; // the dish example's
    const double voxel = spacing / 2;
    std::printf("bench-surface: jittered slab (jitter 0.15 spacing), spacing %.2f mm, voxel %.2f mm, %d threads\n",
                spacing * 1e3, voxel * 1e3, threads);
    std::printf("%10s  %-34s %8s %8s %8s %8s %8s %10s\n", "particles", "method", "total s", "kernel", "raster", "mesh",
                "velocity", "triangles");
    struct Size {
        int nx, ny, nz;
    };
    std::vector<Size> sizes = {{64, 64, 10}};
    if (!smallOnly) sizes.push_back({256, 256, 16});
    for (const Size& sz : sizes) {
        const std::vector<Vec3> x = test::jitteredSlab(sz.nx, sz.ny, sz.nz, spacing, 0.15);
        // A swirl, so that the vertex velocities (VertexVelocity.hpp) cost what a shot's do.
        std::vector<Vec3> v(x.size());
        for (size_t i = 0; i < x.size(); ++i) v[i] = Vec3(-x[i].y(), x[i].x(), 0.1f);
        const int repeats = x.size() < 100000 ? 5 : 1;
        double reference = 0;
        {
            size_t tris = 0;
            const double t = best(repeats, [&] {
                auto grid = openvdb::createLevelSet<openvdb::FloatGrid>(voxel, 3.0);
                openvdb::tools::ParticlesToLevelSet<openvdb::FloatGrid> raster(*grid);
                raster.rasterizeSpheres(ParticleList{x, spacing});
                raster.finalize(true);
                std::vector<openvdb::Vec3s> points;
                std::vector<openvdb::Vec3I> t3;
                std::vector<openvdb::Vec4I> q4;
                openvdb::tools::volumeToMesh(*grid, points, t3, q4, 0.0, 0.0);
                tris = t3.size() + 2 * q4.size();
            });
            reference = t;
            std::printf("%10zu  %-34s %8.3f %8s %8s %8s %8s %10zu\n", x.size(), "OpenVDB ParticlesToLevelSet+v2m", t, "-",
                        "-", "-", "-", tris);
        }
        for (SurfaceMethod m : {SurfaceMethod::Anisotropic, SurfaceMethod::Isotropic, SurfaceMethod::OpenVdb}) {
            SurfaceParams p;
            p.method = m;
            p.voxelSize = voxel;
            SurfaceStats st, bestSt;
            size_t tris = 0;
            double bestTotal = 1e30;
            for (int r = 0; r < repeats; ++r) {
                const tbb::tick_count t0 = tbb::tick_count::now();
                const TriangleMesh mesh = extractSurface(x, p, spacing, {}, &st, &v);
                const double t = (tbb::tick_count::now() - t0).seconds();
                if (t < bestTotal) {
                    bestTotal = t;
                    bestSt = st;
                }
                tris = mesh.triangles.size();
            }
            std::printf("%10zu  %-34s %8.3f %8.3f %8.3f %8.3f %8.3f %10zu   (%.2fx OpenVDB)\n", x.size(),
                        (std::string("ferro-surface ") + methodName(m)).c_str(), bestTotal, bestSt.kernelSeconds,
                        bestSt.rasterSeconds, bestSt.meshSeconds, bestSt.velocitySeconds, tris, bestTotal / reference);
        }
    }
    std::printf("(best of 5 runs for 40,960, one run for 1,048,576; reproduce: build-surface/bin/bench-surface --threads %d)\n",
                threads);
    return 0;
}
