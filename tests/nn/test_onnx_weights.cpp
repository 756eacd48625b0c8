// The ONNX reader on small models assembled here with a protobuf writer (typed data fields, packed and
// unpacked, fp16 in int32_data, damaged files) and the Conv-order mapping's checks on hand-made graphs.
// The golden exports (raw_data, both opsets, fp16) are read in test_realesrgan.cpp and test_u2net.cpp.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <functional>

#include "core/error.h"
#include "nn/checkpoint/onnx_weights.h"

namespace u3d::nn {
namespace {

namespace fs = std::filesystem;

// Protobuf wire format: tag = field << 3 | wire type; varints little-endian base 128.
class Proto {
 public:
  Proto& varint(uint32_t field, uint64_t v) {
    raw_varint(uint64_t(field) << 3);
    raw_varint(v);
    return *this;
  }
  Proto& bytes(uint32_t field, const std::string& b) {
    raw_varint(uint64_t(field) << 3 | 2);
    raw_varint(b.size());
    out_ += b;
    return *this;
  }
  Proto& fixed32(uint32_t field, float v) {
    raw_varint(uint64_t(field) << 3 | 5);
    char b[4];
    std::memcpy(b, &v, 4);
    out_.append(b, 4);
    return *this;
  }
  Proto& message(uint32_t field, const Proto& m) { return bytes(field, m.out_); }
  const std::string& str() const { return out_; }

  static std::string packed_varints(std::initializer_list<uint64_t> values) {
    Proto p;
    for (uint64_t v : values) p.raw_varint(v);
    return p.out_;
  }

 private:
  void raw_varint(uint64_t v) {
    while (v >= 0x80) {
      out_ += char((v & 0x7f) | 0x80);
      v >>= 7;
    }
    out_ += char(v);
  }
  std::string out_;
};

Proto conv_node(const std::string& name, const std::vector<std::string>& inputs) {
  Proto n;
  for (const auto& i : inputs) n.bytes(1, i);
  n.bytes(2, name + "_out").bytes(3, name).bytes(4, "Conv");
  return n;
}

class OnnxReader : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("u3d_onnx_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const Proto& graph) {
    Proto model;
    model.varint(1, 8).bytes(2, "test").message(7, graph);
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << model.str();
    return path;
  }

  static void expect_error(const std::function<void()>& f, std::initializer_list<std::string> fragments) {
    try {
      f();
      ADD_FAILURE() << "no error";
    } catch (const u3d::Error& e) {
      const std::string msg = e.what();
      for (const auto& s : fragments) EXPECT_NE(msg.find(s), std::string::npos) << "'" << s << "' not in: " << msg;
    }
  }

  fs::path dir_;
};

TEST_F(OnnxReader, TypedFieldsAndNodes) {
  Proto graph;
  graph.message(1, conv_node("/c/Conv", {"x", "w16", "b"}));
  // FLOAT16 in int32_data (packed), the name after the data; FLOAT in unpacked float_data; INT64 packed.
  graph.message(5, Proto()
                       .bytes(1, Proto::packed_varints({2}))
                       .varint(2, 10)
                       .bytes(5, Proto::packed_varints({0x3c00, 0xc000}))
                       .bytes(8, "w16"));
  graph.message(5, Proto().varint(1, 2).varint(2, 1).fixed32(4, 1.5f).fixed32(4, -0.25f).bytes(8, "b"));
  graph.message(5, Proto().varint(1, 3).varint(2, 7).bytes(7, Proto::packed_varints({1, 2, 300})).bytes(8, "shape"));
  const OnnxGraph g = load_onnx(write("typed.onnx", graph));
  ASSERT_EQ(g.nodes.size(), 1u);
  EXPECT_EQ(g.nodes[0].op_type, "Conv");
  EXPECT_EQ(g.nodes[0].name, "/c/Conv");
  EXPECT_EQ(g.nodes[0].inputs, (std::vector<std::string>{"x", "w16", "b"}));
  EXPECT_EQ(g.initializers.at("w16").scalar_type(), torch::kHalf);
  EXPECT_TRUE(torch::equal(g.initializers.at("w16").to(torch::kFloat), torch::tensor({1.0f, -2.0f})));
  EXPECT_TRUE(torch::equal(g.initializers.at("b"), torch::tensor({1.5f, -0.25f})));
  EXPECT_TRUE(torch::equal(g.initializers.at("shape"), torch::tensor({1, 2, 300}, torch::kLong)));
}

// An empty packed data field (found by fuzz_onnx: appending its zero values copied to the null data() of
// an empty vector, undefined behaviour that UBSan reports) adds nothing; the tensor is empty.
TEST_F(OnnxReader, EmptyPackedDataIsAnEmptyTensor) {
  Proto graph;
  graph.message(1, conv_node("c", {"x", "w"}));
  graph.message(5, Proto().varint(1, 0).varint(2, 1).bytes(4, "").bytes(8, "w"));
  const OnnxGraph g = load_onnx(write("empty_data.onnx", graph));
  EXPECT_EQ(g.initializers.at("w").numel(), 0);
  EXPECT_EQ(g.initializers.at("w").sizes(), (std::vector<int64_t>{0}));
}

TEST_F(OnnxReader, DamagedTensorsNameTheFileAndTensor) {
  Proto short_raw;
  short_raw.message(1, conv_node("c", {"x", "w"}));
  short_raw.message(5, Proto().varint(1, 4).varint(2, 1).bytes(9, std::string(12, '\0')).bytes(8, "w"));
  expect_error([&] { load_onnx(write("short.onnx", short_raw)); }, {"short.onnx", "'w'", "12 bytes", "16"});

  Proto external;
  external.message(1, conv_node("c", {"x", "w"}));
  external.message(5, Proto().varint(1, 1).varint(2, 1).varint(14, 1).bytes(8, "w"));
  expect_error([&] { load_onnx(write("external.onnx", external)); }, {"external.onnx", "'w'", "external"});

  Proto strings;
  strings.message(1, conv_node("c", {"x", "w"}));
  strings.message(5, Proto().varint(1, 1).varint(2, 8).bytes(8, "w"));
  expect_error([&] { load_onnx(write("strings.onnx", strings)); }, {"strings.onnx", "'w'", "data type 8"});

  expect_error([&] { load_onnx(write("empty.onnx", Proto())); }, {"empty.onnx", "not an ONNX model"});
}

TEST(OnnxConvOrder, ChecksCountNamesAndBatchNorm) {
  OnnxGraph g;
  g.initializers["onnx::Conv_1"] = torch::zeros({2, 1, 3, 3});
  g.initializers["onnx::Conv_2"] = torch::zeros({2});
  g.initializers["b.weight"] = torch::ones({1, 2, 3, 3});
  g.initializers["b.bias"] = torch::ones({1});
  g.nodes = {{"/a/Conv", "Conv", {"x", "onnx::Conv_1", "onnx::Conv_2"}, {"y"}},
             {"/b/Conv", "Conv", {"y", "b.weight", "b.bias"}, {"z"}}};
  const TensorMap m = conv_weights_in_graph_order(g, {"a", "b"}, "ok.onnx");
  EXPECT_EQ(m.size(), 4u);
  EXPECT_TRUE(torch::equal(m.at("b.weight"), g.initializers.at("b.weight")));
  EXPECT_TRUE(torch::equal(m.at("a.bias"), g.initializers.at("onnx::Conv_2")));

  auto expect_error = [&](const std::function<void()>& f, std::initializer_list<std::string> fragments) {
    try {
      f();
      ADD_FAILURE() << "no error";
    } catch (const u3d::Error& e) {
      for (const auto& s : fragments) EXPECT_NE(std::string(e.what()).find(s), std::string::npos) << e.what();
    }
  };
  expect_error([&] { conv_weights_in_graph_order(g, {"a", "b", "c"}, "f.onnx"); }, {"f.onnx", "2 Conv nodes", "3"});
  // The order puts b's weights at a: an export of another architecture.
  expect_error([&] { conv_weights_in_graph_order(g, {"b", "a"}, "f.onnx"); }, {"f.onnx", "b.weight", "another layer"});
  OnnxGraph computed = g;
  computed.nodes[1].inputs[1] = "computed_weight";
  expect_error(
      [&] {
        conv_weights_in_graph_order(computed, {"a", "b"}, "f.onnx");
      },
      {"f.onnx", "computed_weight", "not an initializer"});
  OnnxGraph bn = g;
  bn.nodes.push_back({"/bn", "BatchNormalization", {"z"}, {"w"}});
  expect_error([&] { conv_weights_in_graph_order(bn, {"a", "b"}, "f.onnx"); }, {"f.onnx", "BatchNormalization"});
}

}  // namespace
}  // namespace u3d::nn
