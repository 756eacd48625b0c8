#pragma once
// Real-ESRGAN x4 super-resolution of whole images, as Unique3D's upscaler wrapper runs it
// (scripts/upsampler.py, RealESRGANer.enhance; scripts/refine_lr_to_sr.py, run_sr_fast): values / 255,
// the network, clamp to [0, 1], x 255, rounded to uint8. An RGBA image keeps an upscaled alpha: the alpha
// goes through the network a second time as a grey RGB image and comes back as the luma
// 0.299 R + 0.587 G + 0.114 B of that output. Large images run in tiles with the wrapper's scheme: tiles
// of `tile` input pixels, each run with `kTilePad` pixels of context on every side that exists, the
// context cut off again, no blending (Unique3D itself runs untiled, which needs 8 GB of GPU memory at
// 512 -> 2048). Channel order: the network gets R, G, B, the order it was trained in; Unique3D's wrapper
// expects OpenCV's B, G, R but is handed PIL's RGB, so there the network sees the channels swapped
// (docs/networks.md).
#include <torch/torch.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

#include "nn/models/rrdbnet.h"
#include "nn/precision.h"

namespace u3d::nn {

inline constexpr int64_t kUpscaleFactor = 4;
inline constexpr int64_t kTilePad = 10;       // RealESRGANer's tile_pad default, also run_sr_fast's
inline constexpr int64_t kDefaultTile = 256;  // input pixels; 512 -> 2048 in 4 tiles, about 1 GB in fp32

// How many runs of the network upscale_tiled makes over an h x w image.
int64_t upscale_tile_count(int64_t h, int64_t w, int64_t tile);

// Runs `net` over x [N, C, H, W] in tiles of `tile` x `tile` input pixels with kTilePad pixels of context
// (tile <= 0, or an image no larger than one tile: one run over the whole image), calling `on_tile` after
// each run. Returns [N, out, 4H, 4W] in x's dtype, raw.
torch::Tensor upscale_tiled(RRDBNetImpl& net, const torch::Tensor& x, int64_t tile,
                            const std::function<void()>& on_tile = {});

class UpscaleModel {
 public:
  // load_rrdbnet(path) (ONNX or basicsr checkpoint), converted to `precision` (check_precision_supported).
  static std::unique_ptr<UpscaleModel> load(const std::filesystem::path& path, Precision precision);

  // Each image: uint8 [H, W, 3] RGB or [H, W, 4] RGBA (all checked before any runs). Returns uint8
  // [4H, 4W, same channels] for each. Progress: one "upscale" loop over every tile of every image.
  std::vector<torch::Tensor> upscale(const std::vector<torch::Tensor>& images);
  torch::Tensor upscale(const torch::Tensor& image);

  RRDBNet net{nullptr};
  int64_t tile = kDefaultTile;
};

}  // namespace u3d::nn
