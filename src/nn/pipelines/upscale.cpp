#include "nn/pipelines/upscale.h"

#include <string>

#include "core/error.h"
#include "core/progress.h"

namespace u3d::nn {
namespace {

// ITU-R BT.601 luma, OpenCV's RGB -> grey weights (the wrapper's cvtColor on the alpha output).
torch::Tensor luma(const torch::Tensor& rgb) {
  return 0.299 * rgb.select(1, 0) + 0.587 * rgb.select(1, 1) + 0.114 * rgb.select(1, 2);
}

torch::Tensor to_uint8(const torch::Tensor& unit) { return (unit * 255.0).round().to(torch::kUInt8); }

}  // namespace

int64_t upscale_tile_count(int64_t h, int64_t w, int64_t tile) {
  if (tile <= 0 || (h <= tile && w <= tile)) return 1;
  return ((h + tile - 1) / tile) * ((w + tile - 1) / tile);
}

torch::Tensor upscale_tiled(RRDBNetImpl& net, const torch::Tensor& x, int64_t tile,
                            const std::function<void()>& on_tile) {
  torch::NoGradGuard no_grad;
  const int64_t h = x.size(2), w = x.size(3);
  auto report = [&] {
    if (on_tile) on_tile();
  };
  if (upscale_tile_count(h, w, tile) == 1) {
    torch::Tensor out = net.forward(x);
    report();
    return out;
  }
  // The tiles reuse one set of buffers, freed when the image is done (before its output is converted).
  struct KeptWorkspace {
    RRDBNetImpl& net;
    explicit KeptWorkspace(RRDBNetImpl& n) : net(n) { net.keep_workspace(true); }
    ~KeptWorkspace() { net.keep_workspace(false); }
  } kept(net);
  const int64_t s = kUpscaleFactor;
  const int64_t tiles_y = (h + tile - 1) / tile, tiles_x = (w + tile - 1) / tile;
  torch::Tensor out = torch::empty({x.size(0), net.config.out_channels, h * s, w * s}, x.options());
  for (int64_t ty = 0; ty < tiles_y; ++ty) {
    for (int64_t tx = 0; tx < tiles_x; ++tx) {
      // The tile, and the tile with its context, in input pixels.
      const int64_t y0 = ty * tile, y1 = std::min(y0 + tile, h), x0 = tx * tile, x1 = std::min(x0 + tile, w);
      const int64_t py0 = std::max<int64_t>(y0 - kTilePad, 0), py1 = std::min(y1 + kTilePad, h);
      const int64_t px0 = std::max<int64_t>(x0 - kTilePad, 0), px1 = std::min(x1 + kTilePad, w);
      const torch::Tensor result = net.forward(x.slice(2, py0, py1).slice(3, px0, px1));
      out.slice(2, y0 * s, y1 * s)
          .slice(3, x0 * s, x1 * s)
          .copy_(result.slice(2, (y0 - py0) * s, (y1 - py0) * s).slice(3, (x0 - px0) * s, (x1 - px0) * s));
      report();
    }
  }
  return out;
}

std::unique_ptr<UpscaleModel> UpscaleModel::load(const std::filesystem::path& path, Precision precision) {
  check_precision_supported(precision, torch::kCPU);
  auto m = std::make_unique<UpscaleModel>();
  m->net = load_rrdbnet(path);
  require(m->net->config.in_channels == 3 && m->net->config.out_channels == 3,
          path.string() + ": an RRDBNet with " + std::to_string(m->net->config.in_channels) + " input and " +
              std::to_string(m->net->config.out_channels) + " output channels; the upscaler needs RGB to RGB");
  set_precision(*m->net, precision);
  return m;
}

std::vector<torch::Tensor> UpscaleModel::upscale(const std::vector<torch::Tensor>& images) {
  int total = 0;
  for (const torch::Tensor& image : images) {
    require(image.dim() == 3 && (image.size(2) == 3 || image.size(2) == 4) && image.scalar_type() == torch::kUInt8,
            "upscale: expected a uint8 RGB or RGBA image [H, W, 3|4]");
    total += static_cast<int>(upscale_tile_count(image.size(0), image.size(1), tile) * (image.size(2) == 4 ? 2 : 1));
  }
  torch::NoGradGuard no_grad;
  int done = 0;
  const auto on_tile = [&] { progress_step("upscale", ++done, total); };
  std::vector<torch::Tensor> out;
  for (const torch::Tensor& image : images) {
    const torch::Tensor unit = image.permute({2, 0, 1}).unsqueeze(0).to(torch::kFloat) / 255.0;
    const torch::Tensor rgb = upscale_tiled(*net, unit.slice(1, 0, 3), tile, on_tile).clamp(0.0, 1.0);
    if (image.size(2) == 3) {
      out.push_back(to_uint8(rgb[0].permute({1, 2, 0})).contiguous());
      continue;
    }
    const torch::Tensor alpha_in = unit.slice(1, 3, 4).expand({1, 3, image.size(0), image.size(1)});
    const torch::Tensor alpha = luma(upscale_tiled(*net, alpha_in, tile, on_tile).clamp(0.0, 1.0));
    out.push_back(to_uint8(torch::cat({rgb, alpha.unsqueeze(1)}, 1)[0].permute({1, 2, 0})).contiguous());
  }
  return out;
}

torch::Tensor UpscaleModel::upscale(const torch::Tensor& image) { return upscale(std::vector<torch::Tensor>{image})[0]; }

}  // namespace u3d::nn
