// The progress lines the command prints: stages, and the steps of slow loops with the time left.
#include "core/progress.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <regex>
#include <string>
#include <vector>

namespace u3d {
namespace {

std::string printed(std::FILE* f) {
  std::rewind(f);
  std::string text;
  char buf[256];
  while (std::fgets(buf, sizeof buf, f)) text += buf;
  return text;
}

// A clock the test moves by hand, so the printed times are exact whatever the machine's load.
StderrProgress::Clock::time_point g_fake_now;
StderrProgress::Clock::time_point fake_now() { return g_fake_now; }
void advance(double seconds) {
  g_fake_now += std::chrono::duration_cast<StderrProgress::Clock::duration>(std::chrono::duration<double>(seconds));
}

TEST(StderrProgress, PrintsStepsOfSlowLoopsWithTheTimeLeft) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  StderrProgress lines(false, /*step_interval_seconds=*/0.0, f, fake_now);
  ProgressScope scope(&lines);
  {
    StageTimer stage("denoising");
    for (int i = 1; i <= 3; ++i) {
      advance(20);
      progress_step("denoise", i, 3);
    }
  }
  const std::string text = printed(f);
  EXPECT_NE(text.find("[unique3d] denoising ...\n"), std::string::npos) << text;
  EXPECT_NE(text.find("[unique3d] denoise 1/3, 20 s, about 40 s left\n"), std::string::npos) << text;
  EXPECT_NE(text.find("[unique3d] denoise 2/3, 40 s, about 20 s left\n"), std::string::npos) << text;
  EXPECT_NE(text.find("[unique3d] denoise 3/3, 1 min 0 s\n"), std::string::npos) << text;
  EXPECT_TRUE(std::regex_search(text, std::regex(R"(\[unique3d\] denoising done in [0-9.]+ s)"))) << text;
  std::fclose(f);
}

// A stage that runs one loop after another (the upscaler's tiles, image by image): each loop's time
// left comes from that loop's own pace, not from the whole stage's time.
TEST(StderrProgress, EachLoopEstimatesFromItsOwnStart) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  StderrProgress lines(false, /*step_interval_seconds=*/0.0, f, fake_now);
  ProgressScope scope(&lines);
  {
    StageTimer stage("upscaling");
    for (int image = 0; image < 3; ++image)
      for (int i = 1; i <= 2; ++i) {
        advance(10);
        progress_step("upscale", i, 2);
      }
  }
  // Each image's first tile: one tile of 10 s left. From the stage's start the third image's would be
  // 50 s (5 tiles in 50 s).
  const std::string text = printed(f);
  EXPECT_NE(text.find("upscale 1/2, 10 s, about 10 s left\n"), std::string::npos) << text;
  EXPECT_NE(text.find("upscale 1/2, 30 s, about 10 s left\n"), std::string::npos) << text;
  EXPECT_NE(text.find("upscale 1/2, 50 s, about 10 s left\n"), std::string::npos) << text;
  std::fclose(f);
}

TEST(StderrProgress, FastLoopsPrintNoSteps) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  StderrProgress lines(false, /*step_interval_seconds=*/60.0, f);
  ProgressScope scope(&lines);
  {
    StageTimer stage("coarse");
    for (int i = 1; i <= 200; ++i) progress_step("coarse", i, 200);
  }
  const std::string text = printed(f);
  EXPECT_EQ(text.find("/200"), std::string::npos) << text;
  EXPECT_NE(text.find("coarse done in"), std::string::npos) << text;
  std::fclose(f);
}

}  // namespace
}  // namespace u3d
