// `unique3d reconstruct` end to end: a sphere's views give a closed textured mesh matching the
// silhouettes; every bad input gives a clear message, a non-zero exit and no output file.
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <utility>
#include <vector>

#include "geometry/mesh_topology.h"
#include "io/mesh_io.h"
#include "isomer/reconstruct.h"
#include "core/synthetic_views.h"

namespace u3d {
namespace {

struct CliResult {
  int status = -1;
  std::string output;  // stdout and stderr
};

CliResult run_cli(const std::string& args, const std::filesystem::path& log) {
  const std::string cmd = std::string(UNIQUE3D_CLI) + " reconstruct " + args + " > " + log.string() + " 2>&1";
  CliResult r;
  r.status = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  r.output = ss.str();
  return r;
}

// A textured result splits its vertices at chart borders: as a surface (vertices merged at equal
// positions) it is closed and manifold.
void expect_closed_textured(const Mesh& mesh) {
  EXPECT_TRUE(mesh.has_texture());
  EXPECT_FALSE(mesh.has_colors());
  EXPECT_TRUE(surface_topology(mesh).closed_manifold()) << surface_topology(mesh).summary();
}

TEST(ReconstructCli, SphereGivesClosedTexturedMeshMatchingTheSilhouettes) {
  const auto dir = testing::fresh_temp_dir("cli_sphere");
  testing::write_view_set(testing::sphere_views(0.6f, 192), dir / "views");
  const auto out = dir / "sphere.glb";
  const CliResult r = run_cli((dir / "views").string() + " -o " + out.string() + " --preview --visibility-resolution 512"
                              " --coarse-steps 60 --refine-steps 20",  // shortened: the spot test runs the full default
                              dir / "log.txt");
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_TRUE(std::filesystem::exists(out));
  EXPECT_TRUE(std::filesystem::exists(dir / "sphere_views.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "sphere_turntable.png"));
  expect_closed_textured(read_mesh(out));
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m,
                                std::regex("silhouette IoU: front ([0-9.]+), right ([0-9.]+), back ([0-9.]+), left ([0-9.]+)")))
      << r.output;
  for (int k = 1; k <= 4; ++k) EXPECT_GE(std::stod(m[k]), 0.95) << r.output;
  std::printf("%s", r.output.substr(r.output.find("\nmesh:") + 1).c_str());
}

std::array<double, 4> printed_iou(const std::string& output) {
  std::smatch m;
  std::array<double, 4> iou{-1, -1, -1, -1};
  if (std::regex_search(output, m,
                        std::regex("silhouette IoU: front ([0-9.]+), right ([0-9.]+), back ([0-9.]+), left ([0-9.]+)")))
    for (int k = 0; k < 4; ++k) iou[k] = std::stod(m[k + 1]);
  return iou;
}

// The full default pipeline (initial mesh, coarse, refinement, clean-up, decimation to 40k faces, a
// 2048 texture) once, on the bundled example: about half a minute. Its mesh is then compared with the
// ground truth the views were rendered from, through `unique3d eval` in the views' frame.
TEST(ReconstructCli, BundledExampleFullPipelineCoversTheMasks) {
  const auto dir = testing::fresh_temp_dir("cli_spot");
  const auto out = dir / "spot.glb";
  const CliResult r = run_cli((std::filesystem::path(UNIQUE3D_SOURCE_DIR) / "examples/spot/views").string() + " -o " +
                                  out.string(),
                              dir / "log.txt");
  ASSERT_EQ(r.status, 0) << r.output;
  const Mesh mesh = read_mesh(out);
  expect_closed_textured(mesh);
  EXPECT_LE(mesh.face_count(), kDefaultTextureFaces);
  EXPECT_GE(mesh.face_count(), kDefaultTextureFaces * 99 / 100);
  EXPECT_EQ(mesh.materials[0].texture.width, 2048);
  for (const char* stage : {"initial mesh ", "coarse ", "refine ", "smooth and subdivide ", "decimate ", "texture "})
    EXPECT_NE(r.output.find(std::string(", ") + stage), std::string::npos) << stage << r.output;
  EXPECT_NE(r.output.find(", 0 unreachable"), std::string::npos) << r.output;
  for (double v : printed_iou(r.output)) EXPECT_GE(v, 0.9) << r.output;
  std::printf("%s", r.output.substr(r.output.find("\nmesh:") + 1).c_str());

  const std::string eval = std::string(UNIQUE3D_CLI) + " --quiet eval " + out.string() + " " +
                           (std::filesystem::path(UNIQUE3D_SOURCE_DIR) / "examples/spot/spot.obj").string() +
                           " --given-frame --gt-render-fill 0.9 --samples 50000 --fscore-thresholds 0.005,0.01"
                           " --no-appearance --json " +
                           (dir / "eval.json").string() + " > " + (dir / "eval.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(eval.c_str()), 0);
  std::ifstream json(dir / "eval.json");
  const nlohmann::json metrics = nlohmann::json::parse(json);
  const double chamfer = metrics["chamfer"]["l1"].get<double>(), fscore = metrics["fscore"][0]["fscore"].get<double>();
  std::printf("against spot.obj: Chamfer-L1 %.5f, F-score@0.005 %.4f\n", chamfer, fscore);
  // Measured: Chamfer-L1 0.00195, F-score@0.005 0.931. Bounds about 45 % and 0.05 worse; with
  // --coarse-steps 1 --refine-steps 1 the command gives 0.0165 and 0.305.
  EXPECT_LT(chamfer, 0.0028);
  EXPECT_GT(fscore, 0.88);
}

// The ablations the object benchmark runs exist and change which stages run.
TEST(ReconstructCli, AblationFlagsSelectTheStages) {
  const auto dir = testing::fresh_temp_dir("cli_ablation");
  testing::write_view_set(testing::sphere_views(0.6f, 96), dir / "views");
  const std::string views = (dir / "views").string();
  const CliResult init = run_cli(views + " -o " + (dir / "init.ply").string() + " --init-only", dir / "init.txt");
  ASSERT_EQ(init.status, 0) << init.output;
  EXPECT_EQ(init.output.find(", coarse "), std::string::npos) << init.output;
  EXPECT_EQ(init.output.find(", refine "), std::string::npos) << init.output;
  const CliResult plain = run_cli(views + " -o " + (dir / "plain.ply").string() +
                                      " --refine-target multiview --sphere-init --coarse-steps 20 --refine-steps 5",
                                  dir / "plain.txt");
  ASSERT_EQ(plain.status, 0) << plain.output;
  EXPECT_NE(plain.output.find("time: load"), std::string::npos) << plain.output;
  EXPECT_NE(plain.output.find(", sphere "), std::string::npos) << plain.output;
  EXPECT_NE(plain.output.find(", refine "), std::string::npos) << plain.output;
  const CliResult clash = run_cli(views + " -o " + (dir / "x.ply").string() + " --init-only --refine-steps 5",
                                  dir / "clash.txt");
  EXPECT_NE(clash.status, 0) << clash.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

// The visual-hull baseline of the object benchmark: carve, clean up, texture; no optimisation.
TEST(ReconstructCli, VisualHullReplacesInitialMeshAndOptimisation) {
  const auto dir = testing::fresh_temp_dir("cli_hull");
  testing::write_view_set(testing::sphere_views(0.6f, 96), dir / "views");
  const std::string views = (dir / "views").string();
  const auto out = dir / "hull.glb";
  const CliResult hull = run_cli(views + " -o " + out.string() + " --visual-hull --hull-resolution 64 --subdivide 0",
                                 dir / "hull.txt");
  ASSERT_EQ(hull.status, 0) << hull.output;
  EXPECT_NE(hull.output.find(", visual hull "), std::string::npos) << hull.output;
  for (const char* stage : {", initial mesh ", ", coarse ", ", refine "})
    EXPECT_EQ(hull.output.find(stage), std::string::npos) << stage << hull.output;
  expect_closed_textured(read_mesh(out));
  for (double v : printed_iou(hull.output)) EXPECT_GE(v, 0.95) << hull.output;

  const CliResult clash = run_cli(views + " -o " + (dir / "x.ply").string() + " --visual-hull --init-only",
                                  dir / "clash.txt");
  EXPECT_NE(clash.status, 0) << clash.output;
  const CliResult orphan = run_cli(views + " -o " + (dir / "x.ply").string() + " --hull-resolution 64", dir / "orphan.txt");
  EXPECT_NE(orphan.status, 0) << orphan.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

TEST(ReconstructCli, BadInputFailsCleanlyAndWritesNothing) {
  const ViewSet good = testing::sphere_views(0.6f, 64);
  auto expect_failure = [&](const std::string& name, const std::function<void(const std::filesystem::path&)>& spoil,
                            const std::string& expected) {
    const auto dir = testing::fresh_temp_dir("cli_bad_" + name);
    testing::write_view_set(good, dir / "views");
    spoil(dir / "views");
    const auto out = dir / "out.glb";
    const CliResult r = run_cli((dir / "views").string() + " -o " + out.string() + " --preview", dir / "log.txt");
    EXPECT_NE(r.status, 0) << name;
    EXPECT_NE(r.output.find("unique3d: error: "), std::string::npos) << name << ": " << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << name << ": " << r.output;
    for (const auto& entry : std::filesystem::directory_iterator(dir))
      EXPECT_TRUE(entry.path().filename() == "views" || entry.path().filename() == "log.txt")
          << name << ": wrote " << entry.path();
  };
  expect_failure("missing", [](auto& d) { std::filesystem::remove(d / "front_rgb.png"); }, "lacks front_rgb.png");
  expect_failure("size", [&](auto& d) { save_image(resize_image(good[View::Left].normals, 48, 48), d / "left_normal.png"); },
                 "size mismatch");
  expect_failure("empty_mask", [&](auto& d) { save_image(Image(64, 64, 4, 0.f), d / "right_rgb.png"); }, "mask is empty");
  expect_failure("full_mask", [&](auto& d) { save_image(Image(64, 64, 4, 1.f), d / "back_rgb.png"); },
                 "covers the whole image");
  expect_failure("black_normals", [&](auto& d) { save_image(Image(64, 64, 3, 0.f), d / "front_normal.png"); },
                 "all black");
  expect_failure("not_png", [&](auto& d) { std::ofstream(d / "left_rgb.png") << "GIF89a"; }, "not a PNG");
  expect_failure("jpeg", [&](auto& d) {
    save_image(good[View::Front].rgb, d / "front.jpg");
    std::filesystem::rename(d / "front.jpg", d / "front_rgb.png");
  }, "not a PNG");
}

// --faces hits its count within 1 % and keeps the surface closed and manifold, with vertex colours
// and with a texture (the default); textures go into the GLB or beside an OBJ (PNG or JPEG).
TEST(ReconstructCli, FacesAndTextureOptionsShapeTheOutput) {
  const auto dir = testing::fresh_temp_dir("cli_texture");
  testing::write_view_set(testing::sphere_views(0.6f, 128), dir / "views");
  const std::string views = (dir / "views").string() + " --coarse-steps 20 --refine-steps 5";
  auto expect_faces = [](const Mesh& mesh, size_t faces) {
    EXPECT_LE(mesh.face_count(), faces);
    EXPECT_GE(mesh.face_count(), faces - faces / 100);
    EXPECT_TRUE(surface_topology(mesh).closed_manifold()) << surface_topology(mesh).summary();
  };
  const CliResult vertex = run_cli(views + " -o " + (dir / "v.glb").string() + " --colour vertex --faces 3000", dir / "v.txt");
  ASSERT_EQ(vertex.status, 0) << vertex.output;
  EXPECT_NE(vertex.output.find(", decimate "), std::string::npos) << vertex.output;
  const Mesh v = read_mesh(dir / "v.glb");
  EXPECT_TRUE(v.has_colors());
  EXPECT_FALSE(v.has_texture());
  expect_faces(v, 3000);

  const CliResult texture = run_cli(views + " -o " + (dir / "t.glb").string() + " --faces 2000 --texture-size 256",
                                    dir / "t.txt");
  ASSERT_EQ(texture.status, 0) << texture.output;
  EXPECT_NE(texture.output.find("texture: 256x256, "), std::string::npos) << texture.output;
  const Mesh t = read_mesh(dir / "t.glb");
  ASSERT_TRUE(t.has_texture());
  EXPECT_FALSE(t.has_colors());
  EXPECT_EQ(t.materials[0].texture.width, 256);
  expect_faces(t, 2000);
  if (std::system("command -v node > /dev/null 2>&1") == 0) {  // the Khronos glTF validator (tests/io too)
    EXPECT_EQ(std::system(("node " UNIQUE3D_SOURCE_DIR "/tools/validate_gltf.mjs " + (dir / "t.glb").string()).c_str()), 0);
  }

  const CliResult obj = run_cli(views + " -o " + (dir / "t.obj").string() +
                                    " --colour texture --faces 2000 --texture-size 128 --texture-format jpg",
                                dir / "obj.txt");
  ASSERT_EQ(obj.status, 0) << obj.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "t.mtl"));
  EXPECT_TRUE(std::filesystem::exists(dir / "t_texture.jpg"));
  EXPECT_TRUE(read_mesh(dir / "t.obj").has_texture());
}

TEST(ReconstructCli, BadFaceAndTextureOptionsFailBeforeWork) {
  const auto dir = testing::fresh_temp_dir("cli_texture_bad");
  testing::write_view_set(testing::sphere_views(0.6f, 64), dir / "views");
  const std::string head = (dir / "views").string() + " -o " + (dir / "out.glb").string() + " ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--colour paint", "--colour"},
      {"--faces 10", "--faces"},
      {"--colour texture --texture-size 16", "--texture-size"},
      {"--colour texture --texture-format gif", "--texture-format"},
      {"--colour vertex --texture-size 512", "--texture-size needs --colour texture"},
      {"--colour vertex --texture-format jpg", "--texture-format needs --colour texture"},
  };
  for (const auto& [args, expected] : cases) {
    const CliResult r = run_cli(head + args, dir / "log.txt");
    EXPECT_NE(r.status, 0) << args;
    EXPECT_NE(r.output.find(expected), std::string::npos) << args << ": " << r.output;
    EXPECT_EQ(r.output.find("time:"), std::string::npos) << args << ": " << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.glb")) << args;
  }
}

TEST(ReconstructCli, RejectsUnknownOutputFormatBeforeWork) {
  const auto dir = testing::fresh_temp_dir("cli_ext");
  testing::write_view_set(testing::sphere_views(0.6f, 64), dir / "views");
  const CliResult r = run_cli((dir / "views").string() + " -o " + (dir / "out.stl").string(), dir / "log.txt");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("unsupported extension"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.stl"));
}

}  // namespace
}  // namespace u3d
