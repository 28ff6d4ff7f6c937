#pragma once
// Helpers shared by every stage's tests: scratch directories, whole-file reads and writes,
// and running a shell command (usually one of the ferro-* executables) for its exit code and
// what it printed.
// Header-only; include as "tests/TestUtil.hpp" (the project root is on the include path).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

namespace ferro::test {

/// Relative RMS difference of two sets of vectors (Eigen, any scalar): |a - ref| / |ref|,
/// 2-norms over all of them, summed in double.
template <class V>
double relativeRms(const std::vector<V>& a, const std::vector<V>& ref) {
    double d = 0, r = 0;
    for (size_t i = 0; i < ref.size(); ++i) {
        d += (a[i] - ref[i]).template cast<double>().squaredNorm();
        r += ref[i].template cast<double>().squaredNorm();
    }
    return std::sqrt(d / r);
}

/// Every byte of the file at `path`; empty when it cannot be opened.
inline std::string slurp(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

#ifdef FERRO_SOURCE_DIR
/// The small resting pool of the pipeline tests (tests/data/small_pool.toml: a 4 cm dish, a
/// 5 mm layer of 2,000 particles, a pre-roll) followed by `extra` (magnets, [magnetization],
/// [render]): one scene text, so the tests that share it cannot drift apart.
inline std::string smallPoolScene(const std::string& extra) {
    const std::string base = slurp(std::string(FERRO_SOURCE_DIR) + "/tests/data/small_pool.toml");
    if (base.empty()) throw std::runtime_error("tests/data/small_pool.toml: cannot be read");
    return base + "\n" + extra;
}
#endif

/// Replaces the file at `path` by exactly `bytes` (plainly, not atomically: test input only).
inline void spit(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out << bytes;
}

/// A fresh, empty directory under the system temp directory, removed with everything in it
/// at scope exit. Its name holds `tag`, the process id and a serial number, so test cases
/// and concurrently running test executables never share one.
struct TempDir {
    std::filesystem::path path;

    explicit TempDir(const std::string& tag = "test") {
        static std::atomic<int> serial{0};
        path = std::filesystem::temp_directory_path() /
               ("ferro_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(serial++));
        std::filesystem::remove_all(path);
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    /// The path of `name` inside the directory (nothing is created).
    std::string file(const std::string& name) const { return (path / name).string(); }
    /// Writes `text` to `name` (creating its parent directories); returns its path.
    std::string write(const std::string& name, const std::string& text) const {
        const std::filesystem::path p = path / name;
        std::filesystem::create_directories(p.parent_path());
        spit(p, text);
        return p.string();
    }
    /// The names of the directory's entries, sorted.
    std::vector<std::string> list() const {
        std::vector<std::string> names;
        for (const auto& e : std::filesystem::directory_iterator(path)) names.push_back(e.path().filename().string());
        std::sort(names.begin(), names.end());
        return names;
    }
};

struct CommandResult {
    int code = -1;      ///< exit status; -1 when the command was killed by a signal
    std::string output; ///< what the command wrote to the captured stream(s)
};

/// Which output of a command runCommand captures; the rest goes to the test's own streams.
enum class Capture { Stderr, StdoutAndStderr };

/// Runs `cmd` with /bin/sh (as a group, so `a && b` is captured whole) and waits for it.
/// The captured output passes through a file in the system temp directory, named after
/// this process and call, and removed again.
inline CommandResult runCommand(const std::string& cmd, Capture capture = Capture::Stderr) {
    static std::atomic<int> calls{0};
    const std::string file = (std::filesystem::temp_directory_path() /
                              ("ferro_cmd_" + std::to_string(::getpid()) + "_" + std::to_string(calls++)))
                                 .string();
    const std::string redirect = capture == Capture::Stderr ? " 2>'" + file + "'" : " >'" + file + "' 2>&1";
    const int status = std::system(("(" + cmd + ")" + redirect).c_str());
    CommandResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.output = slurp(file);
    std::error_code ec;
    std::filesystem::remove(file, ec);
    return r;
}

} // namespace ferro::test
