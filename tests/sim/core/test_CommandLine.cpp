// The CLI shell every ferro tool's main() shares (sim/core/CommandLine.hpp): exit codes and
// the one "<program>: error: ..." line for parse errors, ArgumentError and the library
// exceptions mapped by exitOn (first match wins, derived before base); --frames parsing;
// --set collection; --threads.
#include "sim/core/CommandLine.hpp"

#include <catch2/catch.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

using namespace ferro;

namespace {

struct LibraryError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
struct SpecialError : LibraryError {
    using LibraryError::LibraryError;
};

/// Runs runCommandLine on `args` (after the program name) and returns the exit code;
/// stderr and stdout are captured.
struct Run {
    int code = -1;
    std::string err, out;
};

Run run(std::vector<std::string> args, const std::vector<ErrorExit>& errors, const std::function<int()>& body,
        CLI::App* appIn = nullptr) {
    CLI::App local{"ferro-test: a test tool"};
    CLI::App& app = appIn ? *appIn : local;
    args.insert(args.begin(), "ferro-test");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    std::ostringstream err, out;
    std::streambuf* oldErr = std::cerr.rdbuf(err.rdbuf());
    std::streambuf* oldOut = std::cout.rdbuf(out.rdbuf());
    Run r;
    try {
        r.code = runCommandLine("ferro-test", app, int(argv.size()), argv.data(), errors, body);
    } catch (...) {
        std::cerr.rdbuf(oldErr);
        std::cout.rdbuf(oldOut);
        throw;
    }
    std::cerr.rdbuf(oldErr);
    std::cout.rdbuf(oldOut);
    r.err = err.str();
    r.out = out.str();
    return r;
}

} // namespace

TEST_CASE("runCommandLine: body's exit code, --help, parse errors", "[cli]") {
    REQUIRE(run({}, {}, [] { return 0; }).code == kExitOk);
    const Run five = run({}, {}, [] { return 5; });
    REQUIRE(five.code == 5);
    REQUIRE(five.err.empty());

    const Run help = run({"--help"}, {}, [] { return 7; });
    REQUIRE(help.code == 0);
    REQUIRE(help.out.find("a test tool") != std::string::npos);

    bool ran = false;
    const Run bad = run({"--no-such-option"}, {}, [&] { ran = true; return 0; });
    REQUIRE_FALSE(ran);
    REQUIRE(bad.code == kExitBadInput);
    REQUIRE(bad.err.rfind("ferro-test: error: ", 0) == 0);
    REQUIRE(bad.err.find("(see --help)\n") != std::string::npos);
    REQUIRE(std::count(bad.err.begin(), bad.err.end(), '\n') == 1);

    // A CLI::ParseError thrown by the body (a check CLI11 cannot express) is a bad input too.
    const Run late = run({}, {}, []() -> int { throw CLI::ValidationError("--frames", "ends before it starts"); });
    REQUIRE(late.code == kExitBadInput);
    REQUIRE(late.err.find("ends before it starts (see --help)") != std::string::npos);
}

TEST_CASE("runCommandLine: ArgumentError, mapped exceptions in order, unmapped ones", "[cli]") {
    static std::string (*fold)(const std::string&) = [](const std::string& s) {
        std::string r = s;
        for (char& c : r) if (c == '\n') c = '|';
        return r;
    };
    const std::vector<ErrorExit> errors = {exitOn<SpecialError>(kExitSimulationFailed, " (special)"),
                                           exitOn<LibraryError>(kExitIoError, "", fold)};

    const Run arg = run({}, errors, []() -> int { throw ArgumentError("--frames 5:2 ends before it starts"); });
    REQUIRE(arg.code == kExitBadInput);
    REQUIRE(arg.err == "ferro-test: error: --frames 5:2 ends before it starts\n");

    const Run special = run({}, errors, []() -> int { throw SpecialError("boom"); });
    REQUIRE(special.code == kExitSimulationFailed);
    REQUIRE(special.err == "ferro-test: error: boom (special)\n");

    const Run base = run({}, errors, []() -> int { throw LibraryError("two\nlines"); });
    REQUIRE(base.code == kExitIoError);
    REQUIRE(base.err == "ferro-test: error: two|lines\n");

    // Listed base first, the base entry catches the derived exception (as catch clauses do).
    const Run order = run({}, {exitOn<LibraryError>(kExitIoError), exitOn<SpecialError>(kExitSimulationFailed)},
                          []() -> int { throw SpecialError("x"); });
    REQUIRE(order.code == kExitIoError);

    const Run other = run({}, errors, []() -> int { throw std::out_of_range("index 9"); });
    REQUIRE(other.code == kExitFailure);
    REQUIRE(other.err == "ferro-test: error: index 9\n");

    // exitOn<std::exception> matches everything.
    const Run all = run({}, {exitOn<std::exception>(kExitIoError, " [all]")}, []() -> int { throw std::logic_error("l"); });
    REQUIRE(all.code == kExitIoError);
    REQUIRE(all.err == "ferro-test: error: l [all]\n");

    // Not derived from std::exception: not caught.
    REQUIRE_THROWS_AS(run({}, errors, []() -> int { throw 42; }), int);
}

TEST_CASE("frameRangeArgument parses ranges and names the option in its errors", "[cli]") {
    const FrameRange one = frameRangeArgument("--frames", "7");
    REQUIRE(one.first == 7);
    REQUIRE(one.last == 7);
    const FrameRange range = frameRangeArgument("--frames", "3:10");
    REQUIRE(range.first == 3);
    REQUIRE(range.last == 10);
    REQUIRE(range.count() == 8);
    for (const char* bad : {"", "x", "5:2", "-1", "1:", "1:2:3", "0:99999999"}) {
        CAPTURE(bad);
        try {
            frameRangeArgument("--frames", bad);
            FAIL("no ArgumentError");
        } catch (const ArgumentError& e) {
            REQUIRE(std::string(e.what()).rfind("--frames ", 0) == 0);
        }
    }
}

TEST_CASE("the --set option collects every override in order, --threads takes N >= 0", "[cli]") {
    CLI::App app{"ferro-test"};
    std::vector<std::string> overrides;
    int threads = 0;
    addSetOption(app, overrides, "override a scene key");
    addThreadsOption(app, threads, "worker threads");
    const Run ok = run({"--set", "fluid.spacing=0.002", "--threads", "3", "--set", "shot.fps=24"}, {},
                       [] { return 0; }, &app);
    REQUIRE(ok.code == 0);
    REQUIRE(overrides == std::vector<std::string>{"fluid.spacing=0.002", "shot.fps=24"});
    REQUIRE(threads == 3);
    {
        auto limit = limitThreads(threads);
        REQUIRE(limit != nullptr);
        REQUIRE(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) == 3);
    }
    REQUIRE(limitThreads(0) == nullptr);

    CLI::App app2{"ferro-test"};
    int t2 = 0;
    addThreadsOption(app2, t2, "worker threads");
    const Run negative = run({"--threads", "-2"}, {}, [] { return 0; }, &app2);
    REQUIRE(negative.code == kExitBadInput);
    REQUIRE(negative.err.find("--threads") != std::string::npos);
    REQUIRE(negative.err.find("must be a whole number >= 0, 0 = all cores (got -2)") != std::string::npos);
}
