// bench-heap-profile: the heap profile of a settled pool from one particle file, and its error
// against a reference run's file (scripts/bench/sim.sh, scripts/bench/magnetics.sh).
//
//   build/bin/bench-heap-profile FILE [--ref REF_FILE] [--bins 20] [--rmax R] [--width W]
//                                [--centre X,Y] [--base FILE0 --ref-base REF0] [--summary]
//
// The surface height is measured as the fluid's column height h(r): the particles' volume
// (particle_mass / rest_density each, from the file's comments; spacing^3 without them) per unit floor
// area, smoothed by a 2-D Gaussian of a fixed physical width W (default 2.5 mm) and averaged
// over 32 directions around the centre. Column height, not the top particle's z: it does not
// depend on how the surface layer of particles sits (half a spacing below the free surface,
// with a different spacing at each particle count), so runs at 10k and 164k particles compare
// directly; its bias is the fluid's compression (a 1 % denser fluid stands 1 % lower), which is
// a real error of the run. W is the same for every run, so the smoothing cancels in the
// differences. Bins: `bins` radii from 0 to rmax (default 0.9 x the largest particle radius
// minus 2 W, clear of the wall and its meniscus).
//
// Prints the profile (r, h) and a summary: centre height h(0) (the settled surface height over
// the magnet), edge height h(rmax), rise = h(0) - h(rmax), RMS and largest particle speed.
// With --ref: the profile error (RMS and largest |h - h_ref| over the bins), the centre height
// error and the rise error relative to the reference rise. With --base and --ref-base (each
// run's initial frame) also the error of the heap itself, the displacement profile
// h(r) - h_initial(r) against the reference's (heap_rms_err_m, heap_max_err_m): runs at
// different particle counts start from fills that hold slightly different volumes (a coarse
// fill stays further from the walls), and this error leaves that offset out. --summary prints
// only one line of key=value pairs (what the scripts parse).
#include "sim/core/Constants.hpp"
#include "sim/core/ParticleFile.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

using namespace ferro;

namespace {

struct Profile {
    std::vector<double> r, h;
    double rmsSpeed = 0, maxSpeed = 0, spacing = 0, time = 0;
    size_t count = 0;
};

struct Options {
    int bins = 20;
    double rmax = 0, width = 2.5e-3, cx = 0, cy = 0;
};

Profile profileOf(const std::string& path, Options& opt) {
    const ParticleTable t = readParticleFile(path);
    Profile p;
    p.spacing = t.commentNumber("spacing", 0);
    const double mass = t.commentNumber("particle_mass", 0), rho0 = t.commentNumber("rest_density", 0);
    p.time = t.commentNumber("time", 0);
    if (!(p.spacing > 0)) throw std::runtime_error(path + ": no `spacing` comment (not a ferro-sim particle file)");
    const std::vector<Vec3> x = t.vec3("x", "y", "z");
    p.count = x.size();
    if (x.empty()) throw std::runtime_error(path + ": no particles");
    if (t.column("vx") >= 0) {
        const std::vector<Vec3> v = t.vec3("vx", "vy", "vz");
        double s2 = 0;
        for (const Vec3& u : v) {
            s2 += double(u.squaredNorm());
            p.maxSpeed = std::max(p.maxSpeed, double(u.norm()));
        }
        p.rmsSpeed = std::sqrt(s2 / double(v.size()));
    }
    if (opt.rmax <= 0) {
        double rOut = 0;
        for (const Vec3& q : x) rOut = std::max(rOut, std::hypot(q.x() - opt.cx, q.y() - opt.cy));
        opt.rmax = 0.9 * rOut - 2 * opt.width;
        if (opt.rmax <= 0) throw std::runtime_error(path + ": the pool is narrower than the smoothing width");
    }
    // A particle's share of the fluid's volume: mass / rest density (= spacing^3 for a fill).
    const double volume = mass > 0 && rho0 > 0 ? mass / rho0 : std::pow(p.spacing, 3);
    const double w2 = opt.width * opt.width;
    const double norm = volume / (2 * kPi * w2);
    const int directions = 32;
    for (int b = 0; b < opt.bins; ++b) {
        const double r = opt.bins == 1 ? 0 : opt.rmax * b / (opt.bins - 1);
        double sum = 0;
        for (int d = 0; d < directions; ++d) {
            const double a = 2 * kPi * d / directions;
            const double ex = opt.cx + r * std::cos(a), ey = opt.cy + r * std::sin(a);
            for (const Vec3& q : x) {
                const double dx = q.x() - ex, dy = q.y() - ey, d2 = dx * dx + dy * dy;
                if (d2 < 25 * w2) sum += norm * std::exp(-0.5 * d2 / w2);
            }
        }
        p.r.push_back(r);
        p.h.push_back(sum / directions);
    }
    return p;
}

int usage() {
    std::fprintf(stderr, "usage: bench-heap-profile FILE [--ref REF_FILE] [--bins N] [--rmax R] [--width W] "
                         "[--centre X,Y] [--base FILE0 --ref-base REF0] [--summary]\n");
    return 2;
}

} // namespace

int main(int argc, char** argv) {
    Options opt;
    std::string file, ref, base, refBase;
    bool summary = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool more = i + 1 < argc;
        if (a == "--summary") summary = true;
        else if (a == "--ref" && more) ref = argv[++i];
        else if (a == "--base" && more) base = argv[++i];
        else if (a == "--ref-base" && more) refBase = argv[++i];
        else if (a == "--bins" && more) opt.bins = std::atoi(argv[++i]);
        else if (a == "--rmax" && more) opt.rmax = std::atof(argv[++i]);
        else if (a == "--width" && more) opt.width = std::atof(argv[++i]);
        else if (a == "--centre" && more) {
            if (std::sscanf(argv[++i], "%lf,%lf", &opt.cx, &opt.cy) != 2) return usage();
        } else if (!a.empty() && a[0] != '-' && file.empty()) file = a;
        else return usage();
    }
    if (file.empty() || opt.bins < 1 || !(opt.width > 0)) return usage();
    if (base.empty() != refBase.empty() || (!base.empty() && ref.empty())) return usage();
    try {
        // The reference fixes rmax, so both profiles are sampled at the same radii.
        Profile pr;
        if (!ref.empty()) pr = profileOf(ref, opt);
        const Profile p = profileOf(file, opt);
        const double centre = p.h.front(), edge = p.h.back(), rise = centre - edge;
        if (!summary) {
            std::printf("# %s: %zu particles, spacing %.4g m, t = %.4g s, smoothing width %.3g m\n", file.c_str(),
                        p.count, p.spacing, p.time, opt.width);
            std::printf("%12s %14s%s\n", "r_m", "height_m", ref.empty() ? "" : "   ref_height_m");
            for (size_t b = 0; b < p.r.size(); ++b) {
                if (ref.empty()) std::printf("%12.5f %14.6f\n", p.r[b], p.h[b]);
                else std::printf("%12.5f %14.6f %16.6f\n", p.r[b], p.h[b], pr.h[b]);
            }
        }
        std::printf("particles=%zu spacing_m=%.6g time_s=%.6g centre_height_m=%.6g edge_height_m=%.6g rise_m=%.6g "
                    "rms_speed_m_s=%.4g max_speed_m_s=%.4g",
                    p.count, p.spacing, p.time, centre, edge, rise, p.rmsSpeed, p.maxSpeed);
        if (!ref.empty()) {
            double s2 = 0, worst = 0;
            for (size_t b = 0; b < p.h.size(); ++b) {
                const double d = p.h[b] - pr.h[b];
                s2 += d * d;
                worst = std::max(worst, std::abs(d));
            }
            const double refRise = pr.h.front() - pr.h.back();
            std::printf(" profile_rms_err_m=%.4g profile_max_err_m=%.4g centre_err_m=%.4g ref_rise_m=%.6g "
                        "rise_err_rel=%.4g",
                        std::sqrt(s2 / double(p.h.size())), worst, centre - pr.h.front(), refRise,
                        refRise != 0 ? (rise - refRise) / std::abs(refRise) : 0.0);
            if (!base.empty()) {
                const Profile p0 = profileOf(base, opt), pr0 = profileOf(refBase, opt);
                double h2 = 0, hWorst = 0;
                for (size_t b = 0; b < p.h.size(); ++b) {
                    const double d = (p.h[b] - p0.h[b]) - (pr.h[b] - pr0.h[b]);
                    h2 += d * d;
                    hWorst = std::max(hWorst, std::abs(d));
                }
                std::printf(" initial_centre_height_m=%.6g heap_rms_err_m=%.4g heap_max_err_m=%.4g", p0.h.front(),
                            std::sqrt(h2 / double(p.h.size())), hWorst);
            }
        }
        std::printf("\n");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench-heap-profile: %s\n", e.what());
        return 4;
    }
    return 0;
}
