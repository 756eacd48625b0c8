#include "server/job_queue.h"

#include <algorithm>
#include <exception>

#include "core/progress.h"

namespace u3d::server {

JobQueue::JobQueue(size_t max_waiting, JobRunner runner)
    : max_waiting_(max_waiting), runner_(std::move(runner)), worker_([this] { work(); }) {}

JobQueue::~JobQueue() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    for (const auto& job : waiting_) job->set_state(JobState::Cancelled, "the server stopped");
    waiting_.clear();
    if (running_) running_->request_cancel();
  }
  work_ready_.notify_all();
  worker_.join();
  wake_all();
}

bool JobQueue::has_room() const {
  std::lock_guard lock(mutex_);
  return !stopping_ && waiting_.size() < max_waiting_;
}

void JobQueue::submit(const std::shared_ptr<Job>& job) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || waiting_.size() >= max_waiting_)
      throw QueueFull("the queue is full (" + std::to_string(max_waiting_) +
                      " jobs waiting); try again when one has finished");
    jobs_[job->id()] = job;
    waiting_.push_back(job);
    job->add_event("queue", {{"position", waiting_.size()}});
  }
  work_ready_.notify_one();
}

std::shared_ptr<Job> JobQueue::find(const std::string& id) const {
  std::lock_guard lock(mutex_);
  const auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second;
}

int JobQueue::position(const Job& job) const {
  std::lock_guard lock(mutex_);
  if (running_.get() == &job) return 0;
  for (size_t i = 0; i < waiting_.size(); ++i)
    if (waiting_[i].get() == &job) return int(i) + 1;
  return -1;
}

size_t JobQueue::waiting() const {
  std::lock_guard lock(mutex_);
  return waiting_.size();
}

bool JobQueue::running() const {
  std::lock_guard lock(mutex_);
  return running_ != nullptr;
}

void JobQueue::cancel(Job& job) {
  std::lock_guard lock(mutex_);
  const auto it = std::find_if(waiting_.begin(), waiting_.end(), [&](const auto& j) { return j.get() == &job; });
  if (it != waiting_.end()) {
    waiting_.erase(it);
    job.set_state(JobState::Cancelled);
    announce_positions();
  } else if (running_.get() == &job) {
    job.request_cancel();
  }
}

void JobQueue::announce_positions() {
  for (size_t i = 0; i < waiting_.size(); ++i) waiting_[i]->add_event("queue", {{"position", i + 1}});
}

void JobQueue::wake_all() const {
  std::lock_guard lock(mutex_);
  for (const auto& [id, job] : jobs_) job->wake();
}

void JobQueue::work() {
  for (;;) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock lock(mutex_);
      work_ready_.wait(lock, [&] { return stopping_ || !waiting_.empty(); });
      if (stopping_) return;
      job = running_ = waiting_.front();
      waiting_.pop_front();
      job->set_state(JobState::Running);
      announce_positions();
    }
    try {
      runner_(*job);
      job->set_state(JobState::Done);
    } catch (const Cancelled&) {
      job->set_state(JobState::Cancelled);
    } catch (const Error& e) {
      job->set_state(JobState::Failed, e.what());
    } catch (const std::exception& e) {
      job->set_state(JobState::Failed, std::string("internal error: ") + e.what());
    }
    std::lock_guard lock(mutex_);
    running_.reset();
  }
}

}  // namespace u3d::server
