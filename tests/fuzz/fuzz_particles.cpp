// Fuzz target: the particle PLY reader (readParticleFile), as every stage reads particles.
//
// Input encoding: the input is the file's bytes, read from a scratch file `input.ply`.
//
// The documented error is ParticleFileError (one line naming the file). A table it returns
// is consistent: as many values as rows times columns, one name per column.
#include "tests/fuzz/FuzzTarget.hpp"

#include "sim/core/ParticleFile.hpp"

using namespace ferro;
using ferro::fuzz::finding;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = fuzz::writeInput("input.ply", data, size);
    ParticleTable t;
    try {
        t = readParticleFile(path);
    } catch (const ParticleFileError& e) {
        fuzz::requireOneLine(e);
        return 0;
    }
    if (t.columns() == 0 ? !t.values.empty() : t.values.size() != t.rows() * t.columns())
        finding(std::to_string(t.values.size()) + " values for " + std::to_string(t.columns()) + " columns");
    for (const std::string& name : t.names) (void)t.column(name);
    return 0;
}
