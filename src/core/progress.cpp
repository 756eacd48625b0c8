#include "core/progress.h"

#include <atomic>
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

void StderrProgress::on_event(const ProgressEvent& event) {
  if (quiet_) return;
  std::string line;
  switch (event.kind) {
    case ProgressEvent::Kind::StageBegin: line = event.text + " ..."; break;
    case ProgressEvent::Kind::StageEnd: {
      char buf[64];
      std::snprintf(buf, sizeof buf, " done in %.2f s", event.seconds);
      line = event.text + buf;
      break;
    }
    case ProgressEvent::Kind::Message: line = event.text; break;
    case ProgressEvent::Kind::Step: return;
  }
  std::fprintf(stderr, "[unique3d] %s\n", line.c_str());
  std::fflush(stderr);
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
