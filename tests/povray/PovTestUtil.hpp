#pragma once
// Helpers shared by the ferro-pov tests: scratch directories, shell commands, a UV sphere
// built in memory, and a reader for the PPM images POV-Ray writes with +FP.
#include "sim/core/TriangleMesh.hpp"
#include "sim/core/Constants.hpp"
#include "tests/TestUtil.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

namespace ferro::povtest {

namespace fs = std::filesystem;

inline const std::string kBin = std::string(FERRO_BINARY_DIR) + "/bin/";
inline const std::string kSource = FERRO_SOURCE_DIR;

using test::slurp;
using test::spit;
using Result = test::CommandResult;

/// Runs `cmd` with /bin/sh, returning its exit code and its standard output and error
/// together (in `output`).
inline Result run(const std::string& cmd) { return test::runCommand(cmd, test::Capture::StdoutAndStderr); }

/// An empty scratch directory under the build tree.
inline fs::path freshDir(const std::string& name)
{
    const fs::path dir = fs::path(FERRO_BINARY_DIR) / "test-scratch" / "povray" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

/// A UV sphere of `radius` [m] around `center` with exact outward normals.
inline TriangleMesh sphereMesh(const Vec3& center, float radius, int segments = 32, int rings = 16)
{
    TriangleMesh m;
    const double pi = kPi;
    for (int j = 0; j <= rings; ++j) {
        const double th = pi * j / rings;
        for (int i = 0; i < segments; ++i) {
            const double ph = 2 * pi * i / segments;
            const Vec3 n(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)), float(std::cos(th)));
            m.vertices.push_back(center + radius * n);
            m.normals.push_back(n);
        }
    }
    for (int j = 0; j < rings; ++j)
        for (int i = 0; i < segments; ++i) {
            const uint32_t a = j * segments + i, b = j * segments + (i + 1) % segments;
            const uint32_t c = (j + 1) * segments + i, d = (j + 1) * segments + (i + 1) % segments;
            m.triangles.push_back({a, b, c});
            m.triangles.push_back({b, d, c});
        }
    return m;
}

/// An 8-bit RGB image; pixel values in [0, 1].
struct Image {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb;
    /// Mean brightness of the pixels within `r` of (col, row).
    double brightness(int col, int row, int r = 1) const
    {
        double sum = 0;
        int n = 0;
        for (int y = row - r; y <= row + r; ++y)
            for (int x = col - r; x <= col + r; ++x) {
                if (x < 0 || y < 0 || x >= width || y >= height) continue;
                const size_t i = 3 * (size_t(y) * width + x);
                sum += (rgb[i] + rgb[i + 1] + rgb[i + 2]) / (3 * 255.0);
                ++n;
            }
        return n ? sum / n : 0;
    }
};

/// Reads a binary PPM (P6, maxval 255), as POV-Ray writes with +FP.
inline Image readPpm(const fs::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot open " + path.string());
    auto token = [&]() {
        std::string t;
        char c;
        while (in.get(c)) {
            if (c == '#') { std::string line; std::getline(in, line); continue; }
            if (std::isspace(static_cast<unsigned char>(c))) { if (!t.empty()) break; continue; }
            t += c;
        }
        return t;
    };
    if (token() != "P6") throw std::runtime_error(path.string() + ": not a binary PPM");
    Image img;
    img.width = std::stoi(token());
    img.height = std::stoi(token());
    if (std::stoi(token()) != 255) throw std::runtime_error(path.string() + ": not 8 bits per channel");
    img.rgb.resize(size_t(img.width) * img.height * 3);
    in.read(reinterpret_cast<char*>(img.rgb.data()), std::streamsize(img.rgb.size()));
    if (!in) throw std::runtime_error(path.string() + ": truncated");
    return img;
}

/// Renders frame `frame` of the shot in `dir` with the real povray binary, headless, into
/// dir/name.ppm. Returns povray's exit code and output.
inline Result renderFrame(const fs::path& dir, int frame, int width, int height, const std::string& name)
{
    return run("cd '" + dir.string() + "' && povray render.ini -D +FP Declare=FerroFrame=" + std::to_string(frame) +
               " +W" + std::to_string(width) + " +H" + std::to_string(height) + " +O" + name + ".ppm");
}

} // namespace ferro::povtest
