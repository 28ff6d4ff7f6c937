#include "sim/core/MachineMemory.hpp"

#include <fstream>
#include <sstream>

#include <unistd.h>

namespace ferro {

double availableMemoryBytes() {
    // MemAvailable: what can be allocated without swapping (free plus reclaimable cache).
    std::ifstream in("/proc/meminfo");
    std::string key;
    double kb = 0;
    while (in >> key >> kb) {
        if (key == "MemAvailable:") return kb * 1024.0;
        in.ignore(1 << 10, '\n');
    }
    const long pages = sysconf(_SC_AVPHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    return pages > 0 && size > 0 ? double(pages) * double(size) : 0.0;
}

std::string formatBytes(double b) {
    std::ostringstream o;
    o.precision(3);
    if (b >= 1e12) o << b / 1e12 << " TB";
    else if (b >= 1e9) o << b / 1e9 << " GB";
    else o << b / 1e6 << " MB";
    return o.str();
}

} // namespace ferro
