// libFuzzer target: ONNX files as weight containers (nn/checkpoint/onnx_weights), the form in which the
// matting and upscaling networks' weights are published. load_onnx reads the protobuf wire format with
// its own reader; the graph it returns is then mapped to Conv modules by position, as the networks do,
// with one made-up module name per Conv node (the mapping refuses names that contradict the file's).
// onnx_weights.cpp is compiled into the target, which links libtorch for the tensors
// (fuzz/CMakeLists.txt).
#include <string>
#include <vector>

#include "fuzz_common.h"
#include "nn/checkpoint/onnx_weights.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto path = u3d::fuzz::write_scratch_file("model.onnx", data, size);
  u3d::fuzz::expect_clean([&] {
    const u3d::nn::OnnxGraph graph = u3d::nn::load_onnx(path);
    std::vector<std::string> modules;
    for (const auto& node : graph.nodes)
      if (node.op_type == "Conv") modules.push_back("conv" + std::to_string(modules.size()));
    u3d::nn::conv_weights_in_graph_order(graph, modules, "fuzz.onnx");
  });
  return 0;
}
