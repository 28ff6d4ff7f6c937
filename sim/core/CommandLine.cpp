#include "sim/core/CommandLine.hpp"

#include "sim/core/SceneDocument.hpp"
#include "sim/core/StageErrors.hpp"

#include <CLI/CLI.hpp>

#include <iostream>

namespace ferro {

namespace {

int report(const char* program, const std::string& message, int code) {
    std::cerr << program << ": error: " << message << "\n";
    return code;
}

} // namespace

int runCommandLine(const char* program, CLI::App& app, int argc, char** argv, const std::vector<ErrorExit>& errors,
                   const std::function<int()>& body) {
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        return report(program, std::string(e.what()) + " (see --help)", kExitBadInput);
    }
    try {
        return body();
    } catch (const CLI::ParseError& e) {
        return report(program, std::string(e.what()) + " (see --help)", kExitBadInput);
    } catch (const ArgumentError& e) {
        return report(program, e.what(), kExitBadInput);
    } catch (const StageError& e) {
        return report(program, e.what(), e.code());
    } catch (const std::exception& e) {
        for (const ErrorExit& error : errors) {
            if (!error.matches(e)) continue;
            const std::string what = error.rewrite ? error.rewrite(e.what()) : std::string(e.what());
            return report(program, what + error.note, error.code);
        }
        return report(program, e.what(), kExitFailure);
    }
}

FrameRange frameRangeArgument(const std::string& option, const std::string& text) {
    try {
        return parseFrameRange(text);
    } catch (const std::invalid_argument& e) {
        throw ArgumentError(option + " " + e.what());
    }
}

CLI::Option* addSetOption(CLI::App& app, std::vector<std::string>& overrides, const std::string& help) {
    return app.add_option("--set", overrides, help)->type_name("KEY=VALUE");
}

// --print-scene-keys is --print-scene-inputs in another format; one process parses one
// command line, so the choice of format can live here rather than in every stage's main.
static bool printKeySpecs = false;

CLI::Option* addSceneInputsFlag(CLI::App& app, bool& flag, const std::vector<CLI::Option*>& requiredOtherwise,
                                const std::vector<const bool*>& queries) {
    for (CLI::Option* o : requiredOtherwise)
        o->description(o->get_description() + " (required)");
    app.add_flag("--print-scene-keys", printKeySpecs,
                 "print the scene keys this stage reads with their type, range and default, one a line, and exit "
                 "(docs/reference/scene.md is made from it)");
    app.final_callback([&flag, requiredOtherwise, queries] {
        if (printKeySpecs)
            flag = true;
        if (flag)
            return;
        for (const bool* q : queries)
            if (*q)
                return;
        for (CLI::Option* o : requiredOtherwise)
            if (o->count() == 0)
                throw CLI::RequiredError(o->get_name());
    });
    return app.add_flag("--print-scene-inputs", flag,
                        "print the scene keys this stage reads (after --set), one `key = value` a line, and exit");
}

ExitCode printSceneInputs(SceneDocument& doc, const std::function<void(const SceneDocument&)>& parse) {
    doc.recordReads();
    parse(doc);
    std::cout << (printKeySpecs ? doc.keySpecsText() : doc.readsText());
    return kExitOk;
}

CLI::Option* addThreadsOption(CLI::App& app, int& threads, const std::string& help) {
    // Own wording: CLI::NonNegativeNumber's says "not in range 0.000000 to 1797...(300 digits)".
    const CLI::Validator wholeNumber(
        [](std::string& value) {
            const bool digits = !value.empty() && value.find_first_not_of("0123456789") == std::string::npos;
            return digits ? std::string() : "must be a whole number >= 0, 0 = all cores (got " + value + ")";
        },
        "N>=0");
    return app.add_option("--threads", threads, help)->check(wholeNumber);
}

std::unique_ptr<tbb::global_control> limitThreads(int threads) {
    if (threads <= 0) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(threads));
}

} // namespace ferro
