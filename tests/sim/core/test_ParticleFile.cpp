// Particle files: bit-exact round trip, header layout, an independent reader (assimp),
// the tolerant reader (ascii, big-endian, mixed types), error messages and atomic writes.
#include "sim/core/ParticleFile.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <assimp/Importer.hpp>
#include <assimp/scene.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>

using namespace ferro;
using namespace ferro::test;
namespace fs = std::filesystem;

namespace {

ParticleTable sampleTable(size_t rows, unsigned seed = 7) {
    ParticleTable t;
    t.names = {"x", "y", "z", "vx", "vy", "vz", "density"};
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    t.values.resize(rows * t.names.size());
    for (float& v : t.values) v = u(rng);
    if (rows > 0) {
        // Values whose bits a text or double detour would not preserve.
        t.values[0] = -0.0f;
        t.values[1] = std::numeric_limits<float>::denorm_min();
        t.values[2] = std::numeric_limits<float>::max();
        t.values[3] = 0.1f;
    }
    t.comments = {{"frame", "12"}, {"time", "0.4"}, {"note", "two  spaced words"}, {"empty", ""}};
    return t;
}

std::string errorOf(const std::string& path) {
    try {
        readParticleFile(path);
    } catch (const ParticleFileError& e) {
        return e.what();
    }
    return "(no error)";
}

template <typename T>
void putBigEndian(std::string& out, T value) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    for (size_t i = 0; i < sizeof(T); ++i) out.push_back(char(b[sizeof(T) - 1 - i]));
}

} // namespace

TEST_CASE("particle file round trip is bit-exact and keeps comments", "[io]") {
    TempDir dir("io");
    const std::string path = dir.file("frame.ply");
    const ParticleTable t = sampleTable(1000);
    writeParticleFile(path, t);

    const ParticleTable r = readParticleFile(path);
    CHECK(r.names == t.names);
    CHECK(r.comments == t.comments);
    REQUIRE(r.rows() == 1000);
    REQUIRE(r.values.size() == t.values.size());
    CHECK(std::memcmp(r.values.data(), t.values.data(), t.values.size() * sizeof(float)) == 0);
    CHECK(r.comment("note") == "two  spaced words");
    CHECK(r.commentNumber("time", -1) == Approx(0.4));

    // Header layout: exact lines, then exactly rows * columns float32 values.
    const std::string bytes = slurp(path);
    const std::string header = "ply\nformat binary_little_endian 1.0\n"
                               "comment frame 12\ncomment time 0.4\ncomment note two  spaced words\n"
                               "comment empty\nelement vertex 1000\n"
                               "property float x\nproperty float y\nproperty float z\n"
                               "property float vx\nproperty float vy\nproperty float vz\n"
                               "property float density\nend_header\n";
    REQUIRE(bytes.compare(0, header.size(), header) == 0);
    CHECK(bytes.size() == header.size() + 1000 * 7 * 4);
    // Little-endian float32 regardless of the host: decode one value by hand.
    const auto* p = reinterpret_cast<const unsigned char*>(bytes.data() + header.size() + 3 * 4);
    const uint32_t bits = uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
    float decoded;
    std::memcpy(&decoded, &bits, 4);
    CHECK(decoded == 0.1f);
}

TEST_CASE("particle files are readable by assimp's PLY importer", "[io]") {
    TempDir dir("io");
    const std::string path = dir.file("cloud.ply");
    ParticleTable t = sampleTable(500, 11);
    t.values[2] = 0.5f; // keep every coordinate finite and modest for the importer
    writeParticleFile(path, t);

    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(path, 0);
    INFO(importer.GetErrorString());
    REQUIRE(scene != nullptr);
    REQUIRE(scene->mNumMeshes >= 1);
    const aiMesh* mesh = scene->mMeshes[0];
    REQUIRE(mesh->mNumVertices == 500);
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
        CHECK(mesh->mVertices[i].x == t.at(i, 0));
        CHECK(mesh->mVertices[i].y == t.at(i, 1));
        CHECK(mesh->mVertices[i].z == t.at(i, 2));
    }
}

TEST_CASE("large particle files round trip", "[io]") {
    TempDir dir("io");
    const std::string path = dir.file("big.ply");
    ParticleTable t = sampleTable(200000, 3);
    t.names.insert(t.names.end(), {"hx", "hy", "hz", "mx", "my", "mz"});
    t.values.resize(200000 * 13, 0.25f);
    writeParticleFile(path, t);
    const ParticleTable r = readParticleFile(path);
    REQUIRE(r.rows() == 200000);
    CHECK(std::memcmp(r.values.data(), t.values.data(), t.values.size() * sizeof(float)) == 0);
    CHECK(r.vec3("hx", "hy", "hz").size() == 200000);
}

TEST_CASE("broken particle files give one-line errors naming the file", "[io]") {
    TempDir dir("io");
    const std::string path = dir.file("frame.ply");
    writeParticleFile(path, sampleTable(1000));

    SECTION("truncated") {
        fs::resize_file(path, fs::file_size(path) - 10);
        CHECK(errorOf(path) == path + ": truncated (expected 1000 vertices)");
    }
    SECTION("truncated inside the header") {
        fs::resize_file(path, 40);
        CHECK(errorOf(path).rfind(path + ": bad PLY header", 0) == 0);
    }
    SECTION("garbage") {
        std::string junk(4096, '\0');
        std::mt19937 rng(5);
        for (char& c : junk) c = char(rng());
        spit(path, junk);
        CHECK(errorOf(path) == path + ": not a PLY file");
    }
    SECTION("empty") {
        spit(path, "");
        CHECK(errorOf(path) == path + ": not a PLY file");
    }
    SECTION("missing") {
        CHECK(errorOf(dir.file("nope.ply")) == dir.file("nope.ply") + ": cannot open");
    }
    SECTION("list property in the vertex element") {
        spit(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                         "property list uchar int idx\nend_header\n1 0\n");
        CHECK(errorOf(path).find("list property") != std::string::npos);
    }
    SECTION("first element is not vertex") {
        spit(path, "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int idx\n"
                         "element vertex 1\nproperty float x\nend_header\n1\n");
        CHECK(errorOf(path).find("not 'vertex'") != std::string::npos);
    }
    SECTION("ascii with too few values") {
        spit(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                         "property float y\nend_header\n1 2\n3 4\n5\n");
        CHECK(errorOf(path) == path + ": truncated (expected 3 vertices)");
    }
    SECTION("ascii with a bad number") {
        spit(path, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\nabc\n");
        CHECK(errorOf(path).find("bad ascii value") != std::string::npos);
    }
}

TEST_CASE("ascii PLY with mixed types, obj_info and a later element", "[io]") {
    TempDir dir("io");
    const std::string path = dir.file("ascii.ply");
    spit(path, "ply\r\nformat ascii 1.0\r\ncomment frame 3\r\nobj_info made by hand\r\n"
                     "element vertex 3\r\nproperty float x\r\nproperty double y\r\nproperty int z\r\n"
                     "property uchar flag\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\n"
                     "end_header\r\n1.5 2.25 -3 255\r\n-0.5 1e-3 7 0\r\n+2 -inf 0 1\r\n3 0 1 2\r\n");
    const ParticleTable t = readParticleFile(path);
    REQUIRE(t.names == std::vector<std::string>{"x", "y", "z", "flag"});
    REQUIRE(t.rows() == 3);
    CHECK(t.comments == std::vector<std::pair<std::string, std::string>>{{"frame", "3"}});
    CHECK(t.commentNumber("frame", 0) == 3);
    CHECK(t.at(0, 0) == 1.5f);
    CHECK(t.at(0, 1) == 2.25f);
    CHECK(t.at(0, 2) == -3.0f);
    CHECK(t.at(0, 3) == 255.0f);
    CHECK(t.at(1, 1) == 1e-3f);
    CHECK(t.at(2, 0) == 2.0f);
    CHECK(t.at(2, 1) == -std::numeric_limits<float>::infinity());
}

TEST_CASE("big-endian binary PLY with every scalar type", "[io]") {
    TempDir dir("io");
    const std::string path = dir.file("be.ply");
    std::string bytes = "ply\nformat binary_big_endian 1.0\nelement vertex 2\n"
                        "property char a\nproperty uint8 b\nproperty short c\nproperty ushort d\n"
                        "property int32 e\nproperty uint f\nproperty float32 g\nproperty float64 h\n"
                        "element face 0\nproperty list uchar int vertex_indices\nend_header\n";
    for (int row = 0; row < 2; ++row) {
        const int s = row == 0 ? 1 : -1;
        putBigEndian<int8_t>(bytes, int8_t(-5 * s));
        putBigEndian<uint8_t>(bytes, 200);
        putBigEndian<int16_t>(bytes, int16_t(-300 * s));
        putBigEndian<uint16_t>(bytes, 60000);
        putBigEndian<int32_t>(bytes, -70000 * s);
        putBigEndian<uint32_t>(bytes, 4000000000u);
        putBigEndian<float>(bytes, 0.1f * float(s));
        putBigEndian<double>(bytes, 1e300 * s); // beyond float: saturates to +-inf
    }
    spit(path, bytes);
    const ParticleTable t = readParticleFile(path);
    REQUIRE(t.rows() == 2);
    const std::vector<float> row0{-5, 200, -300, 60000, -70000, 4e9f, 0.1f, std::numeric_limits<float>::infinity()};
    for (size_t c = 0; c < row0.size(); ++c) CHECK(t.at(0, int(c)) == row0[c]);
    CHECK(t.at(1, 0) == 5.0f);
    CHECK(t.at(1, 6) == -0.1f);
    CHECK(t.at(1, 7) == -std::numeric_limits<float>::infinity());
}

TEST_CASE("particle file writes are atomic", "[io]") {
    TempDir dir("io");
    const std::string path = dir.file("frame.ply");

    SECTION("overwrite leaves only the target") {
        writeParticleFile(path, sampleTable(10, 1));
        const ParticleTable second = sampleTable(20, 2);
        writeParticleFile(path, second);
        CHECK(dir.list() == std::vector<std::string>{"frame.ply"});
        CHECK(readParticleFile(path).values == second.values);
    }
    SECTION("a missing directory fails and creates nothing") {
        const std::string bad = dir.file("no/such/dir/frame.ply");
        CHECK_THROWS_AS(writeParticleFile(bad, sampleTable(10)), ParticleFileError);
        CHECK(dir.list().empty());
    }
    SECTION("a failed write leaves the old target untouched and no temp file") {
        writeParticleFile(path, sampleTable(10, 1));
        const std::string before = slurp(path);
        ParticleTable bad = sampleTable(10, 2);
        bad.names[1] = "two words";
        CHECK_THROWS_AS(writeParticleFile(path, bad), ParticleFileError);
        bad = sampleTable(10, 2);
        bad.values.pop_back(); // not a whole number of rows
        CHECK_THROWS_AS(writeParticleFile(path, bad), ParticleFileError);
        CHECK(slurp(path) == before);
        CHECK(dir.list() == std::vector<std::string>{"frame.ply"});
    }
    SECTION("a failed rename removes the temp file") {
        // A non-empty directory cannot be replaced by a file: the temp file is complete
        // but the final rename fails.
        const std::string target = dir.file("busy.ply");
        fs::create_directories(target + "/child");
        try {
            writeParticleFile(target, sampleTable(10));
            FAIL("no error");
        } catch (const ParticleFileError& e) {
            CHECK(std::string(e.what()).rfind(target + ": ", 0) == 0);
        }
        CHECK(dir.list() == std::vector<std::string>{"busy.ply"});
        CHECK(fs::is_directory(target + "/child"));
    }
}

TEST_CASE("framePath expands frame placeholders", "[io]") {
    CHECK(framePath("out/frame_{:04}.ply", 7) == "out/frame_0007.ply");
    CHECK(framePath("out/frame_{:04d}.ply", 12345) == "out/frame_12345.ply");
    CHECK(framePath("f{}.ply", 42) == "f42.ply");
    CHECK(framePath("f{:d}.ply", 3) == "f3.ply");
    CHECK(framePath("f{:4}.ply", 3) == "f   3.ply");
    CHECK(framePath("f%04d.ply", 9) == "f0009.ply");
    CHECK(framePath("f%d.ply", 9) == "f9.ply");
    CHECK(framePath("f%3d.ply", 9) == "f  9.ply");
    CHECK(framePath("a{:03}/b{:03}.ply", 5) == "a005/b005.ply");
    CHECK(framePath("f%04d.ply", -3) == "f-003.ply");
    CHECK(framePath("static.ply", 5) == "static.ply");
    CHECK(framePath("100%_{x}_{:q}.ply", 5) == "100%_{x}_{:q}.ply");
}

TEST_CASE("ParticleTable helpers", "[io]") {
    ParticleTable t = sampleTable(4);
    CHECK(t.columns() == 7);
    CHECK(t.rows() == 4);
    CHECK(t.column("vz") == 5);
    CHECK(t.column("nope") == -1);
    CHECK(t.comment("frame") == "12");
    CHECK(t.comment("absent", "dflt") == "dflt");
    CHECK(t.commentNumber("absent", 2.5) == 2.5);
    CHECK_THROWS_AS(t.commentNumber("note", 0), ParticleFileError);
    // A header comment may hold a lone carriage return; the message escapes it (one line).
    t.comments.emplace_back("cr", "1\r2");
    CHECK_THROWS_WITH(t.commentNumber("cr", 0), "comment 'cr' is not a number: '1\\r2'");
    t.comments.pop_back();

    t.comments.emplace_back("frame", "99");
    t.setComment("frame", "13");
    CHECK(t.comment("frame") == "13");
    CHECK(std::count_if(t.comments.begin(), t.comments.end(),
                        [](const auto& c) { return c.first == "frame"; }) == 1);
    CHECK(t.comments.front().first == "frame"); // replaced in place, order kept
    t.setComment("spacing", "0.001");
    CHECK(t.comments.back() == std::pair<std::string, std::string>{"spacing", "0.001"});

    const std::vector<Vec3> x = t.vec3("x", "y", "z");
    REQUIRE(x.size() == 4);
    CHECK(x[2] == Vec3(t.at(2, 0), t.at(2, 1), t.at(2, 2)));
    CHECK_THROWS_AS(t.vec3("x", "y", "w"), ParticleFileError);
}

TEST_CASE("quantized columns: 16 bits a value, within half a step of the column's largest magnitude / 32767", "[io]") {
    // The compact particle cache ([shot] particle_cache = "compact"): positions stay floats,
    // the quantized columns come back within the documented error, and the encoding's
    // comments do not survive a read (a table written again is not scaled twice).
    const TempDir tmp("quantized");
    ParticleTable t = sampleTable(5000);
    t.values[2] = 0.9f; // sampleTable's float max would make every other value round to 0
    for (size_t r = 0; r < t.rows(); ++r) t.values[r * t.columns() + 6] = 1000.0f + 50.0f * t.at(r, 6); // a density
    t.quantized = {"vx", "vy", "vz", "density"};
    const std::string path = tmp.file("q.ply");
    writeParticleFile(path, t);
    const ParticleTable back = readParticleFile(path);
    REQUIRE(back.rows() == t.rows());
    CHECK(back.quantized.empty());
    CHECK(back.comment("quantized", "(none)") == "(none)");
    CHECK(back.comment("frame") == "12");
    // 3 floats + 4 shorts a row after the header.
    const auto header = slurp(path).find("end_header\n") + 11;
    CHECK(fs::file_size(path) == header + t.rows() * (3 * 4 + 4 * 2));
    for (int c = 0; c < 7; ++c) {
        float maxAbs = 0, maxErr = 0;
        for (size_t r = 0; r < t.rows(); ++r) {
            maxAbs = std::max(maxAbs, std::fabs(t.at(r, c)));
            maxErr = std::max(maxErr, std::fabs(back.at(r, c) - t.at(r, c)));
        }
        INFO("column " << t.names[size_t(c)] << ": largest " << maxAbs << ", error " << maxErr);
        if (c < 3) CHECK(maxErr == 0.0f); // positions bit for bit
        else {
            // Half a step, plus the float rounding of the product step x integer on reading.
            CHECK(maxErr <= 0.5f * maxAbs / 32767.0f + maxAbs * 6.0e-8f);
            CHECK(maxErr > 0.0f); // it is a lossy encoding: a test that saw no loss checked nothing
        }
    }
    // Written again as floats: the same values, not scaled twice.
    writeParticleFile(tmp.file("again.ply"), back);
    const ParticleTable again = readParticleFile(tmp.file("again.ply"));
    CHECK(again.values == back.values);

    ParticleTable bad = sampleTable(10);
    bad.values[3] = std::numeric_limits<float>::quiet_NaN(); // row 0, vx
    bad.quantized = {"vx"};
    CHECK_THROWS_WITH(writeParticleFile(tmp.file("nan.ply"), bad), Catch::Contains("cannot quantize"));
}
