// The JSON API of `unique3d serve` (docs/server.md) with the real job runner on the bundled example:
// a job submitted as files and followed through its event stream to a GLB that passes the Khronos
// validator, the same job from a zip giving the same bytes, a cancelled job leaving nothing behind, and a
// job under load (200 status requests and 20 event streams at once) giving the same bytes as alone.
#include <sys/wait.h>
#include <zip.h>

#include <atomic>
#include <cstdlib>
#include <set>

#include "server/zip_archive.h"
#include "server_fixture.h"

namespace u3d::server::test {
namespace {

// The bundled example reconstructed with the fast options, once for the whole suite: its GLB's bytes.
struct Reference {
  std::string glb;
  std::vector<SseEvent> events;
  nlohmann::json status;
  std::string summary, obj_zip;
};

const Reference& reference() {
  static const Reference ref = [] {
    ServerFixture server;
    Reference r;
    const auto [code, reply] = server.submit(example_upload(fast_options()));
    EXPECT_EQ(code, 202) << reply.dump();
    const std::string id = reply.value("id", "");
    r.events = server.follow(id);
    r.status = server.status(id);
    r.glb = server.fetch("/api/jobs/" + id + "/files/mesh.glb");
    r.summary = server.fetch("/api/jobs/" + id + "/files/summary.json");
    r.obj_zip = server.fetch("/api/jobs/" + id + "/files/mesh_obj.zip");
    return r;
  }();
  return ref;
}

int validate_glb(const std::string& bytes) {
  const fs::path file = fs::temp_directory_path() / ("u3d_server_glb_" + std::to_string(::getpid()) + ".glb");
  std::ofstream(file, std::ios::binary) << bytes;
  const std::string command = "node \"" UNIQUE3D_SOURCE_DIR "/tools/validate_gltf.mjs\" \"" + file.string() + "\" > /dev/null";
  const int status = std::system(command.c_str());
  fs::remove(file);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(ServerApi, AJobFollowedToItsEndGivesAValidMeshAndItsFiles) {
  const Reference& r = reference();
  ASSERT_FALSE(r.events.empty());
  // The stream: queued, running, ISOMER's stages with steps, the result files, done, in that order.
  std::vector<std::string> states;
  std::set<std::string> stages, files;
  int steps = 0;
  for (const SseEvent& e : r.events) {
    if (e.type == "state") states.push_back(e.data["state"]);
    if (e.type == "stage" && e.data["state"] == "end") stages.insert(e.data["name"].get<std::string>());
    if (e.type == "step") ++steps;
    if (e.type == "file") files.insert(e.data["name"].get<std::string>());
  }
  EXPECT_EQ(states, (std::vector<std::string>{"queued", "running", "done"}));
  for (const char* stage : {"initial mesh", "coarse", "refine", "texture"}) EXPECT_TRUE(stages.count(stage)) << stage;
  EXPECT_GT(steps, 2);
  EXPECT_EQ(files, (std::set<std::string>{"mesh.glb", "mesh_views.png", "mesh_turntable.png", "mesh_obj.zip", "summary.json"}));
  EXPECT_EQ(r.events.back().type, "state");
  // No event names a path of the server's.
  for (const SseEvent& e : r.events) EXPECT_EQ(e.data.dump().find(fs::temp_directory_path().string()), std::string::npos) << e.data.dump();

  EXPECT_EQ(r.status["state"], "done");
  EXPECT_EQ(r.status["options"]["coarse_steps"], 40);
  EXPECT_EQ(r.status["summary"]["mesh"]["faces"], 5000);
  ASSERT_GT(r.glb.size(), 1000u);
  EXPECT_EQ(r.glb.compare(0, 4, "glTF"), 0);
  EXPECT_EQ(validate_glb(r.glb), 0);
  const nlohmann::json summary = nlohmann::json::parse(r.summary);
  EXPECT_EQ(summary["mesh"]["faces"], 5000);
  for (float iou : summary["mesh"]["silhouette_iou"].get<std::vector<float>>()) EXPECT_GT(iou, 0.9f);
  std::set<std::string> in_zip;
  for (const ZipEntry& e : read_zip(r.obj_zip)) in_zip.insert(e.name);
  EXPECT_EQ(in_zip, (std::set<std::string>{"mesh.obj", "mesh.mtl", "mesh_texture.png"}));
}

TEST(ServerApi, AZipOfTheViewFolderGivesTheSameMeshAsItsFiles) {
  const Reference& r = reference();
  // The folder zipped as a person would: inside a folder, with a file that is not a view.
  const fs::path zip_path = fs::temp_directory_path() / ("u3d_views_" + std::to_string(::getpid()) + ".zip");
  std::vector<std::pair<std::string, fs::path>> files;
  for (const std::string& name : view_names()) files.emplace_back("spot/views/" + name, example_views() / name);
  files.emplace_back("spot/README.md", fs::path(UNIQUE3D_SOURCE_DIR) / "README.md");
  write_zip(zip_path, files);
  httplib::MultipartFormDataItems items = {{"views", read_file(zip_path), "views.zip", "application/zip"}};
  fs::remove(zip_path);
  for (const auto& [k, v] : fast_options()) items.push_back({k, v, "", ""});
  ServerFixture server;
  const auto [code, reply] = server.submit(items);
  ASSERT_EQ(code, 202) << reply.dump();
  EXPECT_EQ(server.wait(reply["id"])["state"], "done");
  const std::string glb = server.fetch("/api/jobs/" + reply["id"].get<std::string>() + "/files/mesh.glb");
  EXPECT_TRUE(glb == r.glb) << "the GLB from the zip differs from the GLB from the files";
}

TEST(ServerApi, ACancelledJobEndsWithNoResultAndNoFolder) {
  ServerFixture server;
  auto options = fast_options();
  options[0].second = "2000";  // a coarse stage of minutes
  const auto [code, reply] = server.submit(example_upload(options));
  ASSERT_EQ(code, 202) << reply.dump();
  const std::string id = reply["id"];
  const fs::path folder = server.jobs_dir() / id;
  EXPECT_TRUE(fs::exists(folder / "input" / "front_rgb.png"));
  // Cancel once the coarse stage is stepping.
  std::vector<SseEvent> events = server.follow(id, [](const SseEvent& e) { return e.type == "step" && e.data["stage"] == "coarse reconstruction"; });
  ASSERT_FALSE(events.empty());
  auto res = server.client().Post("/api/jobs/" + id + "/cancel");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 202);
  const nlohmann::json s = server.wait(id, 30);
  EXPECT_EQ(s["state"], "cancelled");
  EXPECT_TRUE(s["files"].empty());
  EXPECT_FALSE(fs::exists(folder));
  int status = 0;
  server.fetch("/api/jobs/" + id + "/files/mesh.glb", &status);
  EXPECT_EQ(status, 404);
  // A second cancel: the job has ended.
  res = server.client().Post("/api/jobs/" + id + "/cancel");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 409);
  // The stream of a finished job replays to its end.
  events = server.follow(id);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().data["state"], "cancelled");
}

// During a job: 20 clients follow its event stream while 200 status requests come from 8 threads; every
// stream ends with the job, every request is answered 200, and the mesh is the one the job gives alone.
TEST(ServerApi, UnderLoadAJobGivesTheSameBytesAsAlone) {
  const Reference& r = reference();
  ServerFixture server;
  const auto [code, reply] = server.submit(example_upload(fast_options()));
  ASSERT_EQ(code, 202) << reply.dump();
  const std::string id = reply["id"];
  std::atomic<int> streams_ended{0}, ok_status{0}, other_status{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < 20; ++i)
    threads.emplace_back([&] {
      const std::vector<SseEvent> events = server.follow(id);
      if (!events.empty() && events.back().type == "state" && events.back().data["state"] == "done") ++streams_ended;
    });
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&] {
      httplib::Client c("127.0.0.1", server.port());
      for (int i = 0; i < 25; ++i) {
        auto res = c.Get("/api/jobs/" + id);
        (res && res->status == 200 ? ok_status : other_status)++;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(ok_status, 200);
  EXPECT_EQ(other_status, 0);
  EXPECT_EQ(streams_ended, 20);
  EXPECT_EQ(server.wait(id)["state"], "done");
  const std::string glb = server.fetch("/api/jobs/" + id + "/files/mesh.glb");
  EXPECT_TRUE(glb == r.glb) << "the GLB under load differs from the GLB alone";
}

TEST(ServerApi, ThePageAndTheViewerAreServedFromTheBinary) {
  ServerFixture server;
  int status = 0;
  const std::string page = server.fetch("/", &status);
  EXPECT_EQ(status, 200);
  EXPECT_NE(page.find("createElement(\"model-viewer\")"), std::string::npos);
  EXPECT_NE(page.find("/vendor/model-viewer.min.js"), std::string::npos);
  EXPECT_EQ(page.find("https://"), std::string::npos) << "the page must load nothing from elsewhere";
  const std::string viewer = server.fetch("/vendor/model-viewer.min.js", &status);
  EXPECT_EQ(status, 200);
  EXPECT_GT(viewer.size(), 100000u);
  EXPECT_EQ(server.fetch("/example/front_rgb.png", &status), read_file(example_views() / "front_rgb.png"));
  const nlohmann::json info = nlohmann::json::parse(server.fetch("/api/info", &status));
  EXPECT_EQ(info["generate"]["available"], false);
  EXPECT_NE(info["generate"]["reason"].get<std::string>().find("doctor"), std::string::npos);
}

}  // namespace
}  // namespace u3d::server::test
