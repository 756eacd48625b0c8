#pragma once
// Runs the objects of one shard of a batch (`unique3d batch`, docs/cluster.md) through the library facade:
// view folders through reconstruct_folder, photos through generate (pipeline/generate.h) with one
// NetworkCache for the shard, so that each network is read once for all its photos where memory allows
// (pipeline/network_cache.h). Each object gets its own folder, filled under a temporary name and renamed
// when complete:
//   OUT/<name>/  mesh.glb, mesh_views.png, mesh_turntable.png, done.json
// done.json records the input (path and SHA-256), the options, the program's version, the model folder's
// checks and how many networks were read for it (photos), each stage's time and peak memory, and the files. An object whose done.json matches
// its input's hash and the options is skipped; one that does not is redone and replaced. An object that
// fails writes OUT/<name>.failed.json with the error and the batch goes on; a later run retries it.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "batch/batch_inputs.h"
#include "batch/shard.h"
#include "core/progress.h"
#include "pipeline/generate.h"
#include "pipeline/reconstruct.h"

namespace u3d {

struct BatchSpec {
  std::filesystem::path output;    // OUT, created when missing
  ReconstructRequest reconstruct;  // for view folders: all but views_dir, output and previews
  GenerateRequest generate;        // for photos: all but image, output and previews
  // What the objects' results depend on (the command's options as given), per mode: done.json keeps
  // them, and an object done with other options is redone.
  nlohmann::json reconstruct_options = nlohmann::json::object();
  nlohmann::json generate_options = nlohmann::json::object();
  const nlohmann::json& options_for(BatchMode mode) const {
    return mode == BatchMode::Generate ? generate_options : reconstruct_options;
  }
};

enum class ObjectOutcome { Done, Skipped, Failed };
const char* object_outcome_name(ObjectOutcome outcome);  // "done", "skipped", "failed"

struct ObjectReport {
  BatchInput input;
  ObjectOutcome outcome = ObjectOutcome::Failed;
  std::string input_sha256;  // empty when the input could not be read
  std::string error;         // Failed: the message
  double seconds = 0.0;      // the object's run (0 when skipped)
  double peak_memory_mib = 0.0;  // the process's peak resident memory during the object's run
  size_t networks_loaded = 0;    // photos: networks read from their files for this object (0: all kept)
};

struct BatchReport {
  Shard shard;
  size_t batch_objects = 0;  // in the whole batch, all shards
  std::vector<ObjectReport> objects;
  double seconds = 0.0;
  size_t count(ObjectOutcome outcome) const;
  double peak_memory_mib() const;  // the largest of the objects'
};

// The paths of an object in OUT.
std::filesystem::path object_folder(const std::filesystem::path& out, const std::string& name);
std::filesystem::path object_done_file(const std::filesystem::path& out, const std::string& name);
std::filesystem::path object_failed_file(const std::filesystem::path& out, const std::string& name);

// Whether `input`, whose hash is `sha256`, is done in OUT with `options` (its done.json says so).
bool object_is_done(const std::filesystem::path& out, const std::string& name, const std::string& sha256,
                    const nlohmann::json& options);

// Runs `inputs` (one shard's objects) in order. Checks the spec before any object (an Error: OUT cannot
// be made, photos without a model folder, a network of the model folder fails its check); each object's
// own failure is reported in its ObjectReport and the run goes on. Cancelled (through the listener) ends
// the run, leaving no partial folder. Temporary folders a killed run left for these objects are removed.
BatchReport run_batch(const std::vector<BatchInput>& inputs, const BatchSpec& spec, ProgressListener* listener = nullptr);

// {shard: "I/N", batch_objects, done, skipped, failed, seconds, peak_memory_mib, objects: [{name, mode,
// input, outcome, sha256, seconds, peak_memory_mib, error}]}.
nlohmann::json batch_report_json(const BatchReport& report);

}  // namespace u3d
