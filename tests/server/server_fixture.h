#pragma once
// A `unique3d serve` server in the test process (server/http_server.h) on a free loopback port, with a
// jobs folder of its own, and what the server tests share: an HTTP client, the bundled example's views as
// an upload, an event-stream reader, and runners that stand in for the real one.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "core/progress.h"
#include "server/http_server.h"
#include "server/job_runner.h"

// After Eigen (through the headers above): httplib.h includes <resolv.h>, whose `_res` macro breaks
// Eigen's headers when they come later.
#include <httplib.h>

namespace u3d::server::test {

namespace fs = std::filesystem;

inline std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline std::vector<std::string> view_names() {
  std::vector<std::string> names;
  for (const char* v : {"front", "right", "back", "left"})
    for (const char* k : {"_rgb.png", "_normal.png"}) names.push_back(std::string(v) + k);
  return names;
}

inline fs::path example_views() { return fs::path(UNIQUE3D_SOURCE_DIR) / "examples/spot/views"; }

// The bundled example's eight views as the form's 'views' files, plus text fields.
inline httplib::MultipartFormDataItems example_upload(const std::vector<std::pair<std::string, std::string>>& fields = {}) {
  httplib::MultipartFormDataItems items;
  for (const std::string& name : view_names())
    items.push_back({"views", read_file(example_views() / name), name, "image/png"});
  for (const auto& [k, v] : fields) items.push_back({k, v, "", ""});
  return items;
}

// Options that keep a reconstruction of the bundled example to a few seconds (fewer steps leave a
// rougher mesh whose silhouette fit and atlas take longer).
inline std::vector<std::pair<std::string, std::string>> fast_options() {
  return {{"coarse_steps", "40"}, {"refine_steps", "20"}, {"texture_size", "512"}, {"faces", "5000"}};
}

// A runner that only ends when its job is cancelled (a job that holds the worker for the queue tests).
inline void run_until_cancelled(Job& job) {
  job.add_event("stage", {{"name", "waiting"}, {"state", "begin"}});
  while (!job.cancel_requested()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  throw Cancelled();
}

struct SseEvent {
  std::string type;
  nlohmann::json data;
};

class ServerFixture {
 public:
  explicit ServerFixture(JobRunner runner = run_job, size_t max_waiting = 8, fs::path models = {}) {
    set_progress_quiet(true);
    jobs_ = fs::temp_directory_path() / ("u3d_server_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter()++));
    fs::remove_all(jobs_);
    ServerOptions o;
    o.host = "127.0.0.1";
    o.port = 0;
    o.jobs_dir = jobs_;
    o.max_waiting_jobs = max_waiting;
    o.models = std::move(models);
    o.timeout_seconds = 5;
    o.quiet = true;
    server_ = std::make_unique<Server>(o, std::move(runner));
    port_ = server_->bind();
    thread_ = std::thread([this] { server_->serve(); });
    client_ = std::make_unique<httplib::Client>("127.0.0.1", port_);
    client_->set_read_timeout(60, 0);
    for (int i = 0; i < 200 && !client_->Get("/api/info"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ~ServerFixture() {
    server_->stop();
    thread_.join();
    server_.reset();
    fs::remove_all(jobs_);
  }

  httplib::Client& client() { return *client_; }
  int port() const { return port_; }
  const fs::path& jobs_dir() const { return jobs_; }

  // Submits; the reply's status and JSON body.
  std::pair<int, nlohmann::json> submit(const httplib::MultipartFormDataItems& items) {
    auto res = client_->Post("/api/jobs", items);
    if (!res) return {0, {}};
    return {res->status, nlohmann::json::parse(res->body, nullptr, false)};
  }

  nlohmann::json status(const std::string& id) {
    auto res = client_->Get("/api/jobs/" + id);
    return res ? nlohmann::json::parse(res->body, nullptr, false) : nlohmann::json();
  }

  // Reads the job's event stream to its end (or until `stop` returns true for an event, when the
  // client hangs up) and returns the events.
  std::vector<SseEvent> follow(const std::string& id, const std::function<bool(const SseEvent&)>& stop = nullptr) {
    httplib::Client c("127.0.0.1", port_);
    c.set_read_timeout(120, 0);
    std::vector<SseEvent> events;
    std::string buffer;
    c.Get("/api/jobs/" + id + "/events", [&](const char* data, size_t n) {
      buffer.append(data, n);
      for (size_t end; (end = buffer.find("\n\n")) != std::string::npos;) {
        const std::string block = buffer.substr(0, end);
        buffer.erase(0, end + 2);
        SseEvent e;
        std::string data_line;
        size_t start = 0;
        while (start < block.size()) {
          size_t nl = block.find('\n', start);
          if (nl == std::string::npos) nl = block.size();
          const std::string line = block.substr(start, nl - start);
          if (line.rfind("event: ", 0) == 0) e.type = line.substr(7);
          if (line.rfind("data: ", 0) == 0) data_line = line.substr(6);
          start = nl + 1;
        }
        if (e.type.empty()) continue;  // retry hint, keep-alive
        e.data = nlohmann::json::parse(data_line, nullptr, false);
        events.push_back(e);
        if (stop && stop(e)) return false;
      }
      return true;
    });
    return events;
  }

  // Waits until the job has ended; its final status.
  nlohmann::json wait(const std::string& id, double seconds = 120) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    nlohmann::json s;
    while (std::chrono::steady_clock::now() < deadline) {
      s = status(id);
      const std::string state = s.value("state", "");
      if (state == "done" || state == "failed" || state == "cancelled") return s;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ADD_FAILURE() << "job " << id << " did not end within " << seconds << " s: " << s.dump();
    return s;
  }

  std::string fetch(const std::string& url, int* status = nullptr) {
    auto res = client_->Get(url);
    if (status) *status = res ? res->status : 0;
    return res ? res->body : std::string();
  }

 private:
  static int& counter() {
    static int n = 0;
    return n;
  }
  fs::path jobs_;
  std::unique_ptr<Server> server_;
  int port_ = 0;
  std::thread thread_;
  std::unique_ptr<httplib::Client> client_;
};

}  // namespace u3d::server::test
