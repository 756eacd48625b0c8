// The objects of a batch: what a folder or a list file holds, their names (unique, independent of the
// listing's order), and clear errors for inputs that are not photos or view folders.
#include <gtest/gtest.h>

#include <fstream>

#include "batch/batch_inputs.h"
#include "core/error.h"
#include "core/synthetic_views.h"

namespace u3d {
namespace {

namespace fs = std::filesystem;

void touch(const fs::path& path) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << "x";
}

// A folder with the eight view files (their content is not read when listing).
void fake_view_folder(const fs::path& dir) {
  for (View v : kAllViews)
    for (bool normal : {false, true}) touch(dir / view_file_name(v, normal));
}

std::string error_of(const fs::path& inputs) {
  try {
    list_batch_inputs(inputs);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(BatchInputs, FolderOfPhotosAndViewFolders) {
  const fs::path dir = testing::fresh_temp_dir("batch_inputs_folder");
  touch(dir / "in" / "mug.png");
  touch(dir / "in" / "Chair 2.JPG");
  touch(dir / "in" / "notes.txt");  // skipped
  touch(dir / "in" / ".hidden.png");
  fake_view_folder(dir / "in" / "spot");
  const std::vector<BatchInput> inputs = list_batch_inputs(dir / "in");
  ASSERT_EQ(inputs.size(), 3u);
  EXPECT_EQ(inputs[0].name, "Chair_2");
  EXPECT_EQ(inputs[0].mode, BatchMode::Generate);
  EXPECT_EQ(inputs[1].name, "mug");
  EXPECT_EQ(inputs[2].name, "spot");
  EXPECT_EQ(inputs[2].mode, BatchMode::Reconstruct);
  EXPECT_EQ(inputs[2].path, dir / "in" / "spot");
}

TEST(BatchInputs, ListFileWithCommentsAndRelativePaths) {
  const fs::path dir = testing::fresh_temp_dir("batch_inputs_list");
  touch(dir / "photos" / "a.png");
  fake_view_folder(dir / "views" / "b");
  touch(dir / "elsewhere" / "c.jpeg");
  std::ofstream(dir / "list.txt") << "# objects\n\nphotos/a.png\n  views/b  \n" << (dir / "elsewhere" / "c.jpeg").string()
                                  << "\n# done\n";
  const std::vector<BatchInput> inputs = list_batch_inputs(dir / "list.txt");
  ASSERT_EQ(inputs.size(), 3u);
  EXPECT_EQ(inputs[0].name, "a");
  EXPECT_EQ(inputs[0].path, dir / "photos" / "a.png");
  EXPECT_EQ(inputs[1].name, "b");
  EXPECT_EQ(inputs[1].mode, BatchMode::Reconstruct);
  EXPECT_EQ(inputs[2].name, "c");
}

TEST(BatchInputs, CollidingNamesGetStableSuffixes) {
  const std::vector<BatchInput> a =
      name_batch_inputs({"x/cup.png", "y/cup.jpg", "z/plate.png"}, {"x/cup.png", "y/cup.jpg", "z/plate.png"},
                        {BatchMode::Generate, BatchMode::Generate, BatchMode::Generate});
  ASSERT_EQ(a.size(), 3u);
  EXPECT_EQ(a[2].name, "plate");
  EXPECT_NE(a[0].name, a[1].name);
  for (int i = 0; i < 2; ++i) EXPECT_EQ(a[i].name.rfind("cup-", 0), 0u) << a[i].name;
  // The same inputs listed in another order, beside others: the same names.
  const std::vector<BatchInput> b = name_batch_inputs(
      {"q/mug.png", "y/cup.jpg", "x/cup.png"}, {"q/mug.png", "y/cup.jpg", "x/cup.png"},
      {BatchMode::Generate, BatchMode::Generate, BatchMode::Generate});
  for (const BatchInput& i : b)
    for (const BatchInput& j : a)
      if (i.path == j.path) EXPECT_EQ(i.name, j.name);
  // The same file listed twice cannot have two folders.
  EXPECT_THROW(name_batch_inputs({"x/cup.png", "x/cup.png"}, {"x/cup.png", "x/cup.png"},
                                 {BatchMode::Generate, BatchMode::Generate}),
               Error);
}

TEST(BatchInputs, BadInputsAreClearErrors) {
  const fs::path dir = testing::fresh_temp_dir("batch_inputs_bad");
  EXPECT_NE(error_of(dir / "missing").find("do not exist"), std::string::npos);
  fs::create_directories(dir / "empty");
  EXPECT_NE(error_of(dir / "empty").find("hold no photo"), std::string::npos);
  fake_view_folder(dir / "single");
  EXPECT_NE(error_of(dir / "single").find("is a view folder itself"), std::string::npos);
  touch(dir / "partial" / "obj" / "front_rgb.png");
  EXPECT_NE(error_of(dir / "partial").find("has no front_normal.png"), std::string::npos) << error_of(dir / "partial");
  std::ofstream(dir / "list.txt") << "# header\nnothing_here.png\n";
  EXPECT_NE(error_of(dir / "list.txt").find("list.txt:2: "), std::string::npos) << error_of(dir / "list.txt");
  touch(dir / "doc.txt");
  std::ofstream(dir / "list2.txt") << "doc.txt\n";
  EXPECT_NE(error_of(dir / "list2.txt").find("neither a photo"), std::string::npos) << error_of(dir / "list2.txt");
}

}  // namespace
}  // namespace u3d
