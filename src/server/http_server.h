#pragma once
// `unique3d serve`: an HTTP server (cpp-httplib) with the page and a small JSON API over the job queue
// (docs/server.md). The handlers only translate between HTTP and the jobs: what a job does is in
// server/job_runner.h, what a client may upload in server/job_inputs.h and server/job_options.h.
// Every request that is not understood is answered 4xx with {"error": message}; nothing a client sends
// names a file on the server.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>

#include "server/job_inputs.h"
#include "server/job_queue.h"

namespace u3d::server {

struct ServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;                  // 0: any free port
  std::filesystem::path models;     // the --models folder; empty: generate jobs are refused
  std::filesystem::path jobs_dir;   // every job's folder is made here
  size_t max_upload_bytes = 64u << 20;
  size_t max_waiting_jobs = 8;
  size_t max_event_streams = 64;    // event streams open at once (each holds a thread)
  int timeout_seconds = 30;         // reading a request, writing a response
  UploadLimits limits;
  bool quiet = false;               // no lines on stderr for jobs
};

// The default jobs folder: $XDG_CACHE_HOME/unique3d/jobs, or ~/.cache/unique3d/jobs.
std::filesystem::path default_jobs_dir();

class Server {
 public:
  // `runner` runs each job (server/job_runner.h's run_job; tests may pass another).
  explicit Server(ServerOptions options, JobRunner runner);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Makes the jobs folder and binds the socket; returns the port. An Error when either fails.
  int bind();
  // Serves until stop() (from another thread or a signal handler's thread).
  void serve();
  void stop();
  std::string url() const;  // "http://127.0.0.1:8080/"

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Runs the server in the foreground until SIGINT or SIGTERM, printing its URL.
void run_server(const ServerOptions& options);

}  // namespace u3d::server
