// The progress lines the command prints: stages, and the steps of slow loops with the time left.
#include "core/progress.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <regex>
#include <string>
#include <thread>
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

TEST(StderrProgress, PrintsStepsOfSlowLoopsWithTheTimeLeft) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  StderrProgress lines(false, /*step_interval_seconds=*/0.0, f);
  ProgressScope scope(&lines);
  {
    StageTimer stage("denoising");
    for (int i = 1; i <= 3; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      progress_step("denoise", i, 3);
    }
  }
  const std::string text = printed(f);
  EXPECT_NE(text.find("[unique3d] denoising ...\n"), std::string::npos) << text;
  EXPECT_TRUE(std::regex_search(text, std::regex(R"(\[unique3d\] denoise 1/3, [0-9]+ s, about [0-9]+ s left\n)")))
      << text;
  EXPECT_TRUE(std::regex_search(text, std::regex(R"(\[unique3d\] denoise 3/3, [0-9]+ s\n)"))) << text;
  EXPECT_TRUE(std::regex_search(text, std::regex(R"(\[unique3d\] denoising done in [0-9.]+ s)"))) << text;
  std::fclose(f);
}

// A stage that runs one loop after another (the upscaler's tiles, image by image): each loop's time
// left comes from that loop's own pace, not from the whole stage's time.
TEST(StderrProgress, EachLoopEstimatesFromItsOwnStart) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  StderrProgress lines(false, /*step_interval_seconds=*/0.0, f);
  ProgressScope scope(&lines);
  {
    StageTimer stage("upscaling");
    for (int image = 0; image < 3; ++image)
      for (int i = 1; i <= 2; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(600));
        progress_step("upscale", i, 2);
      }
  }
  // The third image's first tile: 3 s into the stage, 0.6 s into its loop; one tile left.
  const std::string text = printed(f);
  const std::regex first_tile(R"(upscale 1/2, [0-9]+ s, about ([0-9]+) s left)");
  std::vector<std::string> left;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), first_tile); it != std::sregex_iterator(); ++it)
    left.push_back((*it)[1]);
  ASSERT_EQ(left.size(), 3u) << text;
  EXPECT_EQ(left[2], "1") << text;  // from the stage's start it would be 3 s
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
