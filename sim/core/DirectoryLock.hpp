#pragma once
// One writer a folder: an exclusive lock a tool holds on its output directory while it
// writes there, so that a second run on the same folder (a second ferro-sim --resume, a
// second artist's shot) is refused at once instead of interleaving frames with the first.
//
// The lock is flock(2) on `<dir>/.ferro.lock`, taken without waiting. The kernel releases it
// when its holder exits however that happens (SIGKILL and a lost node's restart included),
// so a lock file a killed run leaves behind is stale by construction and the next run takes
// it over; the file only keeps the last holder's pid and command line for the refusal's
// message. Local file systems only: flock on NFS is emulated with byte-range locks, which
// this does not promise (docs/shots.md).
#include <string>

namespace ferro {

class DirectoryLock {
public:
    /// The lock file's name inside the locked directory.
    static constexpr const char* kFileName = ".ferro.lock";

    /// Takes the lock on `dir` (which must exist) for `holder` (what the refusal names, e.g.
    /// "ferro-sim examples/dish.toml"). Never waits.
    /// @throw StageError(kExitIoError, "<dir>: in use by <holder> (pid <n>); wait for it to end
    ///        or stop it") when another process holds it, or (kExitIoError, "<dir>: cannot lock:
    ///        <reason>") when the lock file cannot be opened.
    DirectoryLock(const std::string& dir, const std::string& holder);
    ~DirectoryLock();
    DirectoryLock(const DirectoryLock&) = delete;
    DirectoryLock& operator=(const DirectoryLock&) = delete;

    /// What the lock file says about its last holder ("<holder> (pid <n>)"), or "" if nothing.
    static std::string lastHolder(const std::string& dir);

private:
    int fd_ = -1;
};

} // namespace ferro
