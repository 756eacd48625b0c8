#include "nn/layers/onednn_common.h"

namespace u3d::nn {

dnnl::engine& onednn_cpu_engine() {
  static dnnl::engine engine(dnnl::engine::kind::cpu, 0);
  return engine;
}

void onednn_reorder(dnnl::memory source, dnnl::memory target) {
  dnnl::stream stream(onednn_cpu_engine());
  dnnl::reorder(source, target).execute(stream, source, target);
  stream.wait();
}

void onednn_execute(const dnnl::primitive& primitive, const dnnl::memory::desc& scratchpad,
                    std::unordered_map<int, dnnl::memory> args) {
  torch::Tensor scratch;
  if (const size_t bytes = scratchpad.get_size(); bytes > 0) {
    scratch = torch::empty({static_cast<int64_t>(bytes)}, torch::TensorOptions().dtype(torch::kUInt8));
    args.emplace(DNNL_ARG_SCRATCHPAD, dnnl::memory(scratchpad, onednn_cpu_engine(), scratch.data_ptr()));
  }
  dnnl::stream stream(onednn_cpu_engine());
  primitive.execute(stream, args);
  stream.wait();
}

WeightKey weight_key(const torch::Tensor& weight) {
  return {weight.data_ptr(), weight.is_inference() ? -1 : static_cast<int64_t>(weight._version())};
}

}  // namespace u3d::nn
