#include "core/memory.h"

#include <malloc.h>

#include <algorithm>
#include <fstream>
#include <string>

namespace u3d {

namespace {
constexpr int kOwnMappingBytes = 256 << 20;
}  // namespace

void keep_freed_memory_for_reuse() {
  mallopt(M_MMAP_THRESHOLD, kOwnMappingBytes);  // a fixed threshold: glibc no longer raises it by itself
  mallopt(M_TRIM_THRESHOLD, -1);                // glibc reads it as size_t: never trim
}

void release_freed_memory() { malloc_trim(0); }

double available_memory_mib() {
  double available = 0.0;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string line; std::getline(meminfo, line);)
    if (line.rfind("MemAvailable:", 0) == 0) available = std::stod(line.substr(13)) / 1024.0;  // "... kB"
  // cgroup v2: /proc/self/cgroup is "0::/path"; its memory.max is a byte count or "max".
  std::ifstream cgroup("/proc/self/cgroup");
  std::string entry;
  if (std::getline(cgroup, entry) && entry.rfind("0::", 0) == 0) {
    const std::string dir = "/sys/fs/cgroup" + entry.substr(3);
    std::ifstream max_file(dir + "/memory.max"), current_file(dir + "/memory.current");
    std::string max, current;
    if (max_file >> max && current_file >> current && max != "max") {
      const double left = (std::stod(max) - std::stod(current)) / (1024.0 * 1024.0);
      available = available > 0.0 ? std::min(available, left) : left;
    }
  }
  return std::max(available, 0.0);
}

}  // namespace u3d
