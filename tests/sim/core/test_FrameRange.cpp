// --frames parsing shared by ferro-surface, ferro-spikes and ferro-pov (sim/core/ParticleFile.hpp),
// the particle reader's answer to a header that ends the file, and one-line error text.
#include "sim/core/ParticleFile.hpp"
#include "sim/core/ErrorText.hpp"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include <unistd.h>

using namespace ferro;
namespace fs = std::filesystem;

TEST_CASE("parseFrameRange takes A:B and A, and rejects everything else with one line", "[frames]") {
    FrameRange r = parseFrameRange("3:7");
    CHECK(r.first == 3);
    CHECK(r.last == 7);
    CHECK(r.count() == 5);
    r = parseFrameRange("12");
    CHECK((r.first == 12 && r.last == 12));
    r = parseFrameRange(" 08 : 09 "); // leading zeros are decimal
    CHECK((r.first == 8 && r.last == 9));
    r = parseFrameRange("0:9999999");
    CHECK(r.last == kMaxFrame);
    CHECK(r.count() == 10000000);
    r = parseFrameRange("0000000000000005:6"); // many leading zeros are still a small number
    CHECK(r.first == 5);

    for (const char* bad : {"", ":", "1:", ":2", "a:b", "1:2:3", "-1:2", "1:-2", "5:2", "1.5:2", "0x10:20",
                            "0:10000000", "0:2147483647", "0:99999999999", "99999999999999999999999:1", "+1:2"}) {
        INFO("'" << bad << "'");
        try {
            parseFrameRange(bad);
            FAIL("accepted");
        } catch (const std::invalid_argument& e) {
            const std::string what = e.what();
            CHECK(what.find('\n') == std::string::npos);
            CHECK(what.find(std::string("'") + bad + "'") == 0); // names the text
        }
    }
}

TEST_CASE("the particle reader rejects a header that ends without its line break", "[frames][io]") {
    const fs::path dir = fs::temp_directory_path() / ("ferro_frame_range_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string head = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                             "property float y\nproperty float z\n";
    for (const std::string& text : {head + "end_header", head + "end_header\n", head + "end_header\n" + std::string(64, 'x')}) {
        const std::string path = (dir / "p.ply").string();
        {
            std::ofstream(path, std::ios::binary) << text;
        }
        INFO(text.size() << " bytes");
        try {
            readParticleFile(path);
            FAIL("no error");
        } catch (const ParticleFileError& e) {
            CHECK(std::string(e.what()).find('\n') == std::string::npos);
        }
    }
    fs::remove_all(dir);
}

TEST_CASE("oneLine folds a multi-line library message into one line", "[frames]") {
    CHECK(oneLine("plain") == "plain");
    CHECK(oneLine("CGAL ERROR: precondition violation!\nExpr: x  \n  File: a.h\r\nLine: 3\n") ==
          "CGAL ERROR: precondition violation!; Expr: x; File: a.h; Line: 3");
    CHECK(oneLine("\n\nlate start") == "late start");
    CHECK(oneLine("") == "");
}
