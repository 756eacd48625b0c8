#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/temp_dir.h"

namespace fs = std::filesystem;
using namespace u3d;

namespace {

fs::path fresh_dir(const std::string& name) {
  return u3d::testing::fresh_temp_dir("atomic_" + name);
}

size_t entries(const fs::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

}  // namespace

TEST(AtomicFile, ThrowingWriterLeavesNoFile) {
  fs::path dir = fresh_dir("throwing");
  EXPECT_THROW(write_atomically(dir / "out.txt",
                                [](const fs::path& tmp) {
                                  std::ofstream(tmp) << "half of the content";
                                  throw std::runtime_error("writer failed midway");
                                }),
               std::runtime_error);
  EXPECT_EQ(entries(dir), 0u) << "neither the target nor the temporary file may remain";
}

TEST(AtomicFile, ThrowingWriterKeepsThePreviousFile) {
  fs::path dir = fresh_dir("keep");
  std::ofstream(dir / "out.txt") << "old";
  EXPECT_THROW(write_atomically(dir / "out.txt", [](const fs::path& tmp) {
                 std::ofstream(tmp) << "new";
                 throw Error("failed");
               }),
               Error);
  std::ifstream in(dir / "out.txt");
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(content, "old");
  EXPECT_EQ(entries(dir), 1u);
}

TEST(AtomicFile, SuccessfulWriteReplacesTheTargetAndKeepsTheExtension) {
  fs::path dir = fresh_dir("success");
  fs::path seen;
  write_atomically(dir / "out.png", [&](const fs::path& tmp) {
    seen = tmp;
    std::ofstream(tmp) << "data";
  });
  EXPECT_EQ(seen.extension(), ".png");
  EXPECT_EQ(seen.parent_path(), dir);
  EXPECT_TRUE(fs::exists(dir / "out.png"));
  EXPECT_EQ(entries(dir), 1u);
}

TEST(AtomicFile, MissingFolderIsAClearError) {
  fs::path dir = fresh_dir("missing");
  try {
    write_atomically(dir / "nope" / "out.txt", [](const fs::path&) { FAIL() << "writer must not run"; });
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
}

TEST(AtomicFolder, ThrowingWriterLeavesNoFolder) {
  const fs::path parent = fresh_dir("folder_throw");
  EXPECT_THROW(write_folder_atomically(parent / "out",
                                       [](const fs::path& folder) {
                                         std::ofstream(folder / "first.png") << "x";
                                         throw Error("second view failed");
                                       }),
               Error);
  EXPECT_EQ(entries(parent), 0u);
}

TEST(AtomicFolder, NewFolderAppearsWholeAndAnExistingOneIsWrittenInPlace) {
  const fs::path parent = fresh_dir("folder_ok");
  write_folder_atomically(parent / "out", [&](const fs::path& folder) {
    EXPECT_NE(folder, parent / "out");  // a temporary sibling while it is being filled
    EXPECT_FALSE(fs::exists(parent / "out"));
    std::ofstream(folder / "a.txt") << "a";
  });
  EXPECT_TRUE(fs::exists(parent / "out" / "a.txt"));
  EXPECT_EQ(entries(parent), 1u);
  write_folder_atomically(parent / "out", [&](const fs::path& folder) {
    EXPECT_EQ(folder, parent / "out");
    std::ofstream(folder / "b.txt") << "b";
  });
  EXPECT_EQ(entries(parent / "out"), 2u);
}
