#include "core/progress.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>

namespace u3d {
namespace {

std::atomic<bool> g_quiet{false};
thread_local ProgressListener* t_listener = nullptr;

ProgressListener& listener() {
  if (t_listener) return *t_listener;
  thread_local StderrProgress printing(false), quiet(true);
  return g_quiet ? static_cast<ProgressListener&>(quiet) : printing;
}

void emit(ProgressEvent event) { listener().on_event(event); }

}  // namespace

namespace {

// "41 s", "6 min 9 s", "2 h 5 min".
std::string duration_text(double seconds) {
  const long s = std::lround(std::max(seconds, 0.0));
  char buf[48];
  if (s < 60)
    std::snprintf(buf, sizeof buf, "%ld s", s);
  else if (s < 3600)
    std::snprintf(buf, sizeof buf, "%ld min %ld s", s / 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld h %ld min", s / 3600, (s % 3600) / 60);
  return buf;
}

}  // namespace

void StderrProgress::on_event(const ProgressEvent& event) {
  if (quiet_) return;
  const Clock::time_point now = now_();
  std::string line;
  switch (event.kind) {
    case ProgressEvent::Kind::StageBegin:
      stage_begin_ = last_line_ = loop_begin_ = last_step_time_ = now;
      loop_.clear();
      line = event.text + " ...";
      break;
    case ProgressEvent::Kind::StageEnd: {
      char buf[64];
      std::snprintf(buf, sizeof buf, " done in %.2f s", event.seconds);
      line = event.text + buf;
      break;
    }
    case ProgressEvent::Kind::Message: line = event.text; break;
    case ProgressEvent::Kind::Step: {
      if (event.text != loop_ || event.step <= last_step_) {  // a new loop
        loop_ = event.text;
        loop_printed_ = false;
        loop_begin_ = last_step_time_;  // a loop run after another one starts where that one ended
      }
      last_step_ = event.step;
      last_step_time_ = now;
      const bool last = event.step >= event.steps;
      if (!(std::chrono::duration<double>(now - last_line_).count() >= interval_ || (last && loop_printed_))) return;
      loop_printed_ = true;
      const double elapsed = std::chrono::duration<double>(now - stage_begin_).count();
      line = event.text + " " + std::to_string(event.step) + "/" + std::to_string(event.steps) + ", " +
             duration_text(elapsed);
      const double loop_elapsed = std::chrono::duration<double>(now - loop_begin_).count();
      if (!last && event.step > 0)
        line += ", about " + duration_text(loop_elapsed / event.step * (event.steps - event.step)) + " left";
      break;
    }
  }
  last_line_ = now;
  std::fprintf(out_, "[unique3d] %s\n", line.c_str());
  std::fflush(out_);
}

ProgressScope::ProgressScope(ProgressListener* l) : previous_(t_listener) { t_listener = l; }
ProgressScope::~ProgressScope() { t_listener = previous_; }

void set_progress_quiet(bool quiet) { g_quiet = quiet; }

void progress(const std::string& message) { emit({ProgressEvent::Kind::Message, message}); }

void progress_step(const std::string& stage, int step, int steps) {
  emit({ProgressEvent::Kind::Step, stage, 0.0, step, steps});
  check_cancelled();
}

void check_cancelled() {
  if (listener().cancel_requested()) throw Cancelled();
}

StageTimer::StageTimer(std::string name, bool announce)
    : name_(std::move(name)), exceptions_(std::uncaught_exceptions()) {
  check_cancelled();
  if (announce) emit({ProgressEvent::Kind::StageBegin, name_});
  start_ = std::chrono::steady_clock::now();
}

StageTimer::~StageTimer() {
  // A stage left by an exception did not finish: only the error is reported.
  if (!finished_ && std::uncaught_exceptions() == exceptions_) finish();
}

double StageTimer::seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

double StageTimer::finish() {
  const double s = seconds();
  if (!finished_) {
    finished_ = true;
    emit({ProgressEvent::Kind::StageEnd, name_, s});
  }
  return s;
}

}  // namespace u3d
