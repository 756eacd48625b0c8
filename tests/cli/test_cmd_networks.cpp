// The network subcommands' bad inputs give a clear message, a non-zero exit and no output. (The stages
// themselves run in tests/pipeline/test_network_stages.cpp, on the tiny models at a small size.)
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/image.h"
#include "core/synthetic_views.h"
#include "pipeline/tiny_model_folder.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

struct CliResult {
  int status = -1;
  std::string output;  // stdout and stderr
};

CliResult run_cli(const std::string& args, const fs::path& log) {
  const std::string cmd = std::string(UNIQUE3D_CLI) + " " + args + " > " + log.string() + " 2>&1";
  CliResult r;
  r.status = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  r.output = ss.str();
  return r;
}

class NetworkCommands : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir = new fs::path(testing::fresh_temp_dir("cli_networks"));
    testing::write_tiny_model_folder(*dir / "models");
    testing::write_disk_photo(*dir / "photo.png");
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir);
    delete dir;
  }
  static std::string models() { return " --models " + (*dir / "models").string(); }
  static fs::path* dir;
};
fs::path* NetworkCommands::dir = nullptr;

TEST_F(NetworkCommands, BadInputsAreNamedAndWriteNothing) {
  const fs::path out = *dir / "never";
  // A photo without transparency.
  Image opaque(64, 64, 3, 0.5f);
  save_image(opaque, *dir / "opaque.png");
  CliResult r = run_cli("multiview " + (*dir / "opaque.png").string() + " -o " + out.string() + models(), *dir / "b1.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("opaque.png"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("alpha"), std::string::npos) << r.output;
  // A model folder without the multi-view checkpoint.
  fs::create_directories(*dir / "empty_models");
  r = run_cli("multiview " + (*dir / "photo.png").string() + " -o " + out.string() + " --models " +
                  (*dir / "empty_models").string(),
              *dir / "b2.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("img2mvimg"), std::string::npos) << r.output;
  // fp16 needs CUDA.
  r = run_cli("multiview " + (*dir / "photo.png").string() + " -o " + out.string() + models() + " --dtype fp16",
              *dir / "b3.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("fp16"), std::string::npos) << r.output;
  // normals: a folder without views.
  r = run_cli("normals " + (*dir / "empty_models").string() + " -o " + out.string() + models(), *dir / "b4.log");
  EXPECT_EQ(r.status, 1 << 8) << r.output;
  EXPECT_NE(r.output.find("front_rgb.png"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace u3d
