#pragma once
// Progress lines for long work, on stderr so stdout stays machine-readable. Stages print when they
// start and how long they took; quiet mode (tests, --quiet) silences them.
#include <chrono>
#include <string>

namespace u3d {

void set_progress_quiet(bool quiet);
bool progress_quiet();

// printf-like line "[unique3d] message" on stderr unless quiet.
void progress(const std::string& message);

// Times a stage: prints "name ..." on construction and "name done in X s" on finish()/destruction.
class StageTimer {
 public:
  explicit StageTimer(std::string name, bool announce = true);
  ~StageTimer();
  double seconds() const;
  double finish();  // prints once; returns elapsed seconds

 private:
  std::string name_;
  std::chrono::steady_clock::time_point start_;
  bool finished_ = false;
};

}  // namespace u3d
