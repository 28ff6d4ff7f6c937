#include "sim/core/StageErrors.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace ferro {

void requireReadable(const std::string& path)
{
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw InputMissingError(path + ": cannot open: is a directory");
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw InputMissingError(path + ": cannot open: " + std::strerror(errno));
}

void refuseToOverwriteInputs(const std::string& outputOption, const std::string& out,
                             const std::vector<std::string>& inputs)
{
    if (out.empty()) return;
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path outPath = fs::weakly_canonical(fs::absolute(out, ec), ec);
    for (const std::string& in : inputs) {
        if (in.empty()) continue;
        std::error_code ec2;
        const bool same = fs::weakly_canonical(fs::absolute(in, ec2), ec2) == outPath ||
                          (fs::exists(out, ec2) && fs::equivalent(in, out, ec2));
        if (same)
            throw BadInputError(outputOption + " '" + out + "' is the input '" + in +
                                "': refusing to overwrite it");
    }
}

} // namespace ferro
