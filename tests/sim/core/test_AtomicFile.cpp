// Atomic file replacement (sim/core/AtomicFile): the target appears complete or not at all, a
// failing writer leaves an earlier target untouched, and no temporary file is left behind.
#include "sim/core/AtomicFile.hpp"
#include "tests/TestUtil.hpp"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <ostream>
#include <stdexcept>
#include <vector>

#include <unistd.h>

using namespace ferro;
using namespace ferro::test;
namespace fs = std::filesystem;

namespace {

void writeText(const std::string& path, const std::string& text) {
    writeFileAtomically(path, [&](std::ostream& out) { out << text; });
}

} // namespace

TEST_CASE("writeFileAtomically writes and replaces the target, leaving nothing else", "[io][atomic]") {
    TempDir dir("atomic");
    const std::string path = dir.file("out.txt");
    writeText(path, "first\n");
    CHECK(slurp(path) == "first\n");
    writeText(path, std::string(100000, 'x') + '\0' + "binary");
    CHECK(slurp(path) == std::string(100000, 'x') + '\0' + "binary");
    CHECK(dir.list() == std::vector<std::string>{"out.txt"});
}

TEST_CASE("a throwing writer leaves the old target untouched and no temporary file", "[io][atomic]") {
    TempDir dir("atomic");
    const std::string path = dir.file("out.txt");
    writeText(path, "old contents\n");
    CHECK_THROWS_WITH(writeFileAtomically(path,
                                          [](std::ostream& out) {
                                              out << "half of the new";
                                              out.flush(); // the temp file really holds bytes
                                              throw std::runtime_error("writer gave up");
                                          }),
                      "writer gave up");
    CHECK(slurp(path) == "old contents\n");
    CHECK(dir.list() == std::vector<std::string>{"out.txt"});

    // Without an earlier target, nothing appears.
    CHECK_THROWS_AS(writeFileAtomically(dir.file("new.txt"), [](std::ostream&) { throw std::logic_error("no"); }),
                    std::logic_error);
    CHECK(dir.list() == std::vector<std::string>{"out.txt"});
}

TEST_CASE("atomic writes report where they failed, in one line, and clean up", "[io][atomic]") {
    TempDir dir("atomic");
    SECTION("a missing directory: nothing is created") {
        try {
            writeText(dir.file("no/such/dir/out.txt"), "x");
            FAIL("no error");
        } catch (const AtomicFileError& e) {
            CHECK(e.step() == AtomicFileError::Step::Create);
            CHECK(std::string(e.what()).rfind("cannot create " + dir.file("no/such/dir/out.txt.tmp-"), 0) == 0);
            CHECK(std::string(e.what()).find('\n') == std::string::npos);
        }
        CHECK(dir.list().empty());
    }
    SECTION("a failed rename removes the complete temporary file") {
        // A non-empty directory cannot be replaced by a file.
        fs::create_directories(dir.path / "busy" / "child");
        try {
            writeText(dir.file("busy"), "x");
            FAIL("no error");
        } catch (const AtomicFileError& e) {
            CHECK(e.step() == AtomicFileError::Step::Rename);
            CHECK(e.errorNumber() != 0);
            CHECK(std::string(e.what()).rfind("cannot rename the temporary file: ", 0) == 0);
        }
        CHECK(dir.list() == std::vector<std::string>{"busy"});
        CHECK(fs::is_directory(dir.path / "busy" / "child"));
    }
}

TEST_CASE("writeFileAtomicallyByPath hands out a fresh temporary path beside the target", "[io][atomic]") {
    TempDir dir("atomic");
    const std::string path = dir.file("grid.vdb");
    std::vector<std::string> temps;
    for (int i = 0; i < 2; ++i)
        writeFileAtomicallyByPath(path, [&](const std::string& tmp) {
            temps.push_back(tmp);
            std::ofstream(tmp, std::ios::binary) << "grid " << i;
        });
    REQUIRE(temps.size() == 2);
    CHECK(temps[0] != temps[1]); // unique per call, so threads never share one
    for (const std::string& t : temps) {
        CHECK(fs::path(t).parent_path() == dir.path);
        CHECK(t.rfind(path + ".tmp-" + std::to_string(::getpid()) + "-", 0) == 0);
    }
    CHECK(slurp(path) == "grid 1");

    // A writer that created its file and then failed: the file goes, the target stays.
    CHECK_THROWS_AS(writeFileAtomicallyByPath(path,
                                              [&](const std::string& tmp) {
                                                  std::ofstream(tmp, std::ios::binary) << "partial";
                                                  throw std::runtime_error("disk full");
                                              }),
                    std::runtime_error);
    CHECK(slurp(path) == "grid 1");
    CHECK(dir.list() == std::vector<std::string>{"grid.vdb"});
}
