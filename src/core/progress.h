#pragma once
// Progress of long work, and its cancellation. Library code reports to the calling thread's
// ProgressListener: a StageTimer marks a stage's start and end, progress() sends a message and
// progress_step() a loop's step. Cancellation is cooperative: at every stage start and loop step the
// listener is asked whether to stop, and if so the work ends by throwing Cancelled. The CLI installs
// a listener that prints lines on stderr; a web page or a Python binding installs its own. Without one,
// the lines go to stderr unless set_progress_quiet(true) (tests and benches).
#include <chrono>
#include <cstdio>
#include <string>

#include "core/error.h"

namespace u3d {

struct ProgressEvent {
  enum class Kind { StageBegin, StageEnd, Message, Step };
  Kind kind = Kind::Message;
  std::string text;      // the stage's name, or the message
  double seconds = 0.0;  // StageEnd: the stage's time
  int step = 0;          // Step: 1-based step of `steps`, in the stage named by `text`
  int steps = 0;
};

class ProgressListener {
 public:
  virtual ~ProgressListener() = default;
  virtual void on_event(const ProgressEvent& event) = 0;
  // Polled at every stage start and loop step; true ends the work with Cancelled.
  virtual bool cancel_requested() { return false; }
};

// "[unique3d] name ..." when a stage starts, "[unique3d] name done in X s" when it ends, messages as
// they are. A loop's steps are printed only when the loop is slow: at most one line every
// `step_interval_seconds`, "[unique3d] denoise 3/30, 41 s, about 6 min 9 s left" (the time since the
// stage around the loop began, and the rest of this loop extrapolated from the time since it began: the
// stage's start, or the last step of the loop before it), and its last step if any was
// printed. Nothing when quiet. Lines go to `out` (stderr by default); times come from `now` (the steady
// clock; a test passes its own).
class StderrProgress : public ProgressListener {
 public:
  using Clock = std::chrono::steady_clock;
  explicit StderrProgress(bool quiet = false, double step_interval_seconds = 10.0, std::FILE* out = stderr,
                          Clock::time_point (*now)() = Clock::now)
      : quiet_(quiet), interval_(step_interval_seconds), out_(out), now_(now) {}
  void on_event(const ProgressEvent& event) override;

 private:
  bool quiet_;
  double interval_;
  std::FILE* out_;
  Clock::time_point (*now_)();
  Clock::time_point stage_begin_ = now_();  // the last StageBegin: where a loop's time starts
  Clock::time_point last_line_ = now_();
  Clock::time_point loop_begin_ = now_();  // where the current loop's time starts
  Clock::time_point last_step_time_ = now_();
  std::string loop_;  // the loop whose steps are being counted
  int last_step_ = 0;
  bool loop_printed_ = false;
};

// Makes `listener` the calling thread's listener while in scope; the previous one comes back after.
class ProgressScope {
 public:
  explicit ProgressScope(ProgressListener* listener);
  ~ProgressScope();
  ProgressScope(const ProgressScope&) = delete;
  ProgressScope& operator=(const ProgressScope&) = delete;

 private:
  ProgressListener* previous_;
};

// Thrown when the listener asked to stop.
class Cancelled : public Error {
 public:
  Cancelled() : Error("cancelled") {}
};

// The default listener (no ProgressScope): quiet or printing.
void set_progress_quiet(bool quiet);

void progress(const std::string& message);
void progress_step(const std::string& stage, int step, int steps);  // also checks for cancellation
void check_cancelled();                                             // throws Cancelled when the listener asks to stop

// Times a stage: reports its start on construction (after a cancellation check) and its end with the
// elapsed time on finish() or on destruction, unless an exception is leaving the stage.
class StageTimer {
 public:
  explicit StageTimer(std::string name, bool announce = true);
  ~StageTimer();
  double seconds() const;
  double finish();  // reports once; returns elapsed seconds

 private:
  std::string name_;
  std::chrono::steady_clock::time_point start_;
  int exceptions_;  // uncaught exceptions at construction
  bool finished_ = false;
};

}  // namespace u3d
