// unique3d: one photo in, a textured 3D mesh out. This file only wires the subcommands together and
// turns errors into a message and a non-zero exit status.
#include <cstdio>
#include <exception>
#include <map>

#include "cli/command.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "nn/runtime.h"
#include "unique3d/version.h"

namespace u3d::cli {

std::vector<CommandInfo>& command_registry() {
  static std::vector<CommandInfo> registry;
  return registry;
}

}  // namespace u3d::cli

int main(int argc, char** argv) {
  using namespace u3d;
  CLI::App app{"unique3d " UNIQUE3D_VERSION " - single image to textured 3D mesh (Unique3D in C++)"};
  app.set_version_flag("--version", std::string("unique3d ") + UNIQUE3D_VERSION);
  app.require_subcommand(1);
  bool quiet = false;
  int threads = 0;
  app.add_flag("-q,--quiet", quiet, "Do not print progress lines");
  app.add_option("--threads", threads, "Worker threads (default: all cores, or $UNIQUE3D_THREADS)")->check(CLI::NonNegativeNumber);

  std::map<CLI::App*, cli::CommandAction> actions;
  for (auto& cmd : cli::command_registry()) {
    CLI::App* sub = app.add_subcommand(cmd.name, cmd.description);
    actions[sub] = cmd.setup(*sub);
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // Bad options are errors like any other: the same prefix, and status 1.
    std::fprintf(stderr, "unique3d: error: %s\nRun with --help for more information.\n", e.what());
    return 1;
  }
  StderrProgress progress_lines(quiet);
  ProgressScope progress_scope(&progress_lines);
  keep_freed_memory_for_reuse();
  configure_threads(threads);
  nn::configure_torch_threads(threads);
  try {
    for (auto& [sub, action] : actions)
      if (sub->parsed()) action();
  } catch (const cli::ExitStatus& s) {
    return s.code;
  } catch (const Error& e) {
    std::fprintf(stderr, "unique3d: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "unique3d: internal error: %s\n", e.what());
    return 2;
  }
  return 0;
}
