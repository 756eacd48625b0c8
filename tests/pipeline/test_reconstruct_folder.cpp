// The library facade for ISOMER: what a caller other than the CLI sees (progress events, cancellation,
// outputs written only on success, the output scale applied to the file alone).
#include <gtest/gtest.h>

#include <algorithm>

#include "core/synthetic_views.h"
#include "io/mesh_io.h"
#include "pipeline/reconstruct.h"

namespace u3d {
namespace {

struct Recorder : ProgressListener {
  std::vector<ProgressEvent> events;
  int cancel_at_step = -1;  // cancel once this step of any stage was reported
  bool cancel = false;
  void on_event(const ProgressEvent& e) override {
    events.push_back(e);
    if (e.kind == ProgressEvent::Kind::Step && e.step == cancel_at_step) cancel = true;
  }
  bool cancel_requested() override { return cancel; }
  size_t count(ProgressEvent::Kind kind, const std::string& text) const {
    return size_t(std::count_if(events.begin(), events.end(),
                                [&](const ProgressEvent& e) { return e.kind == kind && e.text == text; }));
  }
};

ReconstructRequest sphere_request(const std::string& name) {
  const auto dir = testing::fresh_temp_dir(name);
  testing::write_view_set(testing::sphere_views(0.6f, 128), dir / "views");
  ReconstructRequest r;
  r.views_dir = dir / "views";
  r.output = dir / "sphere.glb";
  r.options.coarse.steps = 12;
  r.options.refine.steps = 6;
  return r;
}

TEST(ReconstructFolder, ReportsStagesAndStepsToItsListener) {
  ReconstructRequest request = sphere_request("facade_events");
  request.previews = true;
  Recorder recorder;
  const ReconstructSummary summary = reconstruct_folder(request, &recorder);
  EXPECT_EQ(recorder.count(ProgressEvent::Kind::StageBegin, "loading views"), 1u);
  EXPECT_EQ(recorder.count(ProgressEvent::Kind::StageEnd, "loading views"), 1u);
  EXPECT_EQ(recorder.count(ProgressEvent::Kind::Step, "coarse reconstruction"), 12u);
  EXPECT_EQ(recorder.count(ProgressEvent::Kind::Step, "mesh refinement"), 6u);
  for (const ProgressEvent& e : recorder.events) {
    if (e.kind == ProgressEvent::Kind::Step) {
      EXPECT_TRUE(e.step >= 1 && e.step <= e.steps);
    }
  }
  std::vector<std::string> names;
  for (const StageTiming& t : summary.timings) names.push_back(t.name);
  EXPECT_EQ(names, (std::vector<std::string>{"load", "initial mesh", "coarse", "refine", "smooth and subdivide",
                                             "silhouette fit", "decimate", "texture", "write", "previews"}));
  ASSERT_EQ(summary.written.size(), 3u);
  for (const auto& p : summary.written) EXPECT_TRUE(std::filesystem::exists(p)) << p;
  EXPECT_TRUE(summary.topology.closed_manifold());
  for (float iou : summary.silhouette_iou) EXPECT_GT(iou, 0.9f);
}

TEST(ReconstructFolder, CancellingEndsTheWorkAndWritesNothing) {
  ReconstructRequest request = sphere_request("facade_cancel");
  request.previews = true;
  Recorder recorder;
  recorder.cancel_at_step = 3;
  EXPECT_THROW(reconstruct_folder(request, &recorder), Cancelled);
  EXPECT_EQ(recorder.count(ProgressEvent::Kind::Step, "coarse reconstruction"), 3u);
  EXPECT_EQ(recorder.count(ProgressEvent::Kind::StageEnd, "coarse reconstruction"), 0u);
  EXPECT_FALSE(std::filesystem::exists(request.output));
  for (const auto& entry : std::filesystem::directory_iterator(request.output.parent_path()))
    EXPECT_EQ(entry.path().filename(), "views") << "unexpected output " << entry.path();
}

TEST(ReconstructFolder, OfficialScaleAppliesToTheFileOnly) {
  ReconstructRequest request = sphere_request("facade_scale");
  request.options.run_coarse = request.options.run_refine = false;
  request.official_output_scale = true;
  Recorder quiet;
  const ReconstructSummary summary = reconstruct_folder(request, &quiet);
  const Mesh written = read_mesh(request.output);
  ASSERT_EQ(written.vertex_count(), summary.mesh.vertex_count());
  for (size_t i = 0; i < written.vertex_count(); ++i)
    EXPECT_LT((written.positions[i] - kOfficialOutputScale * summary.mesh.positions[i]).norm(), 1e-6f);
  // The reports are about the mesh in the views' frame.
  for (float iou : summary.silhouette_iou) EXPECT_GT(iou, 0.9f);
}

TEST(ReconstructFolder, RejectsABadOutputBeforeAnyWork) {
  ReconstructRequest request = sphere_request("facade_bad_output");
  request.output.replace_extension(".stl");
  Recorder recorder;
  try {
    reconstruct_folder(request, &recorder);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unsupported extension"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(recorder.events.empty());
}

TEST(ReconstructFolder, WithoutAnOutputWritesNothingAndKeepsTheMesh) {
  ReconstructRequest request = sphere_request("facade_no_output");
  const std::filesystem::path folder = request.output.parent_path();
  request.output.clear();
  const ReconstructSummary summary = reconstruct_folder(request);
  EXPECT_GT(summary.mesh.face_count(), 0u);
  EXPECT_TRUE(summary.written.empty());
  EXPECT_TRUE(std::none_of(summary.timings.begin(), summary.timings.end(),
                           [](const StageTiming& t) { return t.name == "write"; }));
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) files.push_back(entry.path().filename());
  EXPECT_EQ(files, std::vector<std::filesystem::path>{"views"});
  // Previews are written beside the mesh file, so they need one.
  request.previews = true;
  Recorder recorder;
  EXPECT_THROW(reconstruct_folder(request, &recorder), Error);
  EXPECT_TRUE(recorder.events.empty());
}

}  // namespace
}  // namespace u3d
