// A photo job of `unique3d serve` on the tiny stand-in networks (tests/pipeline/tiny_model_folder.h) at
// their small sizes: the photo is uploaded, every stage's images become files of the job as the stage
// ends (before the mesh), and the job ends with a mesh and its summary.
#include <map>

#include "core/synthetic_views.h"
#include "pipeline/tiny_model_folder.h"
#include "server_fixture.h"

namespace u3d::server::test {
namespace {

// What the client's options cannot set: the tiny networks' sizes.
void run_tiny(Job& job) {
  JobSpec spec = job.spec();
  u3d::testing::use_tiny_sizes(spec.generate);
  run_job_as(job, spec);
}

TEST(ServerGenerate, APhotoJobShowsEveryStagesImagesAsTheyComeAndEndsWithAMesh) {
  const fs::path dir = u3d::testing::fresh_temp_dir("server_generate");
  u3d::testing::write_tiny_model_folder(dir / "models");
  u3d::testing::write_disk_photo(dir / "photo.png");
  ServerFixture server(run_tiny, 8, dir / "models");
  const auto [code, reply] = server.submit({{"image", read_file(dir / "photo.png"), "photo.png", "image/png"},
                                            {"seed", "3", "", ""},
                                            {"steps", "2", "", ""},
                                            {"dtype", "fp32", "", ""},
                                            {"raw_matte", "true", "", ""},
                                            {"colour", "vertex", "", ""}});
  ASSERT_EQ(code, 202) << reply.dump();
  EXPECT_EQ(reply["kind"], "generate");
  const std::string id = reply["id"];
  const std::vector<SseEvent> events = server.follow(id);
  std::map<std::string, size_t> file_at;  // name -> index of its event
  for (size_t i = 0; i < events.size(); ++i)
    if (events[i].type == "file") file_at[events[i].data["name"]] = i;
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().data["state"], "done") << events.back().data.dump();
  for (const char* name : {"front.png", "multiview_front_rgb.png", "multiview_left_rgb.png", "refined_back_rgb.png",
                           "upscaled_right_rgb.png", "views_front_normal.png", "views_left_rgb.png", "mesh.glb",
                           "summary.json", "mesh_obj.zip"})
    EXPECT_TRUE(file_at.count(name)) << name;
  // As they come: each stage's images before the next stage's, all before the mesh.
  EXPECT_LT(file_at["front.png"], file_at["multiview_front_rgb.png"]);
  EXPECT_LT(file_at["multiview_front_rgb.png"], file_at["refined_back_rgb.png"]);
  EXPECT_LT(file_at["refined_back_rgb.png"], file_at["views_front_normal.png"]);
  EXPECT_LT(file_at["views_front_normal.png"], file_at["mesh.glb"]);
  int status = 0;
  const std::string view = server.fetch("/api/jobs/" + id + "/files/multiview_front_rgb.png", &status);
  EXPECT_EQ(status, 200);
  EXPECT_EQ(view, read_file(server.jobs_dir() / id / "intermediates" / "multiview" / "front_rgb.png"));
  const nlohmann::json s = server.status(id);
  EXPECT_EQ(s["options"]["seed"], 3);
  EXPECT_EQ(s["options"]["raw_matte"], true);
  EXPECT_EQ(s["summary"]["precision"], "fp32");
  EXPECT_EQ(s["summary"]["stages"].size(), generate_stage_names().size());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace u3d::server::test
