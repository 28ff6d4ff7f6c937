// The table of pressure solvers: one row per solver (see sim/sph/PressureSolver.hpp).
#include "sim/sph/PressureSolver.hpp"

#include "sim/core/ParticleLoops.hpp"
#include "sim/core/SceneDocument.hpp"
#include "sim/scene/SimParams.hpp"

#include <stdexcept>

namespace ferro {

// sim/sph/WcsphSolver.cpp
std::unique_ptr<PressureSolverSettings> parseWcsphKeys(const TableReader& sim);
std::unique_ptr<PressureSolver> makeWcsphSolver(FluidSimulation& sim, const PressureSolverSettings& settings);
// sim/sph/DfsphSolver.cpp
std::unique_ptr<PressureSolverSettings> parseDfsphKeys(const TableReader& sim);
std::unique_ptr<PressureSolver> makeDfsphSolver(FluidSimulation& sim, const PressureSolverSettings& settings);

void PressureSolver::permute(const std::vector<uint32_t>& order)
{
    if (pressure_.size() == order.size()) ferro::permute(pressure_, order);
    permuteState(order);
}

const std::vector<PressureSolverEntry>& pressureSolvers()
{
    static const std::vector<PressureSolverEntry> table = {
        {"wcsph", "WCSPH", &parseWcsphKeys, &makeWcsphSolver},
        {"dfsph", "DFSPH", &parseDfsphKeys, &makeDfsphSolver},
    };
    return table;
}

std::vector<std::string> pressureSolverNames()
{
    std::vector<std::string> names;
    for (const PressureSolverEntry& e : pressureSolvers()) names.push_back(e.name);
    return names;
}

const PressureSolverEntry& findPressureSolver(const std::string& name)
{
    std::string list;
    for (const PressureSolverEntry& e : pressureSolvers()) {
        if (name == e.name) return e;
        list += (list.empty() ? "" : ", ") + std::string(e.name);
    }
    throw std::invalid_argument("unknown pressure solver '" + name + "' (one of " + list + ")");
}

const PressureSolverEntry& chosenPressureSolver(const SolverParams& p, const std::string& scenePath)
{
    try {
        return findPressureSolver(p.pressureSolver);
    } catch (const std::invalid_argument&) {
        std::string list;
        for (const std::string& name : pressureSolverNames()) list += (list.empty() ? "\"" : ", \"") + name + "\"";
        throw SceneError((p.pressureSolverWhere.empty() ? scenePath : p.pressureSolverWhere) +
                         ": sim.solver: must be one of " + list + " (got \"" + p.pressureSolver + "\")");
    }
}

std::unique_ptr<PressureSolverSettings> parsePressureSolverKeys(const SolverParams& p, const std::string& scenePath)
{
    const PressureSolverEntry& chosen = chosenPressureSolver(p, scenePath);
    static const SceneDocument none = SceneDocument::parse("", "(none)");
    const TableReader reader = (p.solverKeys ? *p.solverKeys : none).section("sim");
    std::unique_ptr<PressureSolverSettings> settings;
    for (const PressureSolverEntry& e : pressureSolvers()) {
        std::unique_ptr<PressureSolverSettings> s = e.parseKeys(reader);
        if (&e == &chosen) settings = std::move(s);
    }
    reader.finish();
    return settings;
}

} // namespace ferro
