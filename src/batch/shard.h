#pragma once
// Which objects of a batch one worker runs: shard I of N. An object's shard is a hash of its name (not its
// position in the listing), so the shards do not depend on the order the file system lists files in, and
// adding or removing an input moves no other object to another shard. Shards 0..N-1 together hold every
// object exactly once.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "batch/batch_inputs.h"

namespace u3d {

struct Shard {
  int index = 0;
  int count = 1;
  std::string to_string() const;  // "I/N"
};

// "I/N" with 0 <= I < N; an Error naming the text otherwise.
Shard parse_shard(const std::string& text);

// The variables a scheduler sets for one task of an array, as getenv gives them (null: unset).
struct SchedulerEnvironment {
  const char* slurm_task_id = nullptr;     // SLURM_ARRAY_TASK_ID
  const char* slurm_task_count = nullptr;  // SLURM_ARRAY_TASK_COUNT
  const char* completion_index = nullptr;  // JOB_COMPLETION_INDEX (Kubernetes Indexed Job)
  static SchedulerEnvironment from_process();
};

// The shard a worker runs: `given` (--shard I/N) when set; else the scheduler's task index with `count`
// (--shards N) as N when given, else SLURM_ARRAY_TASK_COUNT; else 0/1. The task index is the shard
// index, so an array runs as --array=0-(N-1), and a resubmission of some of its indices (--array=3) with
// --shards N runs the same shards. An Error for a malformed variable, an index without a count (a
// Kubernetes index needs --shards), or an index outside the count.
Shard resolve_shard(const std::optional<Shard>& given, std::optional<int> count, const SchedulerEnvironment& env);

// A 64-bit hash of `text` that is the same on every machine and every run (FNV-1a, then a mixing step).
uint64_t stable_hash(std::string_view text);

// The shard, of `count`, that the object named `name` belongs to.
int shard_of(const std::string& name, int count);

// The inputs of `shard`, in their order.
std::vector<BatchInput> select_shard(const std::vector<BatchInput>& inputs, const Shard& shard);

}  // namespace u3d
