// `unique3d serve`: the local web app (server/http_server.h, docs/server.md). This file only turns the
// options into ServerOptions.
#include "cli/command.h"
#include "server/http_server.h"

namespace u3d::cli {
namespace {

struct ServeArgs {
  server::ServerOptions options;
  size_t max_upload_mib = 64;
};

const CommandRegistration registration{
    "serve",
    "A local web app: drop a photo or a view folder on a page, watch the job, turn and download the mesh",
    [](CLI::App& sub) {
      auto a = std::make_shared<ServeArgs>();
      server::ServerOptions& o = a->options;
      sub.footer(
          "Open the printed URL in a browser. The page and its 3D viewer are served by the binary itself, "
          "so it works offline. Jobs run one at a time, in order; each gets a folder under --jobs-dir with "
          "its upload and results. The JSON API the page uses is in docs/server.md.");
      sub.add_option("--models", o.models,
                     "Folder of the network weights (docs/models.md) for photo jobs; without it the page "
                     "reconstructs view sets only");
      sub.add_option("--host", o.host,
                     "Address to listen on. The default answers this machine only; 0.0.0.0 lets every machine that "
                     "can reach this one use the server, its jobs and their files (there are no accounts)")
          ->capture_default_str();
      sub.add_option("--port", o.port, "Port to listen on (0: any free port)")
          ->capture_default_str()
          ->check(CLI::Range(0, 65535));
      o.jobs_dir = server::default_jobs_dir();
      sub.add_option("--jobs-dir", o.jobs_dir, "Folder that holds every job's upload and results")->capture_default_str();
      sub.add_option("--max-upload-mib", a->max_upload_mib, "Largest upload accepted, in MiB")
          ->capture_default_str()
          ->check(CLI::Range(1, 4096));
      sub.add_option("--queue", o.max_waiting_jobs, "Jobs that may wait behind the running one; more are refused (503)")
          ->capture_default_str()
          ->check(CLI::Range(1, 1000));
      sub.add_option("--max-view-side", o.limits.max_view_side, "Largest view image accepted, in pixels per side")
          ->capture_default_str()
          ->check(CLI::Range(16, 8192));
      return [a] {
        server::ServerOptions options = a->options;
        options.max_upload_bytes = a->max_upload_mib << 20;
        options.limits.max_zip_bytes = std::max<size_t>(options.limits.max_zip_bytes, 4 * options.max_upload_bytes);
        server::run_server(options);
      };
    }};

}  // namespace
}  // namespace u3d::cli
