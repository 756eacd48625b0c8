#pragma once
// The bridge between the facade's progress and cancellation (core/progress.h) and Python: a
// ProgressListener that hands each event to an optional Python callable, and asks to stop when the
// callable raised, when a CancelToken was cancelled (from any thread), or when a signal handler raised
// (Ctrl-C's KeyboardInterrupt). The facade runs with the GIL released; the listener takes it only to
// call Python. After the run, rethrow_python_error() raises what Python raised in place of Cancelled.
#include <pybind11/pybind11.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "core/progress.h"

namespace u3d::python {

// `unique3d.CancelToken`: cancel() from any thread stops the runs it was given to at their next check.
class CancelToken {
 public:
  void cancel() { cancelled_.store(true); }
  bool cancelled() const { return cancelled_.load(); }

 private:
  std::atomic<bool> cancelled_{false};
};

// `unique3d.ProgressEvent`: one event as Python sees it.
struct PythonEvent {
  std::string kind;      // "stage_begin", "stage_end", "message", "step"
  std::string text;      // the stage's name or the message
  double seconds = 0.0;  // stage_end: the stage's time
  int step = 0;          // step: 1-based, of `steps`
  int steps = 0;
  std::optional<double> seconds_left;  // step: the rest of the loop extrapolated from its steps so far
};

class PythonProgress : public ProgressListener {
 public:
  // `callback`: None or a callable taking one ProgressEvent; `token`: may be null. Built with the GIL held.
  PythonProgress(pybind11::object callback, std::shared_ptr<CancelToken> token);
  ~PythonProgress() override;
  PythonProgress(const PythonProgress&) = delete;
  PythonProgress& operator=(const PythonProgress&) = delete;

  void on_event(const ProgressEvent& event) override;
  bool cancel_requested() override;

  // With the GIL held, after the run: raises the exception the callback or a signal handler raised, if
  // any (otherwise returns).
  void rethrow_python_error();

 private:
  using Clock = std::chrono::steady_clock;
  void capture_python_error();  // with the GIL held, from a caught error_already_set's state

  pybind11::object callback_;
  std::shared_ptr<CancelToken> token_;
  std::optional<pybind11::error_already_set> error_;
  std::atomic<bool> failed_{false};
  Clock::time_point last_signal_check_ = Clock::now();
  Clock::time_point stage_begin_ = Clock::now();
  Clock::time_point loop_begin_ = Clock::now();
  Clock::time_point last_step_time_ = Clock::now();
  std::string loop_;
};

}  // namespace u3d::python
