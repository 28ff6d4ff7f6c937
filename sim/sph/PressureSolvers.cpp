// The table of pressure solvers: one row per solver (see sim/sph/PressureSolver.hpp).
#include "sim/sph/PressureSolver.hpp"

#include <stdexcept>

namespace ferro {

std::unique_ptr<PressureSolver> makeWcsphSolver(FluidSimulation& sim); // sim/sph/WcsphSolver.cpp
std::unique_ptr<PressureSolver> makeDfsphSolver(FluidSimulation& sim); // sim/sph/DfsphSolver.cpp

const std::vector<PressureSolverEntry>& pressureSolvers()
{
    static const std::vector<PressureSolverEntry> table = {
        {"wcsph", "WCSPH", &makeWcsphSolver},
        {"dfsph", "DFSPH", &makeDfsphSolver},
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

} // namespace ferro
