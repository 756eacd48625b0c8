#include "python/python_progress.h"

namespace py = pybind11;

namespace u3d::python {

namespace {

// How often the run looks for a pending signal (Ctrl-C): each look takes the GIL.
constexpr auto kSignalCheckInterval = std::chrono::milliseconds(50);

const char* kind_name(ProgressEvent::Kind kind) {
  switch (kind) {
    case ProgressEvent::Kind::StageBegin: return "stage_begin";
    case ProgressEvent::Kind::StageEnd: return "stage_end";
    case ProgressEvent::Kind::Message: return "message";
    case ProgressEvent::Kind::Step: return "step";
  }
  return "message";
}

}  // namespace

PythonProgress::PythonProgress(py::object callback, std::shared_ptr<CancelToken> token)
    : callback_(std::move(callback)), token_(std::move(token)) {}

PythonProgress::~PythonProgress() {
  // The callable and a captured error are Python objects: released with the GIL held.
  py::gil_scoped_acquire gil;
  error_.reset();
  callback_ = py::object();
}

void PythonProgress::on_event(const ProgressEvent& event) {
  const auto now = Clock::now();
  PythonEvent e;
  e.kind = kind_name(event.kind);
  e.text = event.text;
  e.seconds = event.seconds;
  e.step = event.step;
  e.steps = event.steps;
  if (event.kind == ProgressEvent::Kind::StageBegin) {
    stage_begin_ = loop_begin_ = last_step_time_ = now;
    loop_.clear();
  } else if (event.kind == ProgressEvent::Kind::Step) {
    if (event.text != loop_) {  // a new loop starts where the stage or the last step before it ended
      loop_ = event.text;
      loop_begin_ = last_step_time_;
    }
    last_step_time_ = now;
    if (event.step > 0 && event.steps >= event.step) {
      const double elapsed = std::chrono::duration<double>(now - loop_begin_).count();
      e.seconds_left = elapsed / event.step * (event.steps - event.step);
    }
  }
  if (failed_.load() || callback_.is_none()) return;
  py::gil_scoped_acquire gil;
  try {
    callback_(std::move(e));
  } catch (py::error_already_set& error) {
    error_.emplace(std::move(error));
    failed_.store(true);
  }
}

bool PythonProgress::cancel_requested() {
  if (failed_.load() || (token_ && token_->cancelled())) return true;
  const auto now = Clock::now();
  if (now - last_signal_check_ < kSignalCheckInterval) return false;
  last_signal_check_ = now;
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) capture_python_error();
  return failed_.load();
}

void PythonProgress::capture_python_error() {
  error_.emplace();  // takes the error indicator PyErr_CheckSignals set
  failed_.store(true);
}

void PythonProgress::rethrow_python_error() {
  if (!error_) return;
  py::error_already_set error = std::move(*error_);
  error_.reset();
  failed_.store(false);
  throw error;
}

}  // namespace u3d::python
