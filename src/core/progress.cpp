#include "core/progress.h"

#include <atomic>
#include <cstdio>

namespace u3d {

static std::atomic<bool> g_quiet{false};

void set_progress_quiet(bool quiet) { g_quiet = quiet; }
bool progress_quiet() { return g_quiet; }

void progress(const std::string& message) {
  if (g_quiet) return;
  std::fprintf(stderr, "[unique3d] %s\n", message.c_str());
  std::fflush(stderr);
}

StageTimer::StageTimer(std::string name, bool announce) : name_(std::move(name)), start_(std::chrono::steady_clock::now()) {
  if (announce) progress(name_ + " ...");
}

StageTimer::~StageTimer() {
  if (!finished_) finish();
}

double StageTimer::seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

double StageTimer::finish() {
  double s = seconds();
  if (!finished_) {
    finished_ = true;
    char buf[64];
    std::snprintf(buf, sizeof buf, " done in %.2f s", s);
    progress(name_ + buf);
  }
  return s;
}

}  // namespace u3d
