#include "batch/batch_runner.h"

#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>

#include "batch/content_hash.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/memory.h"
#include "pipeline/model_check.h"
#include "pipeline/network_stage.h"
#include "pipeline/summary_json.h"
#include "unique3d/version.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr const char* kMeshFile = "mesh.glb";
constexpr const char* kDoneFile = "done.json";

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The temporary folders of `name` in OUT: ".<name>+partial-<host>-<pid>" while it runs, ".<name>+old-..."
// for a moment while a stale folder is replaced ('+' is never part of a name, batch/batch_inputs.h).
std::string temporary_prefix(const std::string& name) { return "." + name + "+"; }

std::string host_and_pid() {
  char host[256] = {0};
  if (gethostname(host, sizeof host - 1) != 0) std::strcpy(host, "host");
  return std::string(host) + "-" + std::to_string(getpid());
}

// Removes what an earlier, killed run left of `name` in OUT.
void remove_leftovers(const fs::path& out, const std::string& name) {
  const std::string prefix = temporary_prefix(name);
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(out, ec)) {
    const std::string file = e.path().filename().string();
    if (file.rfind(prefix + "partial-", 0) == 0 || file.rfind(prefix + "old-", 0) == 0) fs::remove_all(e.path(), ec);
  }
}

void write_json(const fs::path& path, const nlohmann::json& j) {
  write_atomically(path, [&](const fs::path& tmp) {
    std::ofstream f(tmp);
    f << j.dump(2) << "\n";
    f.close();
    require(bool(f), "cannot write " + path.string());
  });
}

// Puts the finished folder `tmp` in place of `target`: a rename when there is none yet, else an atomic
// exchange with the stale one (Linux's renameat2), which is then removed.
void commit_folder(const fs::path& tmp, const fs::path& target, const fs::path& out, const std::string& name) {
  if (!path_exists(target)) {
    fs::rename(tmp, target);
    return;
  }
  if (renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) == 0) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    return;
  }
  // A file system without the exchange: move the stale folder aside first (a moment with neither).
  const fs::path old = out / (temporary_prefix(name) + "old-" + host_and_pid());
  fs::rename(target, old);
  fs::rename(tmp, target);
  std::error_code ec;
  fs::remove_all(old, ec);
}

nlohmann::json program_json() { return {{"name", "unique3d"}, {"version", UNIQUE3D_VERSION}}; }

nlohmann::json input_json(const BatchInput& input, const std::string& sha256) {
  nlohmann::json j = {{"path", fs::absolute(input.path).lexically_normal().string()},
                      {"kind", input.mode == BatchMode::Generate ? "photo" : "view folder"}};
  if (!sha256.empty()) j["sha256"] = sha256;
  return j;
}

// The networks every photo needs, checked once for the shard (generate checks them again per photo, a
// second or so each, and the background removal when a photo is opaque).
nlohmann::json check_models(const GenerateRequest& generate) {
  const ModelFolder folder(generate.network.models);
  std::vector<Network> networks = {Network::kUpscaler, Network::kMultiView, Network::kNormals};
  if (generate.refine) networks.push_back(Network::kRefine);
  nlohmann::json checks = nlohmann::json::array();
  for (Network n : networks) {
    const NetworkCheckResult r = check_network(folder, n, NetworkCheck::kShapes);
    require(r.ok(), "model folder " + folder.root().string() + ": " + network_name(n) + ": " + r.error);
    checks.push_back({{"network", network_name(n)}, {"ok", true}, {"seconds", r.seconds}});
  }
  return {{"folder", fs::absolute(folder.root()).lexically_normal().string()}, {"checks", checks}};
}

// One object's run into the folder `dir`: the facade's call, and done.json's stages.
nlohmann::json run_object(const BatchInput& input, const BatchSpec& spec, const fs::path& dir, NetworkCache& networks) {
  nlohmann::json record;
  if (input.mode == BatchMode::Reconstruct) {
    ReconstructRequest request = spec.reconstruct;
    request.views_dir = input.path;
    request.output = dir / kMeshFile;
    request.previews = true;
    const ReconstructSummary s = reconstruct_folder(request);
    nlohmann::json stages = nlohmann::json::array();
    for (const StageTiming& t : s.timings) stages.push_back({{"name", t.name}, {"seconds", t.seconds}});
    record["stages"] = stages;
    record["mesh"] = summary_json(s)["mesh"];
  } else {
    GenerateRequest request = spec.generate;
    request.image = input.path;
    request.output = dir / kMeshFile;
    request.previews = true;
    const GenerateSummary s = generate(request, nullptr, &networks);
    const nlohmann::json summary = summary_json(s);
    record["stages"] = summary["stages"];
    record["precision"] = summary["precision"];
    record["mesh"] = summary["mesh"];
  }
  return record;
}

}  // namespace

const char* object_outcome_name(ObjectOutcome outcome) {
  switch (outcome) {
    case ObjectOutcome::Done: return "done";
    case ObjectOutcome::Skipped: return "skipped";
    case ObjectOutcome::Failed: return "failed";
  }
  return "?";
}

size_t BatchReport::count(ObjectOutcome outcome) const {
  return size_t(std::count_if(objects.begin(), objects.end(), [&](const ObjectReport& o) { return o.outcome == outcome; }));
}

double BatchReport::peak_memory_mib() const {
  double peak = 0.0;
  for (const ObjectReport& o : objects) peak = std::max(peak, o.peak_memory_mib);
  return peak;
}

fs::path object_folder(const fs::path& out, const std::string& name) { return out / name; }
fs::path object_done_file(const fs::path& out, const std::string& name) { return out / name / kDoneFile; }
fs::path object_failed_file(const fs::path& out, const std::string& name) { return out / (name + ".failed.json"); }

bool object_is_done(const fs::path& out, const std::string& name, const std::string& sha256, const nlohmann::json& options) {
  std::ifstream in(object_done_file(out, name));
  if (!in) return false;
  const nlohmann::json done = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!done.is_object() || !done.contains("input") || !done["input"].is_object()) return false;
  return done["input"].value("sha256", "") == sha256 && done.value("options", nlohmann::json()) == options &&
         fs::is_regular_file(object_folder(out, name) / kMeshFile);
}

BatchReport run_batch(const std::vector<BatchInput>& inputs, const BatchSpec& spec, ProgressListener* listener) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  const Clock::time_point start = Clock::now();
  const bool photos = std::any_of(inputs.begin(), inputs.end(), [](const BatchInput& i) { return i.mode == BatchMode::Generate; });
  nlohmann::json models;
  if (photos) {
    require(!spec.generate.network.models.empty(), "the batch has photos: give the model folder with --models");
    models = check_models(spec.generate);
  }
  ensure_directory(spec.output);

  BatchReport report;
  NetworkCache networks;
  for (size_t i = 0; i < inputs.size(); ++i) {
    const BatchInput& input = inputs[i];
    ObjectReport object;
    object.input = input;
    std::string label = "[";
    label.append(std::to_string(i + 1)).append("/").append(std::to_string(inputs.size())).append("] ").append(input.name);
    const fs::path failed = object_failed_file(spec.output, input.name);
    const Clock::time_point object_start = Clock::now();
    fs::path tmp;
    try {
      remove_leftovers(spec.output, input.name);
      object.input_sha256 = input_hash(input);
      if (object_is_done(spec.output, input.name, object.input_sha256, spec.options_for(input.mode))) {
        object.outcome = ObjectOutcome::Skipped;
        progress(label + ": done before, skipped");
        std::error_code ec;
        fs::remove(failed, ec);
        report.objects.push_back(object);
        continue;
      }
      progress(label + ": " + batch_mode_name(input.mode) + " " + input.path.string());
      release_freed_memory();
      MemoryPeakWatch object_memory;  // (leaves the process's own peak, which the scheduler reads, alone)
      tmp = spec.output / (temporary_prefix(input.name) + "partial-" + host_and_pid());
      fs::create_directories(tmp);
      const size_t loads_before = networks.loads();
      nlohmann::json done = run_object(input, spec, tmp, networks);
      object.networks_loaded = networks.loads() - loads_before;
      object.seconds = seconds_since(object_start);
      object.peak_memory_mib = object_memory.peak_mib();
      done["name"] = input.name;
      done["mode"] = batch_mode_name(input.mode);
      done["input"] = input_json(input, object.input_sha256);
      done["options"] = spec.options_for(input.mode);
      done["program"] = program_json();
      done["models"] = input.mode == BatchMode::Generate ? models : nlohmann::json();
      if (input.mode == BatchMode::Generate) done["models"]["networks_loaded"] = object.networks_loaded;
      done["total_seconds"] = object.seconds;
      done["peak_memory_mib"] = object.peak_memory_mib;
      nlohmann::json files = nlohmann::json::array();
      std::vector<std::string> names;
      for (const fs::directory_entry& e : fs::directory_iterator(tmp)) names.push_back(e.path().filename().string());
      names.push_back(kDoneFile);
      std::sort(names.begin(), names.end());
      for (const std::string& n : names) files.push_back(n);
      done["files"] = files;
      write_json(tmp / kDoneFile, done);
      commit_folder(tmp, object_folder(spec.output, input.name), spec.output, input.name);
      tmp.clear();
      std::error_code ec;
      fs::remove(failed, ec);
      object.outcome = ObjectOutcome::Done;
      progress(label + ": done in " + std::to_string(int(object.seconds + 0.5)) + " s");
    } catch (const Cancelled&) {
      std::error_code ec;
      if (!tmp.empty()) fs::remove_all(tmp, ec);
      throw;
    } catch (const std::exception& e) {
      std::error_code ec;
      if (!tmp.empty()) fs::remove_all(tmp, ec);
      object.outcome = ObjectOutcome::Failed;
      object.error = dynamic_cast<const Error*>(&e) ? e.what() : std::string("internal error: ") + e.what();
      object.seconds = seconds_since(object_start);
      object.peak_memory_mib = peak_memory_mib();
      progress(label + ": failed: " + object.error);
      try {
        write_json(failed, {{"name", input.name},
                            {"mode", batch_mode_name(input.mode)},
                            {"input", input_json(input, object.input_sha256)},
                            {"error", object.error},
                            {"seconds", object.seconds},
                            {"options", spec.options_for(input.mode)},
                            {"program", program_json()}});
      } catch (const Error& write_error) {
        progress(label + ": " + write_error.what());
      }
    }
    report.objects.push_back(object);
  }
  report.seconds = seconds_since(start);
  return report;
}

nlohmann::json batch_report_json(const BatchReport& report) {
  nlohmann::json objects = nlohmann::json::array();
  for (const ObjectReport& o : report.objects) {
    nlohmann::json j = {{"name", o.input.name},
                        {"mode", batch_mode_name(o.input.mode)},
                        {"input", o.input.path.string()},
                        {"outcome", object_outcome_name(o.outcome)},
                        {"sha256", o.input_sha256},
                        {"seconds", o.seconds},
                        {"peak_memory_mib", o.peak_memory_mib}};
    if (o.input.mode == BatchMode::Generate) j["networks_loaded"] = o.networks_loaded;
    if (o.outcome == ObjectOutcome::Failed) j["error"] = o.error;
    objects.push_back(j);
  }
  return {{"shard", report.shard.to_string()},
          {"batch_objects", report.batch_objects},
          {"done", report.count(ObjectOutcome::Done)},
          {"skipped", report.count(ObjectOutcome::Skipped)},
          {"failed", report.count(ObjectOutcome::Failed)},
          {"seconds", report.seconds},
          {"peak_memory_mib", report.peak_memory_mib()},
          {"objects", objects}};
}

}  // namespace u3d
