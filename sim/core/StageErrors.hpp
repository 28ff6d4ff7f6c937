#pragma once
// The errors every stage's library throws, each carrying its exit code from the one table in
// sim/core/ExitCodes.hpp; runCommandLine (sim/core/CommandLine.hpp) ends the tool with that
// code and the one-line what(). A stage may derive its own (MeshFileError, ...) or throw these.
#include "sim/core/ExitCodes.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace ferro {

/// A failure with the exit code it maps to. what() is one line.
class StageError : public std::runtime_error {
public:
    StageError(int code, const std::string& what) : std::runtime_error(what), code_(code) {}
    int code() const { return code_; }

private:
    int code_;
};

/// An input that is missing or cannot be opened (exit 4): a wrong path, a frame not made yet.
class InputMissingError : public StageError {
public:
    explicit InputMissingError(const std::string& what) : StageError(kExitIoError, what) {}
};

/// An input that opens but cannot be used, or options that contradict each other (exit 2).
class BadInputError : public StageError {
public:
    explicit BadInputError(const std::string& what) : StageError(kExitBadInput, what) {}
};

/// Throws InputMissingError("<path>: cannot open: <reason>") unless `path` is a file that opens
/// for reading (a directory is refused with "is a directory").
void requireReadable(const std::string& path);

/// Throws BadInputError("<outputOption> '<out>' is the input '<in>': refusing to overwrite it")
/// if `out` names the same file as one of `inputs` (same path after normalisation, or the
/// same inode through a link). Every stage checks this before it writes a frame, so a typo
/// in --out never replaces the frames it reads. Empty paths are skipped.
void refuseToOverwriteInputs(const std::string& outputOption, const std::string& out,
                             const std::vector<std::string>& inputs);

} // namespace ferro
