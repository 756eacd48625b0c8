#include "pipeline/model_check.h"

#include <chrono>

#include "core/error.h"
#include "nn/pipelines/matting.h"
#include "nn/pipelines/unique3d_multiview.h"
#include "nn/pipelines/unique3d_normal.h"
#include "nn/pipelines/upscale.h"

namespace u3d {

std::string network_name(Network network) {
  switch (network) {
    case Network::kMatting: return "background removal";
    case Network::kUpscaler: return "Real-ESRGAN x4";
    case Network::kMultiView: return "multi-view model (img2mvimg)";
    case Network::kRefine: return "refinement (SD 1.5, tile ControlNet, IP-Adapter)";
    case Network::kNormals: return "normal model (image2normal)";
  }
  return {};
}

std::string network_users(Network network) {
  switch (network) {
    case Network::kMatting: return "generate (photos without transparency), matte";
    case Network::kUpscaler: return "generate, upscale, normals";
    case Network::kMultiView: return "generate, multiview";
    case Network::kRefine: return "generate (unless --no-refine), refine";
    case Network::kNormals: return "generate, normals";
  }
  return {};
}

nn::RefineCheckpoints refine_checkpoints(const ModelFolder& models) {
  return {models.stable_diffusion(), models.root(), models.ip_adapter()};
}

NetworkCheckResult check_network(const ModelFolder& models, Network network, NetworkCheck how) {
  const nn::CheckpointReader reader(how == NetworkCheck::kLoad ? nn::CheckpointReader::Mode::kLoad
                                                                : nn::CheckpointReader::Mode::kCheck);
  const nn::Precision fp32 = nn::Precision::kFp32;
  NetworkCheckResult result{network, {}, 0.0};
  const auto start = std::chrono::steady_clock::now();
  try {
    switch (network) {
      case Network::kMatting: nn::MattingModel::load(models.matting(), fp32); break;
      case Network::kUpscaler: nn::UpscaleModel::load(models.upscaler(), fp32); break;
      case Network::kMultiView: nn::MultiViewModel::load(models.img2mvimg(), fp32, reader); break;
      case Network::kRefine:
        nn::RefineEncoders::load(refine_checkpoints(models), fp32, reader);
        nn::RefineModel::load(refine_checkpoints(models), fp32, reader);
        break;
      case Network::kNormals:
        nn::NormalModel::load(models.image_variations_for_normals(), models.image2normal(), fp32, reader);
        break;
    }
  } catch (const Error& e) {
    result.error = e.what();
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void require_networks(const ModelFolder& models, const std::vector<Network>& networks) {
  for (Network network : networks) {
    const NetworkCheckResult result = check_network(models, network, NetworkCheck::kShapes);
    if (!result.ok()) throw Error(result.error);
  }
}

}  // namespace u3d
