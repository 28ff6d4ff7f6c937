#pragma once
// The machine's memory, for the up-front size checks of ferro-sim (the particles a scene
// asks for) and ferro-surface (the grid a voxel size asks for): a run that cannot fit is
// refused with the key named before anything is allocated, rather than ending in
// std::bad_alloc or the OOM killer after minutes.
#include <string>

namespace ferro {

/// MemAvailable of /proc/meminfo (or sysconf's available pages) [bytes]; 0 if unknown.
double availableMemoryBytes();

/// "1.23 GB", "456 MB", "2.1 TB": three significant digits.
std::string formatBytes(double bytes);

} // namespace ferro
