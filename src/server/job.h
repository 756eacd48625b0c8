#pragma once
// One job of `unique3d serve`: what to run (a reconstruction from an uploaded view set, or a whole
// generate from an uploaded photo), its state, the stream of events a page follows (state changes,
// stages, steps, result files), the result files a client may fetch, and its cancellation. Every
// method is safe to call from the worker and from any number of HTTP threads at once.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/generate.h"
#include "pipeline/reconstruct.h"

namespace u3d::server {

enum class JobKind { Reconstruct, Generate };
enum class JobState { Queued, Running, Done, Failed, Cancelled };

const char* job_kind_name(JobKind kind);     // "reconstruct", "generate"
const char* job_state_name(JobState state);  // "queued", "running", "done", "failed", "cancelled"

// `text` with every "<folder>/" removed: messages name a job's files as the client knows them, by
// their names inside the job's folder.
std::string without_folder(std::string text, const std::filesystem::path& folder);

// What a job runs: one of the two facade requests, whose input and output paths lie in the job's folder.
struct JobSpec {
  JobKind kind = JobKind::Reconstruct;
  ReconstructRequest reconstruct;
  GenerateRequest generate;
  nlohmann::json options;  // the options as the client set them, echoed in the job's status
};

// One event of a job's stream; `index` counts from 0 in the order the events happened.
struct JobEvent {
  size_t index = 0;
  std::string type;  // "state", "stage", "step", "message", "file"
  nlohmann::json data;
};

// A file of a job that clients may fetch: a name the server chose, never one a client sent.
struct JobFile {
  std::string name;
  std::filesystem::path path;
};

class Job {
 public:
  Job(std::string id, std::filesystem::path folder, JobSpec spec);

  const std::string& id() const { return id_; }
  const std::filesystem::path& folder() const { return folder_; }
  const JobSpec& spec() const { return spec_; }

  JobState state() const;
  bool finished() const;  // done, failed or cancelled
  // Moves to `state` (with the error's message for Failed) and records a "state" event.
  void set_state(JobState state, const std::string& error = {});
  void add_event(const std::string& type, nlohmann::json data);
  // Makes a file fetchable and records a "file" event; a name already added is left as it was.
  void add_file(const std::string& name, const std::filesystem::path& path);
  std::optional<JobFile> file(const std::string& name) const;
  void set_summary(nlohmann::json summary);

  // {id, kind, state, error, options, created, seconds, files: [names], summary}.
  nlohmann::json status() const;

  // The events from `from` on. When there are none yet and the job is still going, waits up to
  // `timeout` for one. `ended`: the job finished and these are its last events.
  struct Events {
    std::vector<JobEvent> events;
    bool ended = false;
  };
  Events events_since(size_t from, std::chrono::milliseconds timeout) const;
  // Wakes every events_since that is waiting (the server is stopping).
  void wake() const;

  void request_cancel() { cancel_.store(true); }
  bool cancel_requested() const { return cancel_.load(); }

 private:
  void add_event_locked(const std::string& type, nlohmann::json data);

  const std::string id_;
  const std::filesystem::path folder_;
  const JobSpec spec_;
  const std::chrono::system_clock::time_point created_ = std::chrono::system_clock::now();
  std::atomic<bool> cancel_{false};

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  JobState state_ = JobState::Queued;
  std::string error_;
  std::chrono::steady_clock::time_point started_, ended_;
  std::vector<JobEvent> events_;
  std::vector<JobFile> files_;
  nlohmann::json summary_;
};

}  // namespace u3d::server
