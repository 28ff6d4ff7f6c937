#pragma once
// Atomic file replacement: every Ferro output (particle files, meshes, level sets, POV-Ray
// includes) is written to a temporary file beside the target and renamed over it only once
// complete, so a reader, a crash or a failed write never leaves a half-written file and an
// earlier output survives any failure.
//
// The temporary file is `<path>.tmp-<pid>-<n>`: in the target's directory (rename(2) is
// atomic only within one file system), and unique per process and per call, so threads and
// processes writing different frames never share one. ferro-sim removes leftovers of a killed
// writer (`particles_*.ply.tmp-*`) when it resumes.
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>

namespace ferro {

/// A failure of the helpers below. what() is one line without the target path, ready for
/// the caller to prefix: "cannot create <temp>: <reason>", "write failed: <reason>" or
/// "cannot rename the temporary file: <reason>".
class AtomicFileError : public std::runtime_error {
public:
    enum class Step { Create, Write, Rename };
    AtomicFileError(Step step, const std::string& tempPath, int errorNumber);

    Step step() const { return step_; }
    /// The errno of the failed call; strerror(errorNumber()) is the end of what().
    int errorNumber() const { return errorNumber_; }

private:
    Step step_;
    int errorNumber_;
};

/// Replaces `path` by what `write` puts into a binary output stream.
///
/// The stream goes to a fresh temporary file beside `path`; once `write` returns and the file
/// is flushed and closed without error, it is renamed over `path`.
/// @throw AtomicFileError if the temporary file cannot be created, a write to it fails (the
///        stream's state is checked after `write` returns) or the rename fails.
/// @throw whatever `write` throws, unchanged.
/// In every failure case the temporary file is removed and `path` is left as it was.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// As writeFileAtomically, for writers that open files by name (e.g. openvdb::io::File):
/// `writeTemp` gets the temporary file's path, must create and completely write that file,
/// and throws on failure.
/// @throw AtomicFileError (Step::Rename) if the rename fails; whatever `writeTemp` throws.
/// In every failure case the temporary file is removed and `path` is left as it was.
void writeFileAtomicallyByPath(const std::string& path,
                               const std::function<void(const std::string& tempPath)>& writeTemp);

} // namespace ferro
