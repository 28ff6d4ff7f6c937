// Atomic file replacement: temporary file beside the target, then rename (see AtomicFile.hpp).
#include "sim/core/AtomicFile.hpp"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

namespace ferro {

namespace {

/// The mount point of the file system that holds `path` (the longest mount point in
/// /proc/self/mounts that is a whole-component prefix of its absolute path), "" if unknown.
std::string mountPointOf(const std::string& path) {
    std::error_code ec;
    const std::string dir = std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec).parent_path(), ec).string();
    std::ifstream mounts("/proc/self/mounts");
    std::string line, best;
    while (std::getline(mounts, line)) {
        std::istringstream fields(line);
        std::string device, point;
        if (!(fields >> device >> point)) continue;
        // /proc/self/mounts escapes a space in a path as \040.
        for (size_t at; (at = point.find("\\040")) != std::string::npos;) point.replace(at, 4, " ");
        const bool prefix = point == "/" || dir == point || dir.rfind(point + "/", 0) == 0;
        if (prefix && point.size() > best.size()) best = point;
    }
    return best;
}

std::string describe(AtomicFileError::Step step, const std::string& tempPath, int errorNumber) {
    std::string reason = std::strerror(errorNumber);
    // A full disk names the disk: which file system to free, whatever the path's spelling.
    if (errorNumber == ENOSPC || errorNumber == EDQUOT) {
        const std::string mount = mountPointOf(tempPath);
        if (!mount.empty()) reason += " (the file system mounted at " + mount + " is full)";
    }
    switch (step) {
    case AtomicFileError::Step::Create: return "cannot create " + tempPath + ": " + reason;
    case AtomicFileError::Step::Write: return "write failed: " + reason;
    case AtomicFileError::Step::Rename: return "cannot rename the temporary file: " + reason;
    }
    return reason;
}

/// `<path>.tmp-<pid>-<n>`, n counting calls in this process: unique per process and thread.
std::string temporaryPathFor(const std::string& path) {
    static std::atomic<unsigned long> calls{0};
    return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(calls.fetch_add(1));
}

/// errno after a failed stream operation; EIO when the library left none.
int streamErrno() { return errno != 0 ? errno : EIO; }

} // namespace

AtomicFileError::AtomicFileError(Step step, const std::string& tempPath, int errorNumber)
    : std::runtime_error(describe(step, tempPath, errorNumber)), step_(step), errorNumber_(errorNumber) {}

void writeFileAtomicallyByPath(const std::string& path,
                               const std::function<void(const std::string& tempPath)>& writeTemp) {
    const std::string tmp = temporaryPathFor(path);
    try {
        writeTemp(tmp);
    } catch (...) {
        std::remove(tmp.c_str());
        throw;
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        const int err = errno;
        std::remove(tmp.c_str());
        throw AtomicFileError(AtomicFileError::Step::Rename, tmp, err);
    }
}

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
    writeFileAtomicallyByPath(path, [&](const std::string& tmp) {
        errno = 0;
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw AtomicFileError(AtomicFileError::Step::Create, tmp, streamErrno());
        errno = 0;
        write(out);
        if (!out.flush()) throw AtomicFileError(AtomicFileError::Step::Write, tmp, streamErrno());
        out.close(); // the last buffered bytes reach the file here; a full disk shows now
        if (!out) throw AtomicFileError(AtomicFileError::Step::Write, tmp, streamErrno());
    });
}

} // namespace ferro
