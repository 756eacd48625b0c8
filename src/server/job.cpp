#include "server/job.h"

#include <ctime>

namespace u3d::server {

const char* job_kind_name(JobKind kind) { return kind == JobKind::Reconstruct ? "reconstruct" : "generate"; }

const char* job_state_name(JobState state) {
  switch (state) {
    case JobState::Queued: return "queued";
    case JobState::Running: return "running";
    case JobState::Done: return "done";
    case JobState::Failed: return "failed";
    case JobState::Cancelled: return "cancelled";
  }
  return "unknown";
}

std::string without_folder(std::string text, const std::filesystem::path& folder) {
  const std::string prefix = folder.string() + "/";
  for (size_t at; (at = text.find(prefix)) != std::string::npos;) text.erase(at, prefix.size());
  return text;
}

Job::Job(std::string id, std::filesystem::path folder, JobSpec spec)
    : id_(std::move(id)), folder_(std::move(folder)), spec_(std::move(spec)) {
  std::lock_guard lock(mutex_);
  add_event_locked("state", {{"state", job_state_name(state_)}});
}

JobState Job::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

bool Job::finished() const {
  const JobState s = state();
  return s == JobState::Done || s == JobState::Failed || s == JobState::Cancelled;
}

void Job::set_state(JobState state, const std::string& error) {
  std::lock_guard lock(mutex_);
  state_ = state;
  error_ = error;
  const auto now = std::chrono::steady_clock::now();
  if (state == JobState::Running) started_ = now;
  nlohmann::json data = {{"state", job_state_name(state)}};
  if (state == JobState::Done || state == JobState::Failed || state == JobState::Cancelled) {
    ended_ = now;
    if (started_.time_since_epoch().count() != 0)
      data["seconds"] = std::chrono::duration<double>(ended_ - started_).count();
  }
  if (!error.empty()) data["error"] = error;
  add_event_locked("state", std::move(data));
}

void Job::add_event(const std::string& type, nlohmann::json data) {
  std::lock_guard lock(mutex_);
  add_event_locked(type, std::move(data));
}

void Job::add_event_locked(const std::string& type, nlohmann::json data) {
  events_.push_back({events_.size(), type, std::move(data)});
  changed_.notify_all();
}

void Job::add_file(const std::string& name, const std::filesystem::path& path) {
  std::lock_guard lock(mutex_);
  for (const JobFile& f : files_)
    if (f.name == name) return;
  files_.push_back({name, path});
  add_event_locked("file", {{"name", name}, {"url", "/api/jobs/" + id_ + "/files/" + name}});
}

std::optional<JobFile> Job::file(const std::string& name) const {
  std::lock_guard lock(mutex_);
  for (const JobFile& f : files_)
    if (f.name == name) return f;
  return std::nullopt;
}

void Job::set_summary(nlohmann::json summary) {
  std::lock_guard lock(mutex_);
  summary_ = std::move(summary);
}

nlohmann::json Job::status() const {
  std::lock_guard lock(mutex_);
  char created[32];
  const std::time_t t = std::chrono::system_clock::to_time_t(created_);
  std::tm utc{};
  gmtime_r(&t, &utc);
  std::strftime(created, sizeof created, "%Y-%m-%dT%H:%M:%SZ", &utc);
  nlohmann::json j = {{"id", id_},
                      {"kind", job_kind_name(spec_.kind)},
                      {"state", job_state_name(state_)},
                      {"options", spec_.options},
                      {"created", created},
                      {"files", nlohmann::json::array()}};
  if (!error_.empty()) j["error"] = error_;
  if (started_.time_since_epoch().count() != 0) {
    const auto end = ended_.time_since_epoch().count() != 0 ? ended_ : std::chrono::steady_clock::now();
    j["seconds"] = std::chrono::duration<double>(end - started_).count();
  }
  for (const JobFile& f : files_)
    j["files"].push_back({{"name", f.name}, {"url", "/api/jobs/" + id_ + "/files/" + f.name}});
  if (!summary_.is_null()) j["summary"] = summary_;
  return j;
}

Job::Events Job::events_since(size_t from, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  const auto is_finished = [&] {
    return state_ == JobState::Done || state_ == JobState::Failed || state_ == JobState::Cancelled;
  };
  if (from >= events_.size() && !is_finished())
    changed_.wait_for(lock, timeout, [&] { return from < events_.size() || is_finished(); });
  Events out;
  for (size_t i = from; i < events_.size(); ++i) out.events.push_back(events_[i]);
  out.ended = is_finished();
  return out;
}

void Job::wake() const {
  std::lock_guard lock(mutex_);
  changed_.notify_all();
}

}  // namespace u3d::server
