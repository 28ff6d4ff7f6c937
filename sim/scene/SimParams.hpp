#pragma once
// Plain parameter structs of a shot, in SI units. SimSceneFile.cpp (with
// sim/magnets/MagnetScene.cpp for the magnets) is the one place that fills them from a
// TOML scene file; every default here is the documented default of
// the matching scene key (see examples/annotated.toml).
#include "sim/solids/SolidParams.hpp"
#include "sim/magnets/MagnetField.hpp"
#include "sim/magnets/MagnetizationParams.hpp"
#include "sim/core/ParticleFile.hpp"
#include "sim/geometry/ContainerParams.hpp"
#include "sim/core/Types.hpp"

#include <memory>
#include <string>
#include <vector>

namespace ferro {

class SceneDocument;

/// A region filled with fluid particles at the start of the shot ([[fluid.block]]).
struct FluidBlock {
    enum class Shape { Box, Cylinder };
    Shape shape = Shape::Box;
    Vec3d min{0, 0, 0}, max{0, 0, 0}; ///< box corners [m]
    Vec3d center{0, 0, 0};            ///< cylinder: centre of the bottom disc [m]; axis is +z
    double radius = 0;                ///< cylinder radius [m]
    double height = 0;                ///< cylinder height [m]
    Vec3d velocity{0, 0, 0};          ///< initial velocity [m/s]
    long count = 0;                   ///< exact particle count; 0 = fill at fluid.spacing
    std::string where;                ///< "file:line" of the block, for error messages
};

/// [fluid]: material of the (single) fluid.
struct FluidParams {
    double restDensity = 1000.0;  ///< rho0 [kg/m^3]
    double viscosity = 1e-6;      ///< kinematic viscosity nu [m^2/s]
    /// How viscosity enters the step (`fluid.viscosity_method`). Explicit: in the force
    /// sweep, with the viscous time step limit. Implicit: a backward Euler solve after the
    /// other forces (Weiler et al. 2018, sim/sph/ImplicitViscosity), stable at any step, so
    /// the viscous limit does not bind. Auto (default): implicit when the explicit viscous
    /// limit would be shorter than the step the scene takes otherwise (FluidSimulation).
    enum class ViscosityMethod { Explicit, Implicit, Auto };
    ViscosityMethod viscosityMethod = ViscosityMethod::Auto;
    double surfaceTension = 0.0;  ///< sigma [N/m]; 0 disables surface tension
    /// The pair-force models by their registered names (sim/sph/forces/PairForces.cpp). The
    /// parser takes any name; the simulation checks it against the table and blames the key.
    std::string viscosityModel = "standard";
    std::string viscosityModelWhere;      ///< "file:line" of fluid.viscosity_model, for that message
    std::string surfaceTensionModel = "akinci2013";
    std::string surfaceTensionModelWhere; ///< "file:line" of fluid.surface_tension_model
    double spacing = 0.0;         ///< particle spacing [m]; 0 = derived from a block's count
    std::vector<FluidBlock> blocks;
};

/// [sim]: solver settings.
struct SolverParams {
    /// Pressure solver by its registered name (sim/sph/PressureSolvers.cpp): "dfsph" or
    /// "wcsph". The scene parser takes any name; the simulation checks it against the
    /// registry and blames `pressureSolverWhere`.
    std::string pressureSolver = "dfsph";
    std::string pressureSolverWhere;  ///< "file:line" of the sim.solver key, for that message
    Vec3d gravity{0, 0, -9.81};       ///< [m/s^2]
    double cfl = 0.4;                 ///< CFL number (step <= cfl * spacing / vmax)
    double maxDt = 0.001;             ///< upper bound of the time step [s]
    double minDt = 1e-7;              ///< lower bound; a smaller step aborts the run [s]
    /// Artificial viscosity alpha, dimensionless: adds alpha * h * U to the kinematic
    /// viscosity (h the kernel support, U the flow speed scale of the scene). SPH at
    /// millimetre spacing cannot resolve the tiny physical viscosity of water or oil; this
    /// damps particle noise without depending on the time step.
    double artificialViscosity = 0.02;
    /// Implicit viscosity: relative residual |v* - (I + dt L) v| / |v*| at which the
    /// conjugate gradient solve stops, dimensionless; default 1e-3.
    double viscosityTolerance = 1e-3;
    int viscosityMaxIterations = 100; ///< implicit viscosity: iteration cap of each solve
    int threads = 0;                  ///< worker threads; 0 = all cores
    /// Speed [m/s] beyond which the sanity guard stops the run (exit 3); 0 = derived from
    /// the scene's energy sources (sim/sph/SanityGuard.hpp). For scenes that drive the
    /// fluid by means the derived bound does not know.
    double maxSpeed = 0.0;
    /// The [sim] keys that belong to the chosen pressure solver (sim.max_density_error,
    /// sim.sound_speed, ...): every [sim] key the parser above does not read, as the scene
    /// set them. Each solver's registry row reads its own from here, with their defaults and
    /// checks (sim/sph/PressureSolver.hpp), so a new solver's keys need no line in this file.
    /// Null = none set (every default).
    std::shared_ptr<const SceneDocument> solverKeys;
};

/// [shot]: timing of the output.
struct ShotParams {
    double fps = 30.0;                ///< output frames per second [1/s]
    double duration = 1.0;            ///< simulated time [s]
    /// Pre-roll [s], >= 0: before frame 0 the scene's initial state is simulated for at most
    /// this long with every magnet held as it is at t = 0, so the shot starts from a settled
    /// fluid instead of a released block. 0 = none (frame 0 is the initial fill).
    double preroll = 0.0;
    /// The pre-roll stops early once the RMS particle speed is below this [m/s] (checked
    /// once per frame interval, after the fluid has had time to fall the container's
    /// height); 0 = always run the whole pre-roll.
    double prerollRestSpeed = 1e-3;
    /// What each particle file holds. Full: the whole state as floats (x, v, density,
    /// pressure, H, M: 56 bytes a particle), every frame a point to resume from. Compact:
    /// what the later stages read, x as floats and v, density and M quantized to 16 bits
    /// (ParticleTable::quantized: 26 bytes a particle, an error up to 1.5e-5 of each column's
    /// largest value in the frame), and every `fullEvery`-th frame and the last one full, so
    /// that ferro-sim --resume goes back at most that many frames.
    enum class ParticleCache { Full, Compact };
    ParticleCache particleCache = ParticleCache::Full;
    int fullEvery = 10;               ///< with Compact: every this many frames a full one, >= 1
    /// Whether frame `frame` of a shot whose last frame is `last` is written in full.
    bool fullFrame(int frame, int last) const {
        return particleCache == ParticleCache::Full || frame % fullEvery == 0 || frame == last;
    }
    /// Frames after frame 0, rounded; at most kMaxFrame (the parser refuses longer shots),
    /// so the cast never overflows an int whatever the fields hold.
    int frameCount() const {
        const double n = duration * fps + 0.5;
        return n >= 0 && n < kMaxFrame ? static_cast<int>(n) : n >= kMaxFrame ? kMaxFrame : 0;
    }
};

/// Everything ferro-sim needs to run a shot.
struct SimScene {
    std::string path;                 ///< scene file it came from
    ShotParams shot;
    FluidParams fluid;
    ContainerParams container;
    SolverParams solver;
    std::vector<MagnetTrack> magnets;   ///< [[magnets]], each with optional [[magnets.keys]]
    MagnetizationParams magnetization;  ///< [magnetization]
    std::vector<SolidParams> solids;    ///< [[solids]]: magnetizable solids, walls to the fluid
};

} // namespace ferro
