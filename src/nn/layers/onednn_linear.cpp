#include "nn/layers/onednn_linear.h"

#include <oneapi/dnnl/dnnl.h>

#include <algorithm>
#include <vector>

#include "nn/runtime.h"

namespace u3d::nn {

bool onednn_linear_applies(const torch::Tensor& x, const torch::Tensor& weight) {
  return x.device().is_cpu() && weight.device().is_cpu() && x.scalar_type() == torch::kFloat &&
         weight.scalar_type() == torch::kFloat && x.dim() >= 1 && weight.dim() == 2 && cpu_runs_avx512_kernels();
}

torch::Tensor onednn_linear(const torch::Tensor& x, const torch::Tensor& weight, const torch::Tensor& bias) {
  const int64_t in = weight.size(1), out_features = weight.size(0);
  TORCH_CHECK(x.size(-1) == in, "linear: input has ", x.size(-1), " features, the weights expect ", in);
  TORCH_CHECK(!bias.defined() || (bias.scalar_type() == torch::kFloat && bias.numel() == out_features),
              "linear: the bias must be fp32 with one value per output");
  std::vector<int64_t> sizes = x.sizes().vec();
  sizes.back() = out_features;
  // The bias first, then the product added to it (beta = 1), as ATen's addmm does. A copy, never a
  // view: where every leading size is 1 the expanded bias is contiguous already, and `contiguous()`
  // would hand back the parameter itself to be written.
  torch::Tensor out = torch::empty(sizes, x.options());
  if (bias.defined()) out.copy_(bias.expand(sizes));
  const int64_t rows = x.numel() / std::max<int64_t>(in, 1);
  if (rows == 0 || out_features == 0) return out;
  if (in == 0) return bias.defined() ? out : out.zero_();
  const torch::Tensor a = x.contiguous(), w = weight.contiguous();
  // Row-major: out [rows, out_features] = a [rows, in] * w [out_features, in]^T.
  const dnnl_status_t status =
      dnnl_sgemm('N', 'T', rows, out_features, in, 1.0f, a.data_ptr<float>(), in, w.data_ptr<float>(), in,
                 bias.defined() ? 1.0f : 0.0f, out.data_ptr<float>(), out_features);
  TORCH_CHECK(status == dnnl_success, "linear: oneDNN's sgemm failed (status ", static_cast<int>(status), ")");
  return out;
}

}  // namespace u3d::nn
