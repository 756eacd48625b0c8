#include "nn/checkpoint/safetensors.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"

namespace fs = std::filesystem;
using u3d::nn::load_safetensors;
using u3d::nn::save_safetensors;
using u3d::nn::TensorMap;

namespace {

class SafetensorsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("u3d_safetensors_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes a file with the given header text and data bytes, bypassing save_safetensors.
  fs::path write_raw(const std::string& header, const std::string& data, const std::string& name = "raw.safetensors",
                     std::int64_t header_len_override = -1) {
    fs::path p = dir_ / name;
    std::ofstream os(p, std::ios::binary);
    std::uint64_t len = header_len_override >= 0 ? static_cast<std::uint64_t>(header_len_override) : header.size();
    os.write(reinterpret_cast<const char*>(&len), 8);
    os << header << data;
    return p;
  }

  // Expects load_safetensors(p) to throw u3d::Error whose message contains every fragment.
  static void expect_error(const fs::path& p, std::initializer_list<std::string> fragments) {
    try {
      load_safetensors(p);
      FAIL() << "no error for " << p;
    } catch (const u3d::Error& e) {
      std::string msg = e.what();
      for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
    }
  }

  fs::path dir_;
};

TEST_F(SafetensorsTest, RoundTripsEveryDtype) {
  torch::manual_seed(1);
  TensorMap in;
  in["f32"] = torch::randn({2, 3});
  in["f16"] = torch::randn({4}).to(torch::kFloat16);
  in["bf16"] = torch::randn({3, 1, 2}).to(torch::kBFloat16);
  in["f64"] = torch::randn({5}, torch::kFloat64);
  in["i64"] = torch::tensor({int64_t{-3}, int64_t{0}, int64_t{1} << 40}, torch::kInt64);
  in["i32"] = torch::tensor({-7, 9}, torch::kInt32);
  in["u8"] = torch::tensor({0, 128, 255}, torch::kUInt8).reshape({1, 3});
  in["bool"] = torch::tensor({true, false, true});
  in["scalar"] = torch::tensor(2.5f);
  in["empty"] = torch::zeros({0, 4});
  in["strided"] = torch::arange(12, torch::kFloat32).reshape({3, 4}).t();  // non-contiguous input
  fs::path p = dir_ / "all.safetensors";
  save_safetensors(in, p);

  // The data section starts 8-byte aligned.
  std::ifstream is(p, std::ios::binary);
  std::uint64_t header_len = 0;
  is.read(reinterpret_cast<char*>(&header_len), 8);
  EXPECT_EQ(header_len % 8, 0u);

  TensorMap out = load_safetensors(p);
  ASSERT_EQ(out.size(), in.size());
  for (const auto& [name, t] : in) {
    ASSERT_TRUE(out.count(name)) << name;
    EXPECT_EQ(out[name].scalar_type(), t.scalar_type()) << name;
    EXPECT_EQ(out[name].sizes(), t.sizes()) << name;
    EXPECT_TRUE(torch::equal(out[name], t)) << name;
  }
}

TEST_F(SafetensorsTest, ReadsGoldenFileFromReferenceWriter) {
  TensorMap m = load_safetensors(fs::path(UNIQUE3D_TEST_DATA) / "nn/clip_vision/inputs.safetensors");
  ASSERT_TRUE(m.count("test_image_uint8"));
  EXPECT_EQ(m["test_image_uint8"].scalar_type(), torch::kUInt8);
  EXPECT_EQ(m["test_image_uint8"].sizes(), (std::vector<int64_t>{48, 64, 3}));
  ASSERT_TRUE(m.count("pixel_values"));
  EXPECT_EQ(m["pixel_values"].scalar_type(), torch::kFloat32);
}

TEST_F(SafetensorsTest, AcceptsMetadata) {
  auto p = write_raw(R"({"__metadata__":{"format":"pt"},"a":{"dtype":"I32","shape":[1],"data_offsets":[0,4]}})",
                     std::string("\x07\x00\x00\x00", 4));
  TensorMap m = load_safetensors(p);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m["a"].item<int32_t>(), 7);
}

TEST_F(SafetensorsTest, TruncatedFilesAreErrors) {
  TensorMap in{{"weight", torch::randn({16, 16})}};
  fs::path p = dir_ / "t.safetensors";
  save_safetensors(in, p);
  auto full = fs::file_size(p);

  fs::resize_file(p, full - 10);  // data cut short
  expect_error(p, {p.string(), "weight", "beyond"});

  fs::resize_file(p, 20);  // header cut short
  expect_error(p, {p.string(), "header length"});

  fs::resize_file(p, 5);  // not even the length field
  expect_error(p, {p.string(), "truncated"});
}

TEST_F(SafetensorsTest, MissingFileIsError) { expect_error(dir_ / "nope.safetensors", {"nope.safetensors"}); }

TEST_F(SafetensorsTest, BadHeadersAreErrors) {
  expect_error(write_raw("{not json", ""), {"raw.safetensors", "JSON"});
  expect_error(write_raw("[1,2]", ""), {"not a JSON object"});
  expect_error(write_raw(R"({"x":{"dtype":"F8","shape":[1],"data_offsets":[0,1]}})", "a"), {"'x'", "unsupported dtype"});
  expect_error(write_raw(R"({"x":{"dtype":"F32","shape":[1]}})", "abcd"), {"'x'", "data_offsets"});
  expect_error(write_raw(R"({"x":{"dtype":"F32","shape":[-1],"data_offsets":[0,4]}})", "abcd"), {"'x'", "non-negative"});
  expect_error(write_raw(R"({"x":{"dtype":"F32","shape":[2],"data_offsets":[0,4]}})", "abcd"), {"'x'", "needs 8 bytes"});
  expect_error(write_raw(R"({"x":{"dtype":"F32","shape":[1],"data_offsets":[4,0]}})", "abcd"), {"'x'", "< begin"});
  // A length field far larger than the file.
  expect_error(write_raw("{}", "", "huge.safetensors", 1ll << 40), {"huge.safetensors", "header length"});
}

TEST_F(SafetensorsTest, OffsetsOutOfRangeAreErrors) {
  expect_error(write_raw(R"({"w":{"dtype":"U8","shape":[4],"data_offsets":[2,6]}})", "abcd"), {"'w'", "beyond"});
}

TEST_F(SafetensorsTest, OverlappingTensorsAreErrors) {
  expect_error(write_raw(R"({"a":{"dtype":"U8","shape":[8],"data_offsets":[0,8]},)"
                         R"("b":{"dtype":"U8","shape":[2],"data_offsets":[4,6]},)"
                         R"("c":{"dtype":"U8","shape":[1],"data_offsets":[6,7]}})",
                         "abcdefgh"),
               {"'a'", "overlap"});
}

TEST_F(SafetensorsTest, SaveRejectsUnsupportedDtypeWithoutWriting) {
  fs::path p = dir_ / "bad.safetensors";
  TensorMap in{{"c", torch::zeros({2}, torch::kComplexFloat)}};
  EXPECT_THROW(save_safetensors(in, p), u3d::Error);
  EXPECT_FALSE(fs::exists(p));
}

}  // namespace

// Tensors are views of the mapped file, copied on write: writing to one changes neither the file nor
// a later load, and a view outlives the map it came from.
TEST_F(SafetensorsTest, LoadedTensorsAreTheProcesssOwnToWrite) {
  const fs::path path = dir_ / "writable.safetensors";
  const torch::Tensor w = torch::arange(5000, torch::kFloat32);
  save_safetensors({{"a", w}, {"b", w * 2}}, path);
  torch::Tensor kept;
  {
    TensorMap m = load_safetensors(path);
    m.at("a").fill_(-1.0f);
    EXPECT_EQ(m.at("a").sum().item<float>(), -5000.0f);
    kept = m.at("b");
  }
  EXPECT_TRUE(torch::equal(kept, w * 2));
  EXPECT_TRUE(torch::equal(load_safetensors(path).at("a"), w));
}
