#include "nn/preprocess/clip_image_processor.h"

#include "core/error.h"
#include "nn/checkpoint/config_json.h"

namespace u3d::nn {

namespace {

// "size" / "crop_size" are an int in older configs and a dict in newer ones.
void read_size(const ConfigReader& r, const nlohmann::json& json, const std::string& key, int64_t& height, int64_t& width,
               int64_t* shortest_edge) {
  if (!r.has(key)) return;
  const auto& v = json.at(key);
  if (v.is_number_integer()) {
    if (shortest_edge) *shortest_edge = v.get<int64_t>();
    height = width = v.get<int64_t>();
    return;
  }
  if (v.is_object()) {
    ConfigReader sub(v, r.source() + " (" + key + ")");
    if (shortest_edge && sub.has("shortest_edge")) {
      *shortest_edge = sub.get_int("shortest_edge", 0);
      return;
    }
    if (!shortest_edge && sub.has("height") && sub.has("width")) {
      height = sub.get_int("height", 0);
      width = sub.get_int("width", 0);
      return;
    }
  }
  r.unsupported(key, shortest_edge ? "expected an integer or {\"shortest_edge\": n}"
                                   : "expected an integer or {\"height\": h, \"width\": w}");
}

}  // namespace

ClipImageProcessorConfig ClipImageProcessorConfig::from_json(const nlohmann::json& json, const std::string& source) {
  ConfigReader r(json, source);
  ClipImageProcessorConfig c;
  c.do_resize = r.get_bool("do_resize", c.do_resize);
  int64_t unused_h = 0, unused_w = 0;
  read_size(r, json, "size", unused_h, unused_w, &c.shortest_edge);
  c.resample = pil_filter_from_code(static_cast<int>(r.get_int("resample", 3)));
  c.do_center_crop = r.get_bool("do_center_crop", c.do_center_crop);
  read_size(r, json, "crop_size", c.crop_height, c.crop_width, nullptr);
  c.do_rescale = r.get_bool("do_rescale", c.do_rescale);
  c.rescale_factor = r.get_double("rescale_factor", c.rescale_factor);
  c.do_normalize = r.get_bool("do_normalize", c.do_normalize);
  for (auto [key, target] : {std::pair{"image_mean", &c.image_mean}, std::pair{"image_std", &c.image_std}}) {
    auto v = r.get_double_list(key, {(*target)[0], (*target)[1], (*target)[2]});
    if (v.size() != 3) r.unsupported(key, "expected 3 values");
    for (int i = 0; i < 3; ++i) (*target)[i] = static_cast<float>(v[i]);
  }
  if (c.shortest_edge <= 0 || c.crop_height <= 0 || c.crop_width <= 0)
    throw Error(source + ": image sizes must be positive");
  return c;
}

ClipImageProcessor::ClipImageProcessor(ClipImageProcessorConfig config) : config_(std::move(config)) {}

torch::Tensor ClipImageProcessor::resize_and_crop(const torch::Tensor& rgb) const {
  if (rgb.dim() != 3 || rgb.size(2) != 3 || rgb.scalar_type() != torch::kUInt8)
    throw Error("CLIP image processor: expected a uint8 RGB [H, W, 3] image, got " + c10::str(rgb.sizes()));
  torch::Tensor image = rgb;
  if (config_.do_resize) {
    const int64_t h = image.size(0), w = image.size(1);
    const int64_t s = config_.shortest_edge;
    // The long edge is int(s * long / short): truncated, as transformers computes it.
    const int64_t out_w = w <= h ? s : (s * w) / h;
    const int64_t out_h = w <= h ? (s * h) / w : s;
    image = pil_resize(image, out_w, out_h, config_.resample);
  }
  if (config_.do_center_crop) {
    const int64_t h = image.size(0), w = image.size(1);
    if (h < config_.crop_height || w < config_.crop_width)
      throw Error("CLIP image processor: the " + std::to_string(w) + "x" + std::to_string(h) +
                  " resized image is smaller than the " + std::to_string(config_.crop_width) + "x" +
                  std::to_string(config_.crop_height) + " crop");
    const int64_t top = (h - config_.crop_height) / 2, left = (w - config_.crop_width) / 2;
    image = image.narrow(0, top, config_.crop_height).narrow(1, left, config_.crop_width);
  }
  return image.contiguous();
}

torch::Tensor ClipImageProcessor::pixel_values(const torch::Tensor& rgb) const {
  torch::Tensor image = resize_and_crop(rgb);
  // transformers rescales in float64 and stores float32, then normalises in float32.
  torch::Tensor x = image.to(torch::kFloat64);
  if (config_.do_rescale) x = x * config_.rescale_factor;
  x = x.to(torch::kFloat32);
  if (config_.do_normalize) {
    auto mean = torch::tensor({config_.image_mean[0], config_.image_mean[1], config_.image_mean[2]});
    auto std = torch::tensor({config_.image_std[0], config_.image_std[1], config_.image_std[2]});
    x = (x - mean) / std;
  }
  return x.permute({2, 0, 1}).unsqueeze(0).contiguous();
}

}  // namespace u3d::nn
