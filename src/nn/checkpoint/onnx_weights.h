#pragma once
// ONNX files as weight containers: a small reader of the protobuf wire format (no protobuf library) that
// takes a model's graph initializers (name, dims, FLOAT / FLOAT16 / DOUBLE / INT32 / INT64 from raw_data
// or the typed fields) and its nodes (op type, name, inputs, outputs). The networks themselves are
// written in libtorch; the graph is only read to find which initializer belongs to which layer.
//
// Exporters rename weights: torch.onnx folds an eval-mode BatchNorm into the Conv before it and stores
// the result under anonymous names (`onnx::Conv_1807`), keeping state-dict names only for the other
// convs. conv_weights_in_graph_order() therefore maps by position: the graph's Conv nodes, in graph
// (execution) order, to the model's Conv2d modules in registration order, which is forward order for
// every network read this way (RRDBNet, U^2-Net, ISNet).
//
// Truncated or corrupt files, external data, unsupported element types and data of the wrong size are
// u3d::Error naming the file and, where there is one, the tensor.
#include <filesystem>
#include <string>
#include <vector>

#include "nn/checkpoint/tensor_map.h"

namespace u3d::nn {

struct OnnxNode {
  std::string name;
  std::string op_type;
  std::vector<std::string> inputs;
  std::vector<std::string> outputs;
};

struct OnnxGraph {
  TensorMap initializers;       // as stored: fp16 stays fp16
  std::vector<OnnxNode> nodes;  // in graph order
};

OnnxGraph load_onnx(const std::filesystem::path& path);

// True for a path whose extension is .onnx (any case): such files are read with load_onnx.
bool is_onnx_path(const std::filesystem::path& path);

// "<module>.weight" and "<module>.bias" for the i-th Conv node of `graph` and the i-th name of
// `conv_modules`. An Error names `source` when the counts differ, when a Conv's weight or bias is not an
// initializer, or when an initializer carries the state-dict name of another module than the one its
// position gives (the file is of another architecture). Shapes are left to the strict loader.
// A graph with BatchNormalization nodes (an export that did not fold them) is refused with an Error.
TensorMap conv_weights_in_graph_order(const OnnxGraph& graph, const std::vector<std::string>& conv_modules,
                                      const std::string& source);

// The dotted names of `module`'s Conv2d submodules (nn/layers/layers.h) in registration order.
std::vector<std::string> conv_module_names(torch::nn::Module& module);

}  // namespace u3d::nn
