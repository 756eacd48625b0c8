// Shards of a batch: each object's shard follows from its name alone, so adding inputs moves no other
// object, shards 0..N-1 hold every object exactly once, and the index comes from --shard or a scheduler.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>

#include "batch/shard.h"
#include "core/error.h"

namespace u3d {
namespace {

std::vector<BatchInput> named(int count, const std::string& prefix = "object_") {
  std::vector<BatchInput> inputs;
  for (int i = 0; i < count; ++i) inputs.push_back({"/in/" + prefix + std::to_string(i), prefix + std::to_string(i)});
  return inputs;
}

// Shard of each name, with `count` shards.
std::map<std::string, int> assignment(const std::vector<BatchInput>& inputs, int count) {
  std::map<std::string, int> shard_of_name;
  for (int s = 0; s < count; ++s)
    for (const BatchInput& input : select_shard(inputs, {s, count})) {
      EXPECT_EQ(shard_of_name.count(input.name), 0u) << input.name << " is in two shards";
      shard_of_name[input.name] = s;
    }
  return shard_of_name;
}

TEST(Shard, ShardsCoverEveryInputExactlyOnce) {
  const std::vector<BatchInput> inputs = named(500);
  for (int count : {1, 2, 3, 7, 16}) {
    const std::map<std::string, int> a = assignment(inputs, count);
    EXPECT_EQ(a.size(), inputs.size()) << count << " shards";
    // Hashing spreads the objects: no shard is empty or holds twice its share (500 objects).
    std::vector<int> sizes(size_t(count), 0);
    for (const auto& [name, s] : a) ++sizes[size_t(s)];
    for (int size : sizes) {
      EXPECT_GT(size, 0);
      EXPECT_LT(size, 2 * 500 / count + 5);
    }
  }
}

TEST(Shard, AddingOrRemovingInputsMovesNoOtherInput) {
  const std::vector<BatchInput> before = named(200);
  std::vector<BatchInput> after = before;
  for (const BatchInput& extra : named(50, "added_")) after.push_back(extra);
  after.erase(after.begin() + 10, after.begin() + 20);  // and some removed
  for (int count : {2, 3, 8}) {
    const std::map<std::string, int> a = assignment(before, count), b = assignment(after, count);
    for (const auto& [name, s] : b)
      if (a.count(name)) EXPECT_EQ(a.at(name), s) << name << " moved with " << count << " shards";
  }
}

TEST(Shard, DoesNotDependOnTheOrderOfTheListing) {
  std::vector<BatchInput> inputs = named(60);
  const std::map<std::string, int> a = assignment(inputs, 4);
  std::reverse(inputs.begin(), inputs.end());
  EXPECT_EQ(assignment(inputs, 4), a);
}

// The hash is the same on every machine and in every version: values computed by hand (FNV-1a 64 and
// splitmix64's finaliser, in Python) pin it, since a change would re-shard existing batches.
TEST(Shard, HashIsPinned) {
  EXPECT_EQ(stable_hash("spot"), 0xed8e578fbe1b0307ull);
  EXPECT_EQ(stable_hash(""), 0xf52a15e9a9b5e89bull);
  EXPECT_EQ(shard_of("spot", 1), 0);
  EXPECT_EQ(shard_of("spot", 1000), int(0xed8e578fbe1b0307ull % 1000));
}

TEST(Shard, ParsesIOverN) {
  EXPECT_EQ(parse_shard("0/1").count, 1);
  const Shard s = parse_shard("2/5");
  EXPECT_EQ(s.index, 2);
  EXPECT_EQ(s.count, 5);
  EXPECT_EQ(s.to_string(), "2/5");
  for (const char* bad : {"", "3", "3/3", "-1/3", "1/0", "a/b", "1/3/4", " 1/3", "1/"}) {
    EXPECT_THROW(parse_shard(bad), Error) << bad;
  }
}

TEST(Shard, IndexFromTheScheduler) {
  // --shard wins over the environment.
  EXPECT_EQ(resolve_shard(Shard{1, 4}, 9, {"2", "3", nullptr}).to_string(), "1/4");
  // Nothing: the whole batch.
  EXPECT_EQ(resolve_shard(std::nullopt, std::nullopt, {}).to_string(), "0/1");
  EXPECT_EQ(resolve_shard(std::nullopt, 3, {}).to_string(), "0/3");
  // A Slurm array: the task id, and its count unless --shards says (a resubmission of some indices).
  EXPECT_EQ(resolve_shard(std::nullopt, std::nullopt, {"2", "3", nullptr}).to_string(), "2/3");
  EXPECT_EQ(resolve_shard(std::nullopt, 8, {"5", "1", nullptr}).to_string(), "5/8");
  EXPECT_THROW(resolve_shard(std::nullopt, std::nullopt, {"5", "1", nullptr}), Error);
  EXPECT_THROW(resolve_shard(std::nullopt, 3, {"x", "3", nullptr}), Error);
  // A Kubernetes Indexed Job: the completion index, with --shards.
  EXPECT_EQ(resolve_shard(std::nullopt, 4, {nullptr, nullptr, "3"}).to_string(), "3/4");
  EXPECT_THROW(resolve_shard(std::nullopt, std::nullopt, {nullptr, nullptr, "3"}), Error);
  EXPECT_THROW(resolve_shard(std::nullopt, 3, {nullptr, nullptr, "3"}), Error);
}

}  // namespace
}  // namespace u3d
