// `unique3d batch` as a user runs it: 12 view sets over 3 shards in 3 processes started at once give the
// same meshes, byte for byte, as 12 runs of `unique3d reconstruct`; --jobs-file shows the shards; a
// failed object sets the exit status and the others are done; bad inputs are errors before any output.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "core/synthetic_views.h"
#include "io/io_test_util.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

// Small reconstructions of 64 px views: about a second each (the Poisson initial mesh at depth 5, a 32^3
// grid for 64 px views, is most of it; at the default 6 it took about 1.6 s of a 2.3 s run).
const std::string kOptions =
    " --coarse-steps 5 --refine-steps 3 --texture-size 128 --faces 500 --visibility-resolution 128 --no-silhouette-fit"
    " --poisson-depth 5";

struct CliResult {
  int status = -1;
  std::string output;
};

CliResult run_cli(const std::string& args, const fs::path& log) {
  const std::string cmd = std::string(UNIQUE3D_CLI) + " " + args + " > " + log.string() + " 2>&1";
  const int raw = std::system(cmd.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, test::read_file(log)};
}

// View sets of the bundled example and the test object, each rendered at 64 px with a framing (--fill).
class BatchCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { dir = new fs::path(testing::fresh_temp_dir("cli_batch")); }
  static void TearDownTestSuite() {
    fs::remove_all(*dir);
    delete dir;
  }
  // Renders in/<object>_<fill> and returns its name.
  static std::string view_set(const std::string& object, const std::string& fill) {
    const std::string mesh = object == "spot" ? std::string(UNIQUE3D_SOURCE_DIR) + "/examples/spot/spot.obj"
                                              : std::string(UNIQUE3D_TEST_DATA) + "/objects/avocado/avocado.obj";
    const std::string name = object + "_" + fill;
    const CliResult r =
        run_cli("-q render " + mesh + " -o " + (*dir / "in" / name).string() + " --res 64 --fill " + fill, *dir / "render.log");
    EXPECT_EQ(r.status, 0) << r.output;
    return name;
  }
  static fs::path* dir;
};
fs::path* BatchCli::dir = nullptr;

TEST_F(BatchCli, ThreeShardsInThreeProcessesGiveTheMeshesOfSingleRuns) {
  std::vector<std::string> names;
  for (const char* object : {"spot", "avocado"})
    for (const char* fill : {"0.5", "0.6", "0.7", "0.8", "0.85", "0.9"}) names.push_back(view_set(object, fill));
  const fs::path out = *dir / "out";
  std::ostringstream script;
  script << "bash -c '";
  for (int i = 0; i < 3; ++i) {
    const fs::path shard = *dir / ("shard" + std::to_string(i));
    script << "(" << UNIQUE3D_CLI << " -q --threads 1 batch " << (*dir / "in").string() << " -o " << out.string()
           << " --shard " << i << "/3 --json " << shard.string() << ".json" << kOptions << " > " << shard.string()
           << ".log 2>&1; echo $? > " << shard.string() << ".status) & ";
  }
  script << "wait'";
  ASSERT_EQ(std::system(script.str().c_str()), 0);
  std::map<std::string, int> done_by;
  for (int i = 0; i < 3; ++i) {
    const std::string n = std::to_string(i);
    ASSERT_EQ(test::read_file(*dir / ("shard" + n + ".status")), "0\n") << test::read_file(*dir / ("shard" + n + ".log"));
    const nlohmann::json report = nlohmann::json::parse(test::read_file(*dir / ("shard" + n + ".json")));
    EXPECT_EQ(report["shard"], n + "/3");
    EXPECT_EQ(report["batch_objects"], 12);
    EXPECT_EQ(report["failed"], 0);
    for (const nlohmann::json& o : report["objects"]) {
      EXPECT_EQ(o["outcome"], "done") << o.dump();
      EXPECT_EQ(done_by.count(o["name"]), 0u) << o["name"] << " in two shards";
      done_by[o["name"]] = i;
    }
  }
  ASSERT_EQ(done_by.size(), 12u);

  for (const std::string& name : names) {
    const fs::path single = *dir / (name + ".glb");
    const CliResult r = run_cli("-q --threads 1 reconstruct " + (*dir / "in" / name).string() + " -o " + single.string() + kOptions,
                                *dir / "single.log");
    ASSERT_EQ(r.status, 0) << r.output;
    const std::string batch_mesh = test::read_file(out / name / "mesh.glb");
    ASSERT_FALSE(batch_mesh.empty()) << name;
    EXPECT_TRUE(batch_mesh == test::read_file(single)) << name << ": the batch's mesh.glb differs from `reconstruct`'s";
  }

  // The jobs files of the three shards: each object once, all done.
  std::set<std::string> listed;
  for (int i = 0; i < 3; ++i) {
    const fs::path jobs = *dir / ("jobs" + std::to_string(i) + ".txt");
    const CliResult r = run_cli("-q batch " + (*dir / "in").string() + " -o " + out.string() + " --shard " +
                                    std::to_string(i) + "/3 --jobs-file " + jobs.string() + kOptions,
                                *dir / "jobs.log");
    ASSERT_EQ(r.status, 0) << r.output;
    std::istringstream lines(test::read_file(jobs));
    for (std::string line; std::getline(lines, line);) {
      if (line.empty() || line[0] == '#') continue;
      const std::string name = line.substr(0, line.find('\t'));
      EXPECT_EQ(done_by.at(name), i) << line;
      EXPECT_NE(line.find("\tdone\t"), std::string::npos) << line;
      EXPECT_TRUE(listed.insert(name).second) << name;
    }
  }
  EXPECT_EQ(listed.size(), 12u);
}

TEST_F(BatchCli, FailedObjectsSetTheExitStatusAndTheOthersAreDone) {
  const fs::path in = *dir / "mixed", out = *dir / "mixed_out";
  fs::create_directories(in);
  const std::string set = view_set("spot", "0.7");
  fs::copy(*dir / "in" / set, in / "spot");
  fs::copy(*dir / "in" / set, in / "broken");
  std::ofstream(in / "broken" / "back_rgb.png", std::ios::trunc) << "not a png";
  const CliResult r = run_cli("batch " + in.string() + " -o " + out.string() + kOptions, *dir / "mixed.log");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("failed: broken"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 done, 0 skipped, 1 failed"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_regular_file(out / "spot" / "mesh.glb"));
  EXPECT_TRUE(fs::is_regular_file(out / "broken.failed.json"));
  EXPECT_FALSE(fs::exists(out / "broken"));
}

TEST_F(BatchCli, BadInputsAreErrorsBeforeAnyOutput) {
  const std::string set = view_set("spot", "0.5");
  const fs::path out = *dir / "bad_out";
  const std::map<std::string, std::string> cases = {
      {(*dir / "nothing").string(), "do not exist"},
      {(*dir / "in").string() + " --shard 3/3", "I must be less than N"},
      {(*dir / "in").string() + " --shard 1", "give it as I/N"},
      {(*dir / "in" / set).string(), "is a view folder itself"},
  };
  for (const auto& [args, message] : cases) {
    const CliResult r = run_cli("batch " + args + " -o " + out.string(), *dir / "bad.log");
    EXPECT_EQ(r.status, 1) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("unique3d: error: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
  // Photos need the model folder: said before anything is written.
  fs::create_directories(*dir / "photos");
  fs::copy_file(*dir / "in" / set / "front_rgb.png", *dir / "photos" / "spot.png");
  const CliResult r = run_cli("batch " + (*dir / "photos").string() + " -o " + out.string(), *dir / "bad.log");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("--models"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace u3d
