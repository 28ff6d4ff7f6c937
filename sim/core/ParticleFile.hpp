#pragma once
// Particle files: binary little-endian PLY, one `vertex` element per file.
//
// Ferro writes float properties `x y z vx vy vz density` (and later `hx hy hz mx my mz`)
// and `comment key value` header lines (frame, time, spacing, ...). The reader accepts
// any PLY whose first element is `vertex` (ascii or binary of either endianness, any
// scalar type, extra elements after it ignored), so particle files of other simulators
// can be meshed too. Writes are atomic: a temporary file in the same directory is
// renamed over the target only once complete.
#include "sim/core/Types.hpp"

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace ferro {

class ParticleFileError : public std::runtime_error {
public:
    /// Control characters in `what` (a quoted comment value may hold a lone "\r") are
    /// escaped (\r, \xNN), so that what() is one line.
    explicit ParticleFileError(const std::string& what);
};

/// Columns of per-particle float data plus header metadata.
struct ParticleTable {
    std::vector<std::string> names;              ///< property names, in file order
    std::vector<float> values;                   ///< row-major: values[row * names.size() + col]
    std::vector<std::pair<std::string, std::string>> comments; ///< `comment key value` lines, in order
    /// Columns the writer stores as 16-bit integers (PLY `short`) with a scale of the
    /// column's largest magnitude / 32767, named in a `comment quantized NAME SCALE` line:
    /// half the bytes of a float, an absolute error up to half a step (1.5e-5 of the
    /// frame's largest value of that column). readParticleFile applies the scale and drops
    /// those comment lines, so a table read back holds plain floats and an empty list.
    std::vector<std::string> quantized;

    size_t rows() const { return names.empty() ? 0 : values.size() / names.size(); }
    size_t columns() const { return names.size(); }
    /// Column index of `name`, or -1.
    int column(const std::string& name) const;
    float at(size_t row, int col) const { return values[row * names.size() + size_t(col)]; }
    /// Value of the first `comment key value`, or `def`.
    std::string comment(const std::string& key, const std::string& def = {}) const;
    double commentNumber(const std::string& key, double def) const;
    void setComment(const std::string& key, const std::string& value);
    /// Gathers three columns as vectors (e.g. "x","y","z"); throws if one is missing.
    std::vector<Vec3> vec3(const std::string& a, const std::string& b, const std::string& c) const;
};

/// Writes `table` as binary little-endian PLY to `path` atomically (temp file + rename).
void writeParticleFile(const std::string& path, const ParticleTable& table);
/// Reads a PLY file's vertex element. Throws ParticleFileError with a one-line reason.
ParticleTable readParticleFile(const std::string& path);

/// `pattern` with a `{:04}`-style or printf `%04d` placeholder expanded for `frame`.
std::string framePath(const std::string& pattern, int frame);

/// An inclusive frame range, 0 <= first <= last <= kMaxFrame.
struct FrameRange {
    int first = 0;
    int last = 0;
    /// Number of frames; int64 so that callers never overflow when they multiply it.
    int64_t count() const { return int64_t(last) - int64_t(first) + 1; }
};

/// Largest frame number a range may name: seven digits, far beyond any shot, and small enough
/// that frame arithmetic (last + 1, counts, file names) never overflows an int.
constexpr int kMaxFrame = 9999999;

/// Parses `--frames` text: "A:B" (inclusive) or "A" (one frame), optional spaces around the
/// numbers. Throws std::invalid_argument with a one-line reason (naming the text) for
/// anything that is not two non-negative integers with A <= B <= kMaxFrame.
FrameRange parseFrameRange(const std::string& text);

} // namespace ferro
