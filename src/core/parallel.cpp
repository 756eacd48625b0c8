#include "core/parallel.h"

#include <omp.h>

#include <cstdlib>
#include <thread>

namespace u3d {

int default_thread_count() {
  if (const char* env = std::getenv("UNIQUE3D_THREADS")) {
    int n = std::atoi(env);
    if (n > 0) return n;
  }
  unsigned hw = std::thread::hardware_concurrency();
  return hw > 0 ? int(hw) : 1;
}

void configure_threads(int threads) {
  if (threads <= 0) threads = default_thread_count();
  omp_set_num_threads(threads);
  omp_set_max_active_levels(1);
}

}  // namespace u3d
