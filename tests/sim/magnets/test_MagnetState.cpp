// The magnets in a particle file's header (sim/magnets/MagnetState.hpp): every kind
// survives writeMagnetComments -> particle file -> readMagnetComments to the printed 9
// significant digits, and every malformed header is a one-line ParticleFileError.
#include "sim/magnets/MagnetState.hpp"

#include <catch2/catch.hpp>

#include <filesystem>
#include <string>
#include <vector>

using namespace ferro;
namespace fs = std::filesystem;

namespace {

std::vector<Magnet> oneOfEachKind() {
    std::vector<Magnet> m(4);
    m[0].kind = Magnet::Kind::Dipole;
    m[0].position = Vec3d(0.0123456789, -0.5, 1e-7);
    m[0].direction = Vec3d(0, 0, 2);            // written normalized: (0, 0, 1)
    m[0].strength = 0.5;
    m[0].softening = 0.002;
    m[1].kind = Magnet::Kind::Bar;
    m[1].position = Vec3d(-1, 2, -3);
    m[1].direction = Vec3d(1, 1, 0);
    m[1].strength = 1234.5678912;
    m[1].length = 0.05;
    m[2].kind = Magnet::Kind::Uniform;
    m[2].direction = Vec3d(0.3, -0.4, 0.866);
    m[2].strength = 20000;
    m[3].kind = Magnet::Kind::Loop;
    m[3].position = Vec3d(0.1, 0.2, 0.3);
    m[3].direction = Vec3d(0, -1, 0);
    m[3].strength = -7.25;
    m[3].radius = 0.04;
    m[3].softening = 1e-3;
    return m;
}

void requireSame(const Magnet& a, const Magnet& b) {
    const double tol = 1e-8; // 9 significant digits
    REQUIRE(a.kind == b.kind);
    for (int k = 0; k < 3; ++k) {
        REQUIRE(a.position[k] == Approx(b.position[k]).epsilon(tol).margin(1e-15));
        REQUIRE(a.direction[k] == Approx(b.direction.normalized()[k]).epsilon(tol).margin(1e-15));
    }
    REQUIRE(a.strength == Approx(b.strength).epsilon(tol));
    REQUIRE(a.length == Approx(b.length).epsilon(tol));
    REQUIRE(a.radius == Approx(b.radius).epsilon(tol));
    REQUIRE(a.softening == Approx(b.softening).epsilon(tol));
}

ParticleTable withComments(std::vector<std::pair<std::string, std::string>> comments) {
    ParticleTable t;
    t.comments = std::move(comments);
    return t;
}

std::string errorOf(const ParticleTable& t) {
    try {
        readMagnetComments(t);
    } catch (const ParticleFileError& e) {
        return e.what();
    }
    FAIL("no ParticleFileError");
    return "";
}

} // namespace

TEST_CASE("every magnet kind round-trips through the particle file header", "[magnets][state]") {
    REQUIRE(std::string(magnetKindName(Magnet::Kind::Dipole)) == "dipole");
    REQUIRE(std::string(magnetKindName(Magnet::Kind::Bar)) == "bar");
    REQUIRE(std::string(magnetKindName(Magnet::Kind::Uniform)) == "uniform");
    REQUIRE(std::string(magnetKindName(Magnet::Kind::Loop)) == "loop");

    const std::vector<Magnet> magnets = oneOfEachKind();
    MagnetizationParams law;
    law.susceptibility = 2.5;
    law.saturation = 30000;
    ParticleTable table;
    table.names = {"x", "y", "z"};
    table.values = {1, 2, 3};
    writeMagnetComments(table, magnets, &law);
    REQUIRE(table.comments.size() == 1 + magnets.size() + 2);
    REQUIRE(table.comments[0] == std::pair<std::string, std::string>("magnet_count", "4"));
    REQUIRE(table.comments[5] == std::pair<std::string, std::string>("susceptibility", "2.5"));
    REQUIRE(table.comments[6] == std::pair<std::string, std::string>("saturation", "30000"));

    // In memory and through a file.
    const fs::path dir = fs::path(FERRO_BINARY_DIR) / "test-scratch" / "magnet_state";
    fs::create_directories(dir);
    writeParticleFile((dir / "m.ply").string(), table);
    for (const ParticleTable& t : {table, readParticleFile((dir / "m.ply").string())}) {
        const std::vector<Magnet> back = readMagnetComments(t);
        REQUIRE(back.size() == magnets.size());
        for (size_t i = 0; i < magnets.size(); ++i) {
            CAPTURE(i);
            requireSame(back[i], magnets[i]);
        }
    }
    // No magnets: a count of 0, and a header without any magnet lines at all.
    ParticleTable none;
    writeMagnetComments(none, {});
    REQUIRE(readMagnetComments(none).empty());
    REQUIRE(readMagnetComments(ParticleTable{}).empty());
}

TEST_CASE("a malformed magnet header is a one-line ParticleFileError", "[magnets][state]") {
    const std::vector<std::pair<std::string, std::vector<std::pair<std::string, std::string>>>> cases = {
        {"'comment magnet dipole 0 0 0 0 0 1 0.5 0 0'", {{"magnet_count", "1"}, {"magnet", "dipole 0 0 0 0 0 1 0.5 0 0"}}},
        {"'comment magnet dipole 0 0 x 0 0 1 0.5 0 0 0'", {{"magnet", "dipole 0 0 x 0 0 1 0.5 0 0 0"}}},
        {"'comment magnet '", {{"magnet", ""}}},
        {"unknown magnet kind 'horseshoe'", {{"magnet", "horseshoe 0 0 0 0 0 1 0.5 0 0 0"}}},
        {"magnet_count 2 but lists 1", {{"magnet_count", "2"}, {"magnet", "bar 0 0 0 0 0 1 1 0.1 0 0"}}},
        {"magnet_count 0 but lists 1", {{"magnet", "loop 0 0 0 0 0 1 1 0 0.1 0"}, {"magnet_count", "0"}}},
        // Values the scene refuses (fuzz finding: the header took them, the field overflowed).
        {"(moment must be within +-1e+06 A m^2 for a dipole magnet)", {{"magnet", "dipole 0 0 0 0 0 1 1e30 0 0 0"}}},
        {"(length must be > 0)", {{"magnet", "bar 0 0 0 0 0 1 1 0 0 0"}}},
        {"(radius must be > 0)", {{"magnet", "loop 0 0 0 0 0 1 1 0 -0.1 0"}}},
        {"(softening must be >= 0)", {{"magnet", "dipole 0 0 0 0 0 1 1 0 0 -1"}}},
    };
    for (const auto& [expected, comments] : cases) {
        const std::string what = errorOf(withComments(comments));
        CAPTURE(what, expected);
        REQUIRE(what.find(expected) != std::string::npos);
        REQUIRE(what.find('\n') == std::string::npos);
    }
}
