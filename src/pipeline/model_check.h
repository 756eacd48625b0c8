#pragma once
// Checks of the model folder before any long work, for `generate` and `doctor`: each network a run needs
// has its files, and they parse and match the network's tensor names and shapes
// (nn/checkpoint/checkpoint_reader.h, a second or so per network, nothing allocated), or load for real.
#include <string>
#include <vector>

#include "nn/pipelines/unique3d_refine.h"
#include "pipeline/model_folder.h"

namespace u3d {

// The networks of the pipeline, in the order a run uses them.
enum class Network { kMatting, kUpscaler, kMultiView, kRefine, kNormals };
inline constexpr Network kAllNetworks[] = {Network::kMatting, Network::kUpscaler, Network::kMultiView,
                                           Network::kRefine, Network::kNormals};

// "background removal", "Real-ESRGAN x4", ...; and the commands and generate stages that use it.
std::string network_name(Network network);
std::string network_users(Network network);

enum class NetworkCheck {
  kShapes,  // files, configs, tensor names, shapes and dtypes, file sizes (truncation); the two ONNX-sized
            // networks (background removal, Real-ESRGAN, < 200 MB) are loaded for real
  kLoad,    // every network loaded for real (also checks the zip CRCs); the largest needs ~3.5 GB, briefly
};

struct NetworkCheckResult {
  Network network;
  std::string error;  // empty when the check passed
  double seconds = 0.0;
  bool ok() const { return error.empty(); }
};

// Checks `network` in `models` (fp32; a network that loads in fp32 loads in every precision).
NetworkCheckResult check_network(const ModelFolder& models, Network network, NetworkCheck how);
// Checks each of `networks` (kShapes) and throws the first failure as an Error.
void require_networks(const ModelFolder& models, const std::vector<Network>& networks);

// The refinement's three folders in `models`.
nn::RefineCheckpoints refine_checkpoints(const ModelFolder& models);

}  // namespace u3d
