#include "batch/shard.h"

#include <cstdlib>

#include "core/error.h"

namespace u3d {
namespace {

// A whole non-negative number, or nothing.
std::optional<long> whole_number(const std::string& text) {
  if (text.empty() || text.size() > 9) return std::nullopt;
  for (char c : text)
    if (c < '0' || c > '9') return std::nullopt;
  return std::stol(text);
}

long environment_number(const char* value, const char* name) {
  const std::optional<long> n = whole_number(value);
  require(n.has_value(), std::string(name) + "=" + value + " is not a whole number");
  return *n;
}

}  // namespace

std::string Shard::to_string() const { return std::to_string(index) + "/" + std::to_string(count); }

Shard parse_shard(const std::string& text) {
  const size_t slash = text.find('/');
  const std::string what = "--shard " + text + ": ";
  require(slash != std::string::npos, what + "give it as I/N (shard I of N, counting from 0)");
  const std::optional<long> index = whole_number(text.substr(0, slash));
  const std::optional<long> count = whole_number(text.substr(slash + 1));
  require(index && count, what + "I and N must be whole numbers");
  require(*count >= 1, what + "N must be at least 1");
  require(*index < *count, what + "I must be less than N (shards count from 0)");
  return {int(*index), int(*count)};
}

SchedulerEnvironment SchedulerEnvironment::from_process() {
  return {std::getenv("SLURM_ARRAY_TASK_ID"), std::getenv("SLURM_ARRAY_TASK_COUNT"),
          std::getenv("JOB_COMPLETION_INDEX")};
}

Shard resolve_shard(const std::optional<Shard>& given, std::optional<int> count, const SchedulerEnvironment& env) {
  if (given) return *given;
  require(!count || *count >= 1, "--shards must be at least 1");
  std::optional<long> index;
  std::string source;
  if (env.slurm_task_id) {
    index = environment_number(env.slurm_task_id, "SLURM_ARRAY_TASK_ID");
    if (!count && env.slurm_task_count) count = int(environment_number(env.slurm_task_count, "SLURM_ARRAY_TASK_COUNT"));
    source = "SLURM_ARRAY_TASK_ID";
  } else if (env.completion_index) {
    index = environment_number(env.completion_index, "JOB_COMPLETION_INDEX");
    source = "JOB_COMPLETION_INDEX";
  }
  if (!index) return {0, count.value_or(1)};
  require(count.has_value(), source + " is set but the number of shards is not: give --shards N");
  require(*index < *count, source + " gives shard " + std::to_string(*index) + ", not one of the " +
                               std::to_string(*count) + " shards (0.." + std::to_string(*count - 1) +
                               "): run the array as 0-(N-1), or give --shards N");
  return {int(*index), *count};
}

uint64_t stable_hash(std::string_view text) {
  uint64_t h = 14695981039346656037ull;  // FNV-1a 64
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  // splitmix64's finaliser: FNV's low bits alone split similar names unevenly.
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebull;
  h ^= h >> 31;
  return h;
}

int shard_of(const std::string& name, int count) { return int(stable_hash(name) % uint64_t(count)); }

std::vector<BatchInput> select_shard(const std::vector<BatchInput>& inputs, const Shard& shard) {
  std::vector<BatchInput> selected;
  for (const BatchInput& input : inputs)
    if (shard_of(input.name, shard.count) == shard.index) selected.push_back(input);
  return selected;
}

}  // namespace u3d
