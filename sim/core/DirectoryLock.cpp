#include "sim/core/DirectoryLock.hpp"

#include "sim/core/StageErrors.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sys/file.h>
#include <unistd.h>

namespace ferro {

namespace {

std::string lockPath(const std::string& dir) { return dir + "/" + DirectoryLock::kFileName; }

} // namespace

std::string DirectoryLock::lastHolder(const std::string& dir) {
    std::ifstream in(lockPath(dir));
    std::string line;
    std::getline(in, line);
    return line;
}

DirectoryLock::DirectoryLock(const std::string& dir, const std::string& holder) {
    const std::string path = lockPath(dir);
    // O_CLOEXEC: the stages this process starts (POV-Ray, make) do not inherit the lock.
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw StageError(kExitIoError, dir + ": cannot lock: " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
        const int err = errno;
        ::close(fd_);
        fd_ = -1;
        if (err != EWOULDBLOCK) throw StageError(kExitIoError, dir + ": cannot lock: " + std::strerror(err));
        const std::string who = lastHolder(dir);
        throw StageError(kExitIoError, dir + ": in use by " + (who.empty() ? std::string("another process") : who) +
                                           "; wait for it to end or stop it");
    }
    // Ours: say who holds it (the previous holder's words, if any, were stale).
    const std::string text = holder + " (pid " + std::to_string(::getpid()) + ")\n";
    if (::ftruncate(fd_, 0) == 0) {
        ssize_t ignored = ::pwrite(fd_, text.data(), text.size(), 0);
        (void)ignored;
    }
}

DirectoryLock::~DirectoryLock() {
    if (fd_ >= 0) ::close(fd_); // closing the descriptor releases the lock
}

} // namespace ferro
