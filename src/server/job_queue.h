#pragma once
// The jobs of `unique3d serve` and the one worker thread that runs them in the order they came: a job
// uses every core, so two at once would only slow both. At most `max_waiting` jobs wait behind the
// running one; a submission beyond that is refused (QueueFull) rather than left to wait for hours.
// Jobs stay known (status, events, files) until the server stops. A waiting job gets a "queue" event
// with its place in the line (1: next) whenever that changes.
#include <cstddef>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/error.h"
#include "server/job.h"

namespace u3d::server {

// The queue is full: the client should try again later (HTTP 503).
class QueueFull : public Error {
 public:
  using Error::Error;
};

// Runs one job to its end: returns when it succeeded, throws Error (it failed, with a message for the
// client) or Cancelled. Called on the worker thread.
using JobRunner = std::function<void(Job& job)>;

class JobQueue {
 public:
  JobQueue(size_t max_waiting, JobRunner runner);
  ~JobQueue();  // cancels the running job, drops the waiting ones, joins the worker
  JobQueue(const JobQueue&) = delete;
  JobQueue& operator=(const JobQueue&) = delete;

  // Whether a submission would be accepted now (a cheap check before reading an upload).
  bool has_room() const;
  // Queues the job; QueueFull when max_waiting jobs are waiting already.
  void submit(const std::shared_ptr<Job>& job);
  std::shared_ptr<Job> find(const std::string& id) const;
  // 0 for the running job, k for the k-th waiting one, -1 for a job that is neither.
  int position(const Job& job) const;
  size_t waiting() const;
  bool running() const;
  // A waiting job is cancelled at once; the running one is asked to stop (the facade polls at every
  // stage and step). A finished job stays as it is.
  void cancel(Job& job);
  // Wakes every event stream of every job (the server is stopping).
  void wake_all() const;

 private:
  void work();
  void announce_positions();  // with mutex_ held

  const size_t max_waiting_;
  const JobRunner runner_;
  mutable std::mutex mutex_;
  std::condition_variable work_ready_;
  std::map<std::string, std::shared_ptr<Job>> jobs_;
  std::deque<std::shared_ptr<Job>> waiting_;
  std::shared_ptr<Job> running_;
  bool stopping_ = false;
  std::thread worker_;
};

}  // namespace u3d::server
