// RRDBNet (Real-ESRGAN x4) against the realesrgan_tiny golden case, loaded from basicsr-named safetensors and
// from both ONNX exports; its CPU path (oneDNN, nn/models/rrdbnet_cpu.h) against the layer-by-layer one; the
// tiled upscaler against the untiled network; the uint8 RGB/RGBA wrapper.
#include <gtest/gtest.h>

#include <unistd.h>

#include <fstream>

#include "core/progress.h"
#include "golden.h"
#include "nn/checkpoint/onnx_weights.h"
#include "nn/layers/layers.h"
#include "nn/models/rrdbnet.h"
#include "nn/pipelines/upscale.h"
#include "nn/precision.h"
#include "required_skip.h"

namespace u3d::nn {
namespace {

using namespace u3d::nn::test;
namespace fs = std::filesystem;

// The golden case asks for 1e-5 on the raw output (max |value| 5.6; OpenCV DNN vs torch: 4.7e-6).
constexpr double kRealEsrganTolerance = 1e-5;

TEST(RealEsrgan, TinyMatchesTheReferenceFromEveryFormat) {
  torch::NoGradGuard no_grad;
  const torch::Tensor input = golden_tensors("realesrgan_tiny", "inputs").at("input");
  const torch::Tensor expected = golden_tensors("realesrgan_tiny", "outputs").at("output");
  for (const char* file : {"weights.safetensors", "rrdbnet_tiny_op11.onnx", "rrdbnet_tiny_op17.onnx"}) {
    SCOPED_TRACE(file);
    RRDBNet net = load_rrdbnet(golden_dir("realesrgan_tiny") / file);
    EXPECT_EQ(net->config.num_feat, 8);
    EXPECT_EQ(net->config.num_block, 1);
    EXPECT_EQ(net->config.num_grow, 4);
    EXPECT_CLOSE_TO_GOLDEN(net->forward(input), expected, kRealEsrganTolerance);
  }
}

TEST(RealEsrgan, OnnxInitializersAreTheStateDict) {
  const OnnxGraph graph = load_onnx(golden_dir("realesrgan_tiny") / "rrdbnet_tiny_op17.onnx");
  const TensorMap reference = golden_tensors("realesrgan_tiny", "weights");
  RRDBNet layout(RRDBNetConfig::from_weights(reference, "weights"), torch::TensorOptions().device(torch::kMeta));
  const TensorMap mapped = conv_weights_in_graph_order(graph, conv_module_names(*layout), "op17");
  ASSERT_EQ(mapped.size(), reference.size());
  for (const auto& [name, tensor] : reference) EXPECT_TRUE(torch::equal(mapped.at(name), tensor)) << name;
}

// max |a - b| / max |b| (golden.h's relative_error is the L2 ratio)
double peak_relative_error(const torch::Tensor& a, const torch::Tensor& b) {
  return max_abs_diff(a, b) / b.to(torch::kDouble).abs().max().item<double>();
}

// A network whose widths are multiples of every channel block (32 features, growth 16, 2 blocks), random.
RRDBNet aligned_random_net() {
  RRDBNetConfig config;
  config.num_feat = 32;
  config.num_grow = 16;
  config.num_block = 2;
  RRDBNet net(config, torch::TensorOptions());
  torch::manual_seed(6);
  randomize_parameters(*net, 0.05);
  return net;
}

// The CPU path (blocked layout, fused post-ops, padded widths for the tiny golden net's 8 and 4 channels)
// computes what the layers compute, in fp32 to rounding: a batch of two images of an odd size.
TEST(RealEsrgan, CpuPathComputesWhatTheLayersComputeInFp32) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(7);
  const torch::Tensor input = torch::rand({2, 3, 13, 17});
  RRDBNet tiny = load_rrdbnet(golden_dir("realesrgan_tiny") / "weights.safetensors");
  RRDBNet aligned = aligned_random_net();
  for (RRDBNet* net : {&tiny, &aligned}) {
    SCOPED_TRACE((*net)->config.num_feat);
    ASSERT_TRUE(RrdbCpuForward::applies(input, (*net)->conv_first->weight));
    const torch::Tensor fast = (*net)->forward(input);
    const torch::Tensor layers = (*net)->forward_layers(input);
    ASSERT_EQ(fast.sizes(), layers.sizes());
    EXPECT_EQ(fast.scalar_type(), torch::kFloat);
    EXPECT_LE(peak_relative_error(fast, layers), 1e-5);
    // Each image of the batch is the image alone.
    EXPECT_LE(peak_relative_error(fast[1], (*net)->forward(input.slice(0, 1, 2))[0]), 1e-6);
  }
}

// In bf16 the CPU path rounds once per convolution (the layers round after the convolution, the
// LeakyReLU, the scaling and the sum): against the fp32 network it is as close as the layers or closer,
// and within the bf16 golden tolerance.
TEST(RealEsrgan, CpuPathInBf16StaysCloseToFp32) {
  U3D_SKIP_UNLESS_BF16_KERNELS();
  torch::NoGradGuard no_grad;
  torch::manual_seed(8);
  const torch::Tensor input = torch::rand({1, 3, 24, 20});
  RRDBNet net = aligned_random_net();
  const torch::Tensor reference = net->forward_layers(input);
  set_precision(*net, Precision::kBf16);
  ASSERT_TRUE(RrdbCpuForward::applies(input, net->conv_first->weight));
  const torch::Tensor fast = net->forward(input);
  EXPECT_EQ(fast.scalar_type(), torch::kFloat);
  const double fast_error = peak_relative_error(fast, reference);
  const double layers_error = peak_relative_error(net->forward_layers(input), reference);
  std::printf("  bf16 vs fp32: CPU path %.3g, layers %.3g (relative to the largest output)\n", fast_error,
              layers_error);
  EXPECT_LE(fast_error, 2e-2);
  EXPECT_LE(fast_error, 1.1 * layers_error);
}

class RealEsrganFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("u3d_esrgan_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The first `keep` bytes of a golden file, written to dir_/name.
  fs::path truncated_copy(const fs::path& from, size_t keep, const std::string& name) {
    std::ifstream in(from, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(std::min(keep, bytes.size())));
    return path;
  }

  template <class F>
  static void expect_error(F&& load, std::initializer_list<std::string> fragments) {
    try {
      load();
      ADD_FAILURE() << "no error";
    } catch (const u3d::Error& e) {
      const std::string msg = e.what();
      for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
    }
  }

  fs::path dir_;
};

TEST_F(RealEsrganFiles, TruncatedOnnxNamesTheFile) {
  const fs::path op17 = golden_dir("realesrgan_tiny") / "rrdbnet_tiny_op17.onnx";
  for (size_t keep : {size_t{5}, size_t{20000}, fs::file_size(op17) - 3}) {
    const fs::path path = truncated_copy(op17, keep, "cut.onnx");
    expect_error([&] { load_rrdbnet(path); }, {"cut.onnx", "truncated"});
  }
}

TEST_F(RealEsrganFiles, WrongArchitectureNamesTheFileAndTensor) {
  // A U^2-Net export: the Conv count does not fit an RRDBNet.
  const fs::path u2net = golden_dir("u2net_tiny") / "u2net_div8" / "u2net_div8_op17.onnx";
  expect_error([&] { load_rrdbnet(u2net); }, {"u2net_div8_op17.onnx", "Conv nodes"});
  // A U^2-Net state dict: the first RRDBNet tensor is missing.
  const fs::path u2net_st = golden_dir("u2net_tiny") / "u2net_div8" / "weights.safetensors";
  expect_error([&] { load_rrdbnet(u2net_st); }, {"weights.safetensors", "conv_first.weight"});
}

// Tiles of 200 input pixels (so the last one is smaller) over a 512 px image, each with the wrapper's 10 px
// of context, against one run over the whole image, with the tiny golden weights (random, output O(1)).
// The tiny network sees 18 input pixels around each pixel (1 + 15 + 1 convs at 1x, 4 at 2x and 4x), so a
// pixel at least 18 - 10 = 8 input pixels from a tile edge sees exactly what it sees untiled.
TEST(RealEsrgan, TilesEqualTheWholeImageAwayFromSeams) {
  torch::NoGradGuard no_grad;
  set_progress_quiet(true);
  RRDBNet net = load_rrdbnet(golden_dir("realesrgan_tiny") / "weights.safetensors");
  torch::manual_seed(3);
  const torch::Tensor image = torch::rand({1, 3, 512, 512});
  const torch::Tensor whole = upscale_tiled(*net, image, 0);
  const torch::Tensor tiled = upscale_tiled(*net, image, 200);
  ASSERT_EQ(tiled.sizes(), whole.sizes());

  // Distance in input pixels of each output row/column to the nearest seam (tile edges at 200 and 400).
  const torch::Tensor pos = torch::arange(512 * 4, torch::kLong).div(4, "floor");
  torch::Tensor dist = torch::full_like(pos, 1 << 20);
  for (int64_t edge : {200, 400}) dist = torch::minimum(dist, torch::where(pos < edge, edge - 1 - pos, pos - edge));
  const torch::Tensor far = (dist >= 8).view({-1, 1}) & (dist >= 8).view({1, -1});
  const torch::Tensor diff = (tiled - whole).abs().amax(1)[0];
  const double far_err = diff.masked_select(far).max().item<double>();
  const double near_err = diff.max().item<double>();
  const double range = whole.abs().max().item<double>();
  std::printf("  tiled vs whole: max abs %.3g away from seams, %.3g next to them (outputs up to %.2f)\n", far_err,
              near_err, range);
  EXPECT_LE(far_err, 1e-4);
  // Seam-free: next to a seam the tiles miss at most 8 pixels of context; the difference that leaves is far
  // below the output's own pixel-to-pixel variation, so no edge shows where tiles meet.
  const double neighbour_step = (whole.slice(3, 1) - whole.slice(3, 0, -1)).abs().mean().item<double>();
  std::printf("  mean step between neighbouring output pixels %.3g\n", neighbour_step);
  EXPECT_LE(near_err, 0.1 * neighbour_step);
}

TEST(RealEsrgan, RgbaKeepsAnUpscaledAlpha) {
  set_progress_quiet(true);
  UpscaleModel model;
  model.net = load_rrdbnet(golden_dir("realesrgan_tiny") / "weights.safetensors");
  torch::manual_seed(4);
  const torch::Tensor rgba = torch::randint(0, 256, {12, 16, 4}, torch::kUInt8);
  const torch::Tensor out = model.upscale(rgba);
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{48, 64, 4}));
  // The colours do not depend on the alpha.
  EXPECT_TRUE(torch::equal(out.slice(2, 0, 3), model.upscale(rgba.slice(2, 0, 3).contiguous())));
  // The alpha is the luma of the network's output for the alpha as a grey image.
  const torch::Tensor grey = model.upscale(rgba.slice(2, 3, 4).expand({12, 16, 3}).contiguous()).to(torch::kFloat);
  const torch::Tensor luma = 0.299 * grey.select(2, 0) + 0.587 * grey.select(2, 1) + 0.114 * grey.select(2, 2);
  EXPECT_LE((out.select(2, 3).to(torch::kFloat) - luma).abs().max().item<double>(), 1.0);
}

// A set of images is one loop of progress over all their tiles (an RGBA image's alpha runs a second
// time), so the time left is the set's; each image comes out as it does alone; a bad image anywhere
// stops the set before any runs.
TEST(RealEsrgan, ASetOfImagesIsOneLoopOverAllItsTiles) {
  struct Steps : ProgressListener {
    std::vector<std::pair<int, int>> seen;
    void on_event(const ProgressEvent& e) override {
      if (e.kind == ProgressEvent::Kind::Step && e.text == "upscale") seen.emplace_back(e.step, e.steps);
    }
  } steps;
  ProgressScope scope(&steps);
  UpscaleModel model;
  model.net = load_rrdbnet(golden_dir("realesrgan_tiny") / "weights.safetensors");
  model.tile = 8;
  torch::manual_seed(5);
  const torch::Tensor rgb = torch::randint(0, 256, {12, 16, 3}, torch::kUInt8);  // 2 x 2 tiles
  const torch::Tensor rgba = torch::randint(0, 256, {8, 8, 4}, torch::kUInt8);   // 1 tile, twice
  const std::vector<torch::Tensor> out = model.upscale({rgb, rgba});
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(steps.seen, (std::vector<std::pair<int, int>>{{1, 6}, {2, 6}, {3, 6}, {4, 6}, {5, 6}, {6, 6}}));
  EXPECT_TRUE(torch::equal(out[0], model.upscale(rgb)));
  EXPECT_TRUE(torch::equal(out[1], model.upscale(rgba)));

  steps.seen.clear();
  EXPECT_THROW(model.upscale({rgb, rgb.to(torch::kFloat)}), u3d::Error);
  EXPECT_TRUE(steps.seen.empty());
}

}  // namespace
}  // namespace u3d::nn
