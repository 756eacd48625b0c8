#include "server/http_server.h"

#include <httplib.h>
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <thread>

#include "core/error.h"
#include "core/progress.h"
#include "server/job_options.h"
#include "server/job_runner.h"
#include "server/web_assets.h"
#include "unique3d/version.h"

namespace u3d::server {

namespace fs = std::filesystem;

fs::path default_jobs_dir() {
  if (const char* cache = std::getenv("XDG_CACHE_HOME"); cache && *cache) return fs::path(cache) / "unique3d" / "jobs";
  if (const char* home = std::getenv("HOME"); home && *home) return fs::path(home) / ".cache" / "unique3d" / "jobs";
  return fs::temp_directory_path() / "unique3d-jobs";
}

namespace {

constexpr const char* kJobPath = R"(/api/jobs/([0-9a-f]{32}))";

void send_json(httplib::Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  res.set_content(body.dump(), "application/json");
}

void send_error(httplib::Response& res, int status, const std::string& message) {
  send_json(res, status, {{"error", message}});
}

std::string new_job_id() {
  static std::mutex mutex;
  static std::random_device device;
  std::lock_guard lock(mutex);
  static const char* hex = "0123456789abcdef";
  std::string id;
  for (int i = 0; i < 4; ++i) {  // 128 bits
    const uint32_t word = device();
    for (int k = 0; k < 8; ++k) id += hex[(word >> (4 * k)) & 15];
  }
  return id;
}

bool is_loopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host == "[::1]" || host.rfind("127.", 0) == 0;
}

// The host name of a Host header ("127.0.0.1:8080" -> "127.0.0.1", "[::1]:8080" -> "[::1]").
std::string host_name(const std::string& header) {
  if (!header.empty() && header[0] == '[') return header.substr(0, header.find(']') + 1);
  return header.substr(0, header.find(':'));
}

std::string content_type_of(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".glb") return "model/gltf-binary";
  if (ext == ".png") return "image/png";
  if (ext == ".jpg") return "image/jpeg";
  if (ext == ".json") return "application/json";
  if (ext == ".zip") return "application/zip";
  return "application/octet-stream";
}

// What an error status of httplib's own (a request it could not parse or route) means, in words.
std::string status_words(int status) {
  switch (status) {
    case 400: return "bad request";
    case 404: return "not found";
    case 405: return "method not allowed";
    case 408: return "the request took too long";
    case 413: return "the request is too large";
    case 414: return "the URL is too long";
    case 416: return "the range is not satisfiable";
    case 431: return "the request's headers are too large";
    case 503: return "unavailable";
    default: return "error " + std::to_string(status);
  }
}

std::string sse_event(const JobEvent& e) {
  return "id: " + std::to_string(e.index) + "\nevent: " + e.type + "\ndata: " + e.data.dump() + "\n\n";
}

}  // namespace

struct Server::Impl {
  ServerOptions options;
  JobQueue queue;
  httplib::Server http;
  int port = 0;
  std::atomic<size_t> streams{0};
  std::atomic<bool> stopping{false};

  Impl(ServerOptions o, JobRunner runner)
      : options(std::move(o)), queue(options.max_waiting_jobs, logged(std::move(runner), options.quiet)) {
    routes();
  }

  // The runner, with a line on stderr as each job starts and ends.
  static JobRunner logged(JobRunner runner, bool quiet) {
    return [runner = std::move(runner), quiet](Job& job) {
      if (!quiet) std::fprintf(stderr, "[unique3d] job %s (%s) started\n", job.id().c_str(), job_kind_name(job.spec().kind));
      try {
        runner(job);
      } catch (const std::exception& e) {
        if (!quiet) std::fprintf(stderr, "[unique3d] job %s ended: %s\n", job.id().c_str(), e.what());
        throw;
      }
      if (!quiet) std::fprintf(stderr, "[unique3d] job %s done\n", job.id().c_str());
    };
  }

  nlohmann::json info() const {
    nlohmann::json generate = {{"available", !options.models.empty()}};
    if (options.models.empty())
      generate["reason"] =
          "this server has no model folder: start it with `unique3d serve --models DIR` (`unique3d doctor --models DIR` "
          "checks a folder; docs/models.md lists its files)";
    return {{"version", UNIQUE3D_VERSION},
            {"generate", generate},
            {"limits",
             {{"max_upload_bytes", options.max_upload_bytes},
              {"max_waiting_jobs", options.max_waiting_jobs},
              {"max_view_side", options.limits.max_view_side},
              {"max_photo_side", options.limits.max_photo_side > 0 ? options.limits.max_photo_side : kMaxPhotoSide}}},
            {"queue", {{"running", queue.running()}, {"waiting", queue.waiting()}}}};
  }

  nlohmann::json job_status(const Job& job) const {
    nlohmann::json j = job.status();
    j["position"] = queue.position(job);
    j["urls"] = {{"status", "/api/jobs/" + job.id()},
                 {"events", "/api/jobs/" + job.id() + "/events"},
                 {"cancel", "/api/jobs/" + job.id() + "/cancel"}};
    return j;
  }

  std::shared_ptr<Job> job_of(const httplib::Request& req, httplib::Response& res) {
    std::shared_ptr<Job> job = queue.find(req.matches[1]);
    if (!job) send_error(res, 404, "no job " + std::string(req.matches[1]) + " (jobs are forgotten when the server stops)");
    return job;
  }

  std::string too_large_message() const {
    return "the upload is larger than " + std::to_string(options.max_upload_bytes >> 20) +
           " MiB (serve --max-upload-mib raises the limit)";
  }

  // Before a request's body is read: a body larger than the limit is refused at once (httplib would read
  // and discard it all first), and so are requests meant for another host (a page of another site that
  // rebound its name to this address).
  httplib::Server::HandlerResponse screen(const httplib::Request& req, httplib::Response& res) {
    if (req.has_header("Content-Length")) {
      const std::string length = req.get_header_value("Content-Length");
      char* end = nullptr;
      const unsigned long long n = std::strtoull(length.c_str(), &end, 10);
      if (!end || *end != '\0' || n > options.max_upload_bytes) {
        res.set_header("Connection", "close");
        send_error(res, 413, too_large_message());
        return httplib::Server::HandlerResponse::Handled;
      }
    }
    const std::string host = req.get_header_value("Host");
    if (is_loopback(options.host) && !is_loopback(host_name(host))) {
      send_error(res, 403, "this server answers requests for localhost only (Host: " + host + ")");
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  }

  // A post from a page of another site (a form it submits here) is refused; checked in the handlers,
  // after the body is read, so that the client gets the answer rather than a broken connection.
  bool from_another_site(const httplib::Request& req, httplib::Response& res) {
    if (!req.has_header("Origin") || req.get_header_value("Origin") == "http://" + req.get_header_value("Host"))
      return false;
    send_error(res, 403, "posts from pages of other sites are refused (Origin: " + req.get_header_value("Origin") + ")");
    return true;
  }

  void submit(const httplib::Request& req, httplib::Response& res) {
    if (from_another_site(req, res)) return;
    if (!req.is_multipart_form_data())
      return send_error(res, 415,
                        "send a job as multipart/form-data: the view set's PNGs (or one zip) as 'views', or a photo as "
                        "'image', and options as text fields (docs/server.md)");
    if (!queue.has_room()) {
      res.set_header("Retry-After", "60");
      return send_error(res, 503, "the queue is full (" + std::to_string(options.max_waiting_jobs) +
                                      " jobs waiting); try again when one has finished");
    }
    std::map<std::string, std::string> fields;
    std::vector<UploadedFile> views, images;
    for (const auto& [key, part] : req.files) {
      if (key == "views") {
        views.push_back({part.filename, part.content});
      } else if (key == "image") {
        images.push_back({part.filename, part.content});
      } else if (!part.filename.empty()) {
        return send_error(res, 400, "unexpected file '" + key + "': files go in 'views' (a view set) or 'image' (a photo)");
      } else if (!fields.emplace(key, part.content).second) {
        return send_error(res, 400, "option " + key + " given twice");
      }
    }
    if (views.empty() == images.empty())
      return send_error(res, 400, "send either a view set's eight PNGs (or one zip) as 'views', or one photo as 'image'");
    if (images.size() > 1) return send_error(res, 400, "send one photo as 'image', not " + std::to_string(images.size()));
    const JobKind kind = views.empty() ? JobKind::Generate : JobKind::Reconstruct;
    if (auto it = fields.find("kind"); it != fields.end()) {
      if (it->second != job_kind_name(kind))
        return send_error(res, 400, "kind '" + it->second + "' does not match the files sent ('" + job_kind_name(kind) + "')");
      fields.erase(it);
    }
    if (kind == JobKind::Generate && options.models.empty())
      return send_error(res, 409, info()["generate"]["reason"].get<std::string>());

    const std::string id = new_job_id();
    const fs::path folder = options.jobs_dir / id;
    try {
      JobSpec spec = make_job_spec(kind, fields, folder, options.models);
      const fs::path input = job_input_dir(folder);
      fs::create_directories(input);
      if (kind == JobKind::Reconstruct)
        write_view_set_upload(views, input, options.limits);
      else
        spec.generate.image = write_photo_upload(images[0], input, options.limits);
      auto job = std::make_shared<Job>(id, folder, std::move(spec));
      queue.submit(job);
      res.set_header("Location", "/api/jobs/" + id);
      send_json(res, 202, job_status(*job));
    } catch (const QueueFull& e) {
      std::error_code ec;
      fs::remove_all(folder, ec);
      res.set_header("Retry-After", "60");
      send_error(res, 503, e.what());
    } catch (const Error& e) {
      std::error_code ec;
      fs::remove_all(folder, ec);
      send_error(res, 400, e.what());
    } catch (const fs::filesystem_error& e) {
      std::error_code ec;
      fs::remove_all(folder, ec);
      send_error(res, 500, std::string("cannot store the upload in the jobs folder: ") + e.code().message());
    }
  }

  void events(const httplib::Request& req, httplib::Response& res) {
    std::shared_ptr<Job> job = job_of(req, res);
    if (!job) return;
    size_t from = 0;
    if (req.has_header("Last-Event-ID")) {
      const std::string last = req.get_header_value("Last-Event-ID");
      char* end = nullptr;
      const unsigned long long n = std::strtoull(last.c_str(), &end, 10);
      if (end && *end == '\0' && !last.empty()) from = size_t(n) + 1;
    }
    if (streams.fetch_add(1) >= options.max_event_streams) {
      streams.fetch_sub(1);
      res.set_header("Retry-After", "10");
      return send_error(res, 503, "too many event streams are open; poll " + std::string(req.path.substr(0, req.path.size() - 7)) + " instead");
    }
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Accel-Buffering", "no");
    using Clock = std::chrono::steady_clock;
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, job, next = from, first = true, last_write = Clock::now()](size_t, httplib::DataSink& sink) mutable {
          if (stopping) return false;
          const Job::Events got = job->events_since(next, std::chrono::milliseconds(1000));
          std::string out = first ? "retry: 2000\n\n" : "";
          first = false;
          for (const JobEvent& e : got.events) {
            out += sse_event(e);
            next = e.index + 1;
          }
          if (out.empty() && Clock::now() - last_write > std::chrono::seconds(15)) out = ": keep-alive\n\n";
          if (!out.empty()) {
            if (!sink.write(out.data(), out.size())) return false;  // the client went away
            last_write = Clock::now();
          }
          if (got.ended) sink.done();
          return true;
        },
        [this](bool) { streams.fetch_sub(1); });
  }

  void cancel(const httplib::Request& req, httplib::Response& res) {
    if (from_another_site(req, res)) return;
    std::shared_ptr<Job> job = job_of(req, res);
    if (!job) return;
    if (job->finished())
      return send_error(res, 409, std::string("the job has already ended (") + job_state_name(job->state()) + ")");
    queue.cancel(*job);
    send_json(res, 202, job_status(*job));
  }

  void file(const httplib::Request& req, httplib::Response& res) {
    std::shared_ptr<Job> job = job_of(req, res);
    if (!job) return;
    const std::optional<JobFile> f = job->file(req.matches[2]);
    std::error_code ec;
    const uintmax_t size = f ? fs::file_size(f->path, ec) : 0;
    if (!f || ec) return send_error(res, 404, "job " + job->id() + " has no file " + std::string(req.matches[2]));
    auto stream = std::make_shared<std::ifstream>(f->path, std::ios::binary);
    if (!*stream) return send_error(res, 404, "job " + job->id() + " has no file " + f->name);
    res.set_header("Cache-Control", "no-cache");
    res.set_content_provider(size_t(size), content_type_of(f->path),
                             [stream](size_t offset, size_t length, httplib::DataSink& sink) {
                               std::vector<char> buffer(std::min<size_t>(length, 1 << 16));
                               stream->seekg(std::streamoff(offset));
                               stream->read(buffer.data(), std::streamsize(buffer.size()));
                               const std::streamsize n = stream->gcount();
                               return n > 0 && sink.write(buffer.data(), size_t(n));
                             });
  }

  void routes() {
    http.new_task_queue = [n = options.max_event_streams + 16] { return new httplib::ThreadPool(n); };
    http.set_payload_max_length(options.max_upload_bytes);
    http.set_read_timeout(options.timeout_seconds, 0);
    http.set_write_timeout(options.timeout_seconds, 0);
    http.set_pre_routing_handler(
        [this](const httplib::Request& req, httplib::Response& res) { return screen(req, res); });
    http.set_error_handler(httplib::Server::HandlerWithResponse([this](const httplib::Request& req, httplib::Response& res) {
      if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
      std::string message = status_words(res.status);
      if (res.status == 413) message = too_large_message();
      else if (res.status == 404)
        message = "nothing at " + req.path;
      send_error(res, res.status, message);
      return httplib::Server::HandlerResponse::Handled;
    }));
    http.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
      std::string message = "internal error";
      try {
        std::rethrow_exception(ep);
      } catch (const std::exception& e) {
        message += std::string(": ") + e.what();
      } catch (...) {
      }
      send_error(res, 500, message);
    });

    http.Get("/api/info", [this](const auto&, auto& res) { send_json(res, 200, info()); });
    http.Post("/api/jobs", [this](const auto& req, auto& res) { submit(req, res); });
    http.Get(kJobPath, [this](const auto& req, auto& res) {
      if (auto job = job_of(req, res)) send_json(res, 200, job_status(*job));
    });
    http.Get(std::string(kJobPath) + "/events", [this](const auto& req, auto& res) { events(req, res); });
    http.Post(std::string(kJobPath) + "/cancel", [this](const auto& req, auto& res) { cancel(req, res); });
    http.Get(std::string(kJobPath) + "/files/([A-Za-z0-9_.-]+)", [this](const auto& req, auto& res) { file(req, res); });
    http.Get(R"(/(|[A-Za-z0-9_./-]+))", [](const httplib::Request& req, httplib::Response& res) {
      const WebAsset* asset = find_web_asset(req.path);
      if (!asset) return send_error(res, 404, "nothing at " + req.path);
      res.set_header("Cache-Control", req.path == "/" ? "no-cache" : "max-age=3600");
      res.set_content(asset->data.data(), asset->data.size(), std::string(asset->content_type));
    });
  }
};

Server::Server(ServerOptions options, JobRunner runner) {
  // A client that hangs up must not end the process: a write to its socket then fails with EPIPE.
  signal(SIGPIPE, SIG_IGN);
  impl_ = std::make_unique<Impl>(std::move(options), std::move(runner));
}

Server::~Server() { stop(); }

int Server::bind() {
  const ServerOptions& o = impl_->options;
  std::error_code ec;
  fs::create_directories(o.jobs_dir, ec);
  require(!ec && fs::is_directory(o.jobs_dir), "cannot make the jobs folder " + o.jobs_dir.string() +
                                                   (ec ? ": " + ec.message() : ""));
  if (o.port == 0) {
    impl_->port = impl_->http.bind_to_any_port(o.host);
    require(impl_->port > 0, "cannot listen on " + o.host + " (any port)");
  } else {
    require(impl_->http.bind_to_port(o.host, o.port),
            "cannot listen on " + o.host + ":" + std::to_string(o.port) + " (in use, or not an address of this machine)");
    impl_->port = o.port;
  }
  return impl_->port;
}

void Server::serve() { impl_->http.listen_after_bind(); }

void Server::stop() {
  impl_->stopping = true;
  impl_->queue.wake_all();
  impl_->http.stop();
}

std::string Server::url() const {
  std::string host = impl_->options.host;
  if (host == "0.0.0.0") host = "127.0.0.1";
  if (host == "::") host = "::1";
  if (host.find(':') != std::string::npos) host = "[" + host + "]";
  return "http://" + host + ":" + std::to_string(impl_->port) + "/";
}

void run_server(const ServerOptions& options) {
  // SIGINT and SIGTERM are taken by one thread that stops the server; every other thread (the HTTP
  // threads and the worker, created below) inherits the blocked mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  Server server(options, run_job);
  server.bind();
  std::fprintf(stderr, "[unique3d] serving on %s (jobs in %s); Ctrl-C stops\n", server.url().c_str(),
               options.jobs_dir.string().c_str());
  std::thread waiter([&] {
    int signal = 0;
    sigwait(&signals, &signal);
    server.stop();
  });
  server.serve();
  kill(getpid(), SIGTERM);  // wakes the waiter when serve() ended for another reason; harmless otherwise
  waiter.join();
  std::fprintf(stderr, "[unique3d] stopped\n");
}

}  // namespace u3d::server
