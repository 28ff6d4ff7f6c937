// sim/core/StageErrors: exit codes carried by the errors, the readable-input probe and the
// guard that keeps a stage from writing onto its own input.
#include "sim/core/StageErrors.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <filesystem>

using namespace ferro;
using ferro::test::TempDir;
using ferro::test::spit;

TEST_CASE("stage errors carry the exit code of the one table", "[core]") {
    CHECK(InputMissingError("x").code() == kExitIoError);
    CHECK(InputMissingError("x").code() == 4);
    CHECK(BadInputError("x").code() == kExitBadInput);
    CHECK(BadInputError("x").code() == 2);
    CHECK(StageError(kExitSimulationFailed, "x").code() == 3);
}

TEST_CASE("requireReadable names the file and why it cannot be opened", "[core]") {
    TempDir dir("stage-errors");
    const std::string file = (dir.path / "a.ply").string();
    spit(file, "ply\n");
    CHECK_NOTHROW(requireReadable(file));
    try {
        requireReadable((dir.path / "missing.ply").string());
        FAIL("a missing file was accepted");
    } catch (const InputMissingError& e) {
        CHECK(std::string(e.what()) == (dir.path / "missing.ply").string() + ": cannot open: No such file or directory");
    }
    try {
        requireReadable(dir.path.string());
        FAIL("a directory was accepted");
    } catch (const InputMissingError& e) {
        CHECK(std::string(e.what()) == dir.path.string() + ": cannot open: is a directory");
    }
}

TEST_CASE("an output that names an input is refused, whatever the spelling", "[core]") {
    TempDir dir("stage-errors");
    const std::filesystem::path in = dir.path / "particles_0001.ply";
    spit(in, "ply\n");
    const std::string inText = in.string();
    // The same path, the same path spelt with ./ and .., and a hard link to it.
    CHECK_THROWS_AS(refuseToOverwriteInputs("--out", inText, {inText}), BadInputError);
    const std::string dotted = (dir.path / "." / "sub" / ".." / "particles_0001.ply").string();
    CHECK_THROWS_AS(refuseToOverwriteInputs("--out", dotted, {inText}), BadInputError);
    const std::filesystem::path link = dir.path / "link.ply";
    std::filesystem::create_hard_link(in, link);
    CHECK_THROWS_AS(refuseToOverwriteInputs("--out", link.string(), {"", inText}), BadInputError);
    try {
        refuseToOverwriteInputs("--out", inText, {inText});
    } catch (const BadInputError& e) {
        CHECK(std::string(e.what()) == "--out '" + inText + "' is the input '" + inText + "': refusing to overwrite it");
    }
    // Other files, and a missing output, are fine.
    CHECK_NOTHROW(refuseToOverwriteInputs("--out", (dir.path / "surface_0001.ply").string(), {inText}));
    CHECK_NOTHROW(refuseToOverwriteInputs("--out", "", {inText}));
}
