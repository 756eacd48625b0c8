// `unique3d batch INPUTS -o OUT [--shard I/N]`: many objects, one folder each, a shard of them per worker
// (docs/cluster.md). The inputs, shards and runs are the batch library's (batch/); this file turns the
// options into its spec, prints the summary and exits with the number of failed objects.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <optional>
#include <set>

#include "batch/batch_inputs.h"
#include "batch/batch_runner.h"
#include "batch/content_hash.h"
#include "batch/shard.h"
#include "cli/command.h"
#include "cli/network_options.h"
#include "cli/reconstruct_options.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace u3d::cli {
namespace {

namespace fs = std::filesystem;

// The most failures the exit status counts; shells give statuses above 125 their own meanings.
constexpr int kMaxExitStatus = 100;

struct BatchArgs {
  fs::path inputs;
  fs::path output;
  std::string shard;
  int shards = 0;  // 0: not given
  fs::path jobs_file;
  fs::path json_path;
  ReconstructArgs reconstruct;
  NetworkArgs network;
  bool no_refine = false, raw_matte = false;
  int steps = 0;  // 0: each stage's own
  nlohmann::json reconstruct_options, generate_options;  // given_options() of each mode
};

// The options the results of objects of `mode` depend on, as given: every option but the batch's own and
// those of the other mode.
nlohmann::json given_options(const CLI::App& sub, BatchMode mode) {
  static const std::set<std::string> own = {"inputs", "--output", "--shard", "--shards", "--jobs-file", "--json", "--help"};
  static const std::set<std::string> photos_only = {"--models", "--dtype", "--seed", "--no-refine", "--raw-matte",
                                                    "--steps"};
  static const std::set<std::string> view_folders_only = {"--normal-space"};
  const std::set<std::string>& other = mode == BatchMode::Generate ? view_folders_only : photos_only;
  nlohmann::json options = nlohmann::json::object();
  for (const CLI::Option* o : sub.get_options()) {
    if (o->count() == 0 || own.count(o->get_name()) || other.count(o->get_name())) continue;
    const std::vector<std::string>& values = o->results();
    options[o->get_name()] = values.size() == 1 ? nlohmann::json(values[0]) : nlohmann::json(values);
  }
  return options;
}

void write_text(const fs::path& path, const std::string& text) {
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << text;
    f.close();
    require(bool(f), "cannot write " + path.string());
  });
}

// --jobs-file: the shard's objects, one a line: name, mode, whether done in OUT with these options, input.
void write_jobs_file(const BatchArgs& a, const std::vector<BatchInput>& all, const std::vector<BatchInput>& mine,
                     const Shard& shard) {
  std::string text = "# unique3d batch " + a.inputs.string() + " -o " + a.output.string() + ": shard " +
                     shard.to_string() + ", " + std::to_string(mine.size()) + " of " + std::to_string(all.size()) +
                     " objects\n# name\tmode\tstate\tinput\n";
  for (const BatchInput& input : mine) {
    const nlohmann::json& options = input.mode == BatchMode::Generate ? a.generate_options : a.reconstruct_options;
    const bool done = object_is_done(a.output, input.name, input_hash(input), options);
    text += input.name + "\t" + batch_mode_name(input.mode) + "\t" + (done ? "done" : "todo") + "\t" +
            input.path.string() + "\n";
  }
  write_text(a.jobs_file, text);
  std::printf("wrote %s: shard %s, %zu of %zu objects\n", a.jobs_file.string().c_str(), shard.to_string().c_str(),
              mine.size(), all.size());
}

void run(const BatchArgs& a) {
  std::optional<Shard> given;
  if (!a.shard.empty()) given = parse_shard(a.shard);
  std::optional<int> count;
  if (a.shards > 0) count = a.shards;
  const Shard shard = resolve_shard(given, count, SchedulerEnvironment::from_process());
  const std::vector<BatchInput> all = list_batch_inputs(a.inputs);
  const std::vector<BatchInput> mine = select_shard(all, shard);
  if (!a.jobs_file.empty()) return write_jobs_file(a, all, mine, shard);

  BatchSpec spec;
  spec.output = a.output;
  spec.reconstruct_options = a.reconstruct_options;
  spec.generate_options = a.generate_options;
  spec.reconstruct = make_reconstruct_request(a.reconstruct);
  GenerateRequest& g = spec.generate;
  g.network = a.network.resolved();
  g.refine = !a.no_refine;
  g.raw_matte = a.raw_matte;
  if (a.steps > 0) g.multiview.steps = g.normals.steps = a.steps;
  g.reconstruct = spec.reconstruct.options;
  g.official_output_scale = spec.reconstruct.official_output_scale;
  g.texture_format = spec.reconstruct.texture_format;

  BatchReport report = run_batch(mine, spec);
  report.shard = shard;
  report.batch_objects = all.size();
  const size_t failed = report.count(ObjectOutcome::Failed);
  for (const ObjectReport& o : report.objects)
    if (o.outcome == ObjectOutcome::Failed)
      std::printf("failed: %s (%s): %s\n", o.input.name.c_str(), o.input.path.string().c_str(), o.error.c_str());
  std::printf("batch: shard %s, %zu of %zu objects: %zu done, %zu skipped, %zu failed in %.1f s; peak memory %.0f MiB\n",
              shard.to_string().c_str(), mine.size(), all.size(), report.count(ObjectOutcome::Done),
              report.count(ObjectOutcome::Skipped), failed, report.seconds, report.peak_memory_mib());
  if (!a.json_path.empty()) write_text(a.json_path, batch_report_json(report).dump(2) + "\n");
  std::fflush(stdout);
  if (failed > 0) throw ExitStatus{int(std::min<size_t>(failed, kMaxExitStatus))};
}

const CommandRegistration registration{
    "batch",
    "Many photos or view folders, one output folder each; a shard of them per worker (Slurm, Kubernetes)",
    [](CLI::App& sub) {
      auto a = std::make_shared<BatchArgs>();
      sub.add_option("inputs", a->inputs,
                     "A folder of photos and/or view folders, or a text file listing them (one per line, # comments). "
                     "Photos run through `generate`, view folders through `reconstruct`")
          ->required();
      sub.add_option("-o,--output", a->output,
                     "Output folder: <name>/ per object (mesh.glb, previews, done.json), <name>.failed.json per failure")
          ->required();
      sub.add_option("--shard", a->shard,
                     "Run shard I of N (I/N, from 0); default: from SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX "
                     "with --shards, else 0/1. An object's shard is a hash of its name");
      sub.add_option("--shards", a->shards,
                     "Number of shards when the index comes from the scheduler (default: SLURM_ARRAY_TASK_COUNT)")
          ->check(CLI::Range(1, 1000000));
      sub.add_option("--jobs-file", a->jobs_file,
                     "Write this shard's objects (name, mode, done or todo, input) to this file and run nothing");
      sub.add_option("--json", a->json_path, "Also write the summary with a line per object to this JSON file");
      add_reconstruct_options(sub, a->reconstruct);
      add_network_options(sub, a->network, /*seeded=*/true, /*models_required=*/false);
      sub.add_flag("--no-refine", a->no_refine, "Photos: skip the ControlNet-tile refinement (as `generate --no-refine`)");
      sub.add_flag("--raw-matte", a->raw_matte,
                   "Photos: keep the background-removal mask as the network draws it (as `generate --raw-matte`)");
      sub.add_option("--steps", a->steps, "Photos: denoising steps of the multi-view and normal models (default: 30 each)")
          ->check(CLI::Range(1, 1000));
      return [a, &sub] {
        a->reconstruct_options = given_options(sub, BatchMode::Reconstruct);
        a->generate_options = given_options(sub, BatchMode::Generate);
        run(*a);
      };
    }};

}  // namespace
}  // namespace u3d::cli
