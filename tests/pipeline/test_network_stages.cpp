// The facade's network stages on a model folder in the official layout made of the tiny golden models,
// at a small size: the multi-view stage writes four views and is reproducible from its seed; the normal
// stage turns them into a view set with world-space normal maps and the photo's mask on the front view.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "core/memory.h"
#include "core/synthetic_views.h"
#include "core/view_set.h"
#include "pipeline/image_stages.h"
#include "pipeline/multiview_stage.h"
#include "pipeline/network_stage.h"
#include "pipeline/normal_stage.h"
#include "pipeline/tiny_model_folder.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

NetworkStageSummary views_with_seed(const fs::path& dir, const fs::path& out, uint64_t seed) {
  MultiViewRequest r;
  r.image = dir / "photo.png";
  r.output_dir = out;
  r.network.models = dir / "models";
  r.network.precision = nn::Precision::kFp32;
  r.network.seed = seed;
  r.options.size = 32;
  r.options.steps = 2;
  return generate_views(r);
}

TEST(NetworkStages, MultiViewThenNormalsGiveAViewSet) {
  set_progress_quiet(true);
  const fs::path dir = testing::fresh_temp_dir("network_stages");
  testing::write_tiny_model_folder(dir / "models");
  testing::write_disk_photo(dir / "photo.png");

  const NetworkStageSummary mv = views_with_seed(dir, dir / "views", 7);
  EXPECT_EQ(mv.written.size(), 4u);
  EXPECT_EQ(mv.precision, nn::Precision::kFp32);
  for (View v : kAllViews) {
    const Image view = load_image(dir / "views" / view_file_name(v, false));
    EXPECT_EQ(view.width, 32);
    EXPECT_EQ(view.channels, 3);
  }
  // The seed decides the noise: the same seed gives the same views, another seed other views.
  views_with_seed(dir, dir / "again", 7);
  views_with_seed(dir, dir / "other", 8);
  const auto pixels = [&](const char* folder) { return load_image(dir / folder / "right_rgb.png").data; };
  EXPECT_EQ(pixels("views"), pixels("again"));
  EXPECT_NE(pixels("views"), pixels("other"));

  NormalRequest n;
  n.views_dir = dir / "views";
  n.front = dir / "photo.png";
  n.output_dir = dir / "view_set";
  n.network.models = dir / "models";
  n.network.precision = nn::Precision::kFp32;
  n.options.size = 32;
  n.options.steps = 2;
  const NetworkStageSummary normals = predict_view_normals(n);
  NetworkStageSummary prepare;
  const Image prepared = quantized_8bit(run_prepare_stage(load_photo(n.front.value()), n.network, false, prepare));
  EXPECT_EQ(normals.written.size(), 8u);
  for (View v : kAllViews) {
    const Image rgb = load_image(dir / "view_set" / view_file_name(v, false));
    const Image normal = load_image(dir / "view_set" / view_file_name(v, true));
    EXPECT_EQ(rgb.channels, 4);
    EXPECT_EQ(rgb.width, prepared.width);  // the largest input view: the prepared photo
    EXPECT_EQ(normal.channels, 4);
    EXPECT_EQ(normal.width, 128);  // the model's 32 px, x4 by Real-ESRGAN
  }
  // The front view is the photo prepared as generate prepares it, with its mask, which the front normal
  // map takes too.
  const Image front = load_image(dir / "view_set" / "front_rgb.png");
  EXPECT_EQ(front.data, prepared.data);
  EXPECT_EQ(front.pixel(front.width / 2, front.height / 2)[3], 1.f);
  EXPECT_EQ(front.pixel(0, 0)[3], 0.f);
  const Image front_normal = load_image(dir / "view_set" / "front_normal.png");
  EXPECT_EQ(front_normal.pixel(64, 64)[3], 1.f);
  EXPECT_EQ(front_normal.pixel(2, 2)[3], 0.f);
  fs::remove_all(dir);
}

TEST(NetworkStages, RejectsBadRequestsBeforeLoading) {
  const fs::path dir = testing::fresh_temp_dir("network_stages_bad");
  testing::write_disk_photo(dir / "photo.png");
  MultiViewRequest r;
  r.image = dir / "photo.png";
  r.output_dir = dir / "out";
  r.network.models = dir / "no_models";
  r.options.size = 30;
  EXPECT_THROW(generate_views(r), Error);  // size not a multiple of 8
  r.options.size = 32;
  try {
    generate_views(r);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no_models"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

// generate reports each stage's own peak memory (MemoryPeakWatch) without resetting the process's peak,
// which getrusage and /usr/bin/time -v report.
TEST(NetworkStages, StagePeakMemoryLeavesTheProcessPeakAlone) {
  MemoryPeakWatch with_block;
  {
    std::vector<char> block(size_t(300) << 20);  // 300 MiB, touched, held over many samples, then freed
    for (size_t i = 0; i < block.size(); i += 4096) block[i] = 1;
    std::this_thread::sleep_for(std::chrono::milliseconds(40 * MemoryPeakWatch::kSampleMilliseconds));
  }
  release_freed_memory();  // in case the allocator keeps freed memory (core/memory.h)
  MemoryPeakWatch after_block;
  const double block_peak = with_block.peak_mib();
  const double later_peak = after_block.peak_mib();
  EXPECT_LT(later_peak, block_peak - 250.0);  // a watch started after the block does not see it
  EXPECT_GE(peak_memory_mib(), block_peak);   // the process's peak still does
}

}  // namespace
}  // namespace u3d
