#pragma once
// What the fuzz targets share (see tests/fuzz/README.md): the libFuzzer entry point every
// target defines, a private scratch file for readers that take a path, and `finding`, which
// turns a broken promise of a reader into a crash the fuzzer reports.
// Header-only: each target is one .cpp file plus the libraries it tests.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include <unistd.h>

/// libFuzzer's entry point: runs one input through the reader. Returns 0. Documented errors
/// of the reader are caught; anything else (another exception, a sanitizer report, a failed
/// `finding`) ends the process and is a finding.
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace ferro::fuzz {

/// A directory of this process's own under the temp directory, removed at exit.
class ScratchDir {
public:
    ScratchDir()
        : path_(std::filesystem::temp_directory_path() / ("ferro-fuzz-" + std::to_string(::getpid()))) {
        std::filesystem::create_directories(path_);
    }
    ~ScratchDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
};

/// Replaces the scratch file `name` by the input bytes and returns its path, for readers
/// that only take a path.
inline std::string writeInput(const std::string& name, const uint8_t* data, size_t size) {
    static const ScratchDir dir;
    const std::string path = (dir.path() / name).string();
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    if (!out) {
        std::fprintf(stderr, "fuzz harness: cannot write %s\n", path.c_str());
        std::abort();
    }
    return path;
}

/// A reader broke a promise (a non-finite value it guarantees finite, an index out of
/// range, ...): print why and abort, so libFuzzer saves the input as a crash.
[[noreturn]] inline void finding(const std::string& what) {
    std::fprintf(stderr, "FINDING: %s\n", what.c_str());
    std::fflush(stderr);
    std::abort();
}

/// The documented errors are one line: no line break, not even a lone carriage return.
inline void requireOneLine(const std::exception& e) {
    const std::string what = e.what();
    if (what.find_first_of("\r\n") != std::string::npos) finding("multi-line error: " + what);
}

} // namespace ferro::fuzz
