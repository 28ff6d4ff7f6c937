#pragma once
// The part every Ferro tool's main() shares (ferro-sim, ferro-surface, ferro-spikes,
// ferro-pov): parsing with CLI11, running the stage's library, and turning whatever went
// wrong into one line "ferro-<stage>: error: <reason>" on stderr and an exit code
// (ferro::ExitCode in sim/core/ExitCodes.hpp). Each main.cpp declares its options, says which of
// its library's exceptions mean which exit code, and hands the work over as a function:
//
//   CLI::App app{"ferro-x: ..."};
//   app.add_option(...);
//   return runCommandLine("ferro-x", app, argc, argv,
//                         {exitOn<SceneError>(kExitBadInput), exitOn<XIoError>(kExitIoError)},
//                         [&] { ...; return kExitOk; });
#include "sim/core/ParticleFile.hpp" // FrameRange
#include "sim/core/ExitCodes.hpp"

#include <tbb/global_control.h>

#include <exception>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace CLI {
class App;
class Option;
} // namespace CLI

namespace ferro {

class SceneDocument;

/// What one kind of failure of a stage's library means on the command line: an exception
/// that `matches` ends the tool with exit code `code` and the line
/// "<program>: error: <rewrite(what())><note>" (rewrite = identity when null).
struct ErrorExit {
    std::function<bool(const std::exception&)> matches;
    int code = kExitFailure;
    std::string note;
    std::string (*rewrite)(const std::string&) = nullptr;
};

/// The ErrorExit for exceptions of type E and the types derived from it. `rewrite` can fold a
/// library's multi-line message into one line (sim/core/ErrorText.hpp's oneLine).
template <class E>
ErrorExit exitOn(int code, std::string note = "", std::string (*rewrite)(const std::string&) = nullptr) {
    auto matches = [](const std::exception& e) {
        if constexpr (std::is_base_of_v<E, std::exception>) return true; // E = std::exception: all
        else return dynamic_cast<const E*>(&e) != nullptr;
    };
    return {matches, code, std::move(note), rewrite};
}

/// A bad argument found after CLI11 has parsed the line (a malformed --frames range, ...):
/// runCommandLine reports what() as it is, with exit code kExitBadInput.
class ArgumentError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Parses argc/argv into `app`, then returns body()'s exit code. Failures become one line on
/// stderr, prefixed "<program>: error: ", and an exit code:
///  - --help: CLI11's help text, exit 0 (CLI::App::exit);
///  - a CLI::ParseError, from parsing or thrown by body (a check CLI11 cannot express):
///    "<what> (see --help)", kExitBadInput;
///  - an ArgumentError from body: "<what>", kExitBadInput;
///  - a StageError from body (sim/core/StageErrors.hpp): "<what>", its own code;
///  - another std::exception from body: the first entry of `errors` that matches it, in
///    order (list derived types before their bases, as catch clauses); if none does,
///    "<what>" and kExitFailure.
/// Exceptions not derived from std::exception are not caught.
int runCommandLine(const char* program, CLI::App& app, int argc, char** argv, const std::vector<ErrorExit>& errors,
                   const std::function<int()>& body);

/// The frame range `text` given to `option` (e.g. "--frames"), parsed by parseFrameRange;
/// a malformed one throws ArgumentError("<option> <reason>").
FrameRange frameRangeArgument(const std::string& option, const std::string& text);

/// Adds the repeatable option --set KEY=VALUE that collects scene overrides for
/// SceneDocument::load(path, overrides); `help` is its help line (with a stage's example).
CLI::Option* addSetOption(CLI::App& app, std::vector<std::string>& overrides, const std::string& help);

/// Adds the flag --print-scene-inputs: the stage parses its scene (after --set) and prints
/// every key it read, SceneDocument::readsText, instead of running; scripts/shot.mk stamps
/// each stage with that text, so the stage's own parser is the one list of what it reads.
/// The options in `requiredOtherwise` are required except with this flag or one of the
/// stage's other query flags `queries` (CLI11's ->required() cannot say "unless"); their
/// help lines say so.
CLI::Option* addSceneInputsFlag(CLI::App& app, bool& flag, const std::vector<CLI::Option*>& requiredOtherwise,
                                const std::vector<const bool*>& queries = {});

/// Turns on doc's read log, runs `parse` on it and prints the keys it read to stdout
/// (--print-scene-inputs); returns kExitOk.
ExitCode printSceneInputs(SceneDocument& doc, const std::function<void(const SceneDocument&)>& parse);

/// Adds --threads N (N >= 0; 0 = all cores, see limitThreads) with the help line `help`.
CLI::Option* addThreadsOption(CLI::App& app, int& threads, const std::string& help);

/// Limits TBB to `threads` worker threads while the returned object lives; threads <= 0
/// (the --threads default) sets no limit and returns null: all cores.
std::unique_ptr<tbb::global_control> limitThreads(int threads);

} // namespace ferro
