#include "pipeline/normal_stage.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/view_set.h"
#include "nn/pipelines/unique3d_normal.h"
#include "nn/pipelines/upscale.h"
#include "nn/preprocess/pil_resize.h"
#include "pipeline/image_stages.h"
#include "pipeline/model_check.h"
#include "pipeline/model_folder.h"

namespace u3d {
namespace {

constexpr int kBackgroundKeyThreshold = 80;  // remove_color: sum of |c - c(0,0)| over R, G, B, 8-bit

// The view on white at the model's size (geo_reconstruct resizes with Lanczos).
torch::Tensor model_input(const Image& view, int size) {
  const torch::Tensor rgb = nn::image_to_uint8_rgb(composite_over_white(view));
  if (rgb.size(0) == size && rgb.size(1) == size) return rgb;
  return nn::pil_resize(rgb, size, size, nn::PilFilter::Lanczos);
}

// A map in [0, 1] as the 8-bit image the official code works on.
torch::Tensor to_bytes(const torch::Tensor& unit) {
  return unit.mul(255).round().clamp(0, 255).to(torch::kUInt8).contiguous();
}

// A camera-space normal map of view v (float [H, W, 3] in [0, 1]) -> RGBA world-space map, the background
// keyed out by the colour of pixel (0, 0) as remove_color does, on the 8-bit image the official code keys.
Image key_and_rotate(const torch::Tensor& map, View v) {
  const torch::Tensor u8 = to_bytes(map);
  const int h = int(u8.size(0)), w = int(u8.size(1));
  const uint8_t* px = u8.data_ptr<uint8_t>();
  // World normal = R_y(90 deg * i) n_cam (docs/conventions.md, "Normal maps").
  const double angle = 0.5 * M_PI * int(v);
  const float c = float(std::cos(angle)), s = float(std::sin(angle));
  Image out(w, h, 4, 0.f);
  for (int i = 0; i < w * h; ++i) {
    const uint8_t* p = px + 3 * i;
    const int diff = std::abs(p[0] - px[0]) + std::abs(p[1] - px[1]) + std::abs(p[2] - px[2]);
    if (diff <= kBackgroundKeyThreshold) continue;
    const float x = 2.f * p[0] / 255.f - 1.f, y = 2.f * p[1] / 255.f - 1.f, z = 2.f * p[2] / 255.f - 1.f;
    const float world[3] = {c * x + s * z, y, -s * x + c * z};
    float* o = out.data.data() + 4 * size_t(i);
    for (int k = 0; k < 3; ++k) o[k] = std::clamp(0.5f * (world[k] + 1.f), 0.f, 1.f);
    o[3] = 1.f;
  }
  return out;
}

// The alpha channel of an image resampled to size x size (area/bilinear).
Image alpha_at(const Image& rgba, int size) {
  Image alpha(rgba.width, rgba.height, 1);
  for (size_t i = 0; i < rgba.pixel_count(); ++i) alpha.data[i] = rgba.data[4 * i + 3];
  return resize_image(alpha, size, size);
}

// A binary mask (foreground where alpha >= 0.5) eroded by one pixel with a 3x3 square, as erode_alpha.
Image eroded_mask(const Image& alpha) {
  const int w = alpha.width, h = alpha.height;
  Image out(w, h, 1, 0.f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      bool inside = true;
      for (int dy = -1; dy <= 1 && inside; ++dy)
        for (int dx = -1; dx <= 1 && inside; ++dx) {
          const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
          inside = is_foreground(alpha.at(xx, yy, 0));
        }
      out.at(x, y, 0) = inside ? 1.f : 0.f;
    }
  return out;
}

Image with_alpha(const Image& rgb, const Image& alpha) {
  Image out(rgb.width, rgb.height, 4);
  for (size_t i = 0; i < rgb.pixel_count(); ++i) {
    for (int c = 0; c < 3; ++c) out.data[4 * i + c] = rgb.data[i * rgb.channels + c];
    out.data[4 * i + 3] = alpha.data[i];
  }
  return out;
}

Image resized_square(const Image& image, int size) {
  return image.width == size && image.height == size ? image : resize_image(image, size, size);
}

}  // namespace

ViewSetImages run_normal_stage(const std::array<Image, 4>& views, const NetworkOptions& network,
                               const NormalOptions& options, NetworkStageSummary& summary, NetworkCache* cache) {
  const ModelFolder folder(network.models);
  summary.precision = resolve_precision(network);
  // The views are encoded before the UNets are read, so the CLIP encoder is freed by then
  // (nn/pipelines/unique3d_normal.h).
  StageTimer load_timer("loading the normal model's encoders");
  // (A cached model keeps its encoder and UNets loaded together.)
  std::shared_ptr<nn::NormalModel> model =
      cache ? cache->normals(folder, summary.precision)
            : nn::NormalModel::load_conditioning(folder.image_variations_for_normals(), folder.image2normal(),
                                                 summary.precision);
  summary.timings.push_back({"load encoders", load_timer.finish()});
  nn::NormalSettings settings;
  settings.size = options.size;
  settings.steps = options.steps;
  settings.guidance_scale = options.guidance_scale;
  settings.free_networks_as_done = !cache;
  StageTimer encode_timer("encoding the views");
  std::vector<torch::Tensor> inputs;
  for (const Image& view : views) inputs.push_back(model_input(view, options.size));
  const nn::ImageConditions conditions = model->encode(inputs, settings);
  summary.timings.push_back({"encode", encode_timer.finish()});
  StageTimer unet_timer("loading the normal model's UNets");
  model->load_unet();
  summary.timings.push_back({"load UNets", unet_timer.finish()});

  StageTimer timer("normal prediction");
  nn::SeededNoise noise(network.seed);
  const torch::Tensor maps = model->sample(conditions, settings, noise);
  model.reset();
  release_freed_memory();
  summary.timings.push_back({"normals", timer.finish()});
  std::vector<torch::Tensor> normal_maps;
  for (int64_t i = 0; i < maps.size(0); ++i) normal_maps.push_back(maps[i]);
  if (options.upscale) {
    StageTimer load_upscaler("loading the upscaler");
    std::shared_ptr<nn::UpscaleModel> upscaler = cache ? cache->upscaler(folder, summary.precision)
                                                       : nn::UpscaleModel::load(folder.upscaler(), summary.precision);
    summary.timings.push_back({"load upscaler", load_upscaler.finish()});
    StageTimer upscale_timer("upscaling the normal maps x4");
    std::vector<torch::Tensor> bytes;
    for (const torch::Tensor& map : normal_maps) bytes.push_back(to_bytes(map));
    std::vector<torch::Tensor> upscaled = upscaler->upscale(bytes);
    for (size_t i = 0; i < normal_maps.size(); ++i) normal_maps[i] = upscaled[i].to(torch::kFloat).div(255);
    summary.timings.push_back({"upscale normals", upscale_timer.finish()});
  }
  summary.peak_memory_mib = peak_memory_mib();

  ViewSetImages out;
  int rgb_size = 0;
  for (const Image& view : views) rgb_size = std::max(rgb_size, view.width);
  for (View v : kAllViews) {
    const size_t i = size_t(v);
    out.normals[i] = key_and_rotate(normal_maps[i], v);
    if (v != View::Front || views[i].channels != 4) {  // (the front view takes the photo's alpha below)
      bool any = false;
      for (size_t p = 0; p < out.normals[i].pixel_count() && !any; ++p) any = out.normals[i].data[4 * p + 3] > 0.f;
      require(any, std::string("normal prediction: the ") + view_name(v) +
                       " normal map is one colour, so keying out its background (the colour of its corner, as the "
                       "official code does) leaves no object; the normal model's weights may not be the official ones");
    }
    const Image rgb = resized_square(views[i], rgb_size);
    if (v == View::Front && views[i].channels == 4) {
      out.rgb[i] = rgb;
      // The front normal map takes the photo's alpha; pixels inside it that the colour key dropped get the
      // normal facing the camera.
      Image& n = out.normals[i];
      const Image alpha = alpha_at(views[i], n.width);
      for (size_t p = 0; p < n.pixel_count(); ++p) {
        float* o = n.data.data() + 4 * p;
        if (o[3] == 0.f && is_foreground(alpha.data[p])) {
          o[0] = o[1] = 0.5f;
          o[2] = 1.f;
        }
        o[3] = alpha.data[p];
      }
    } else {
      out.rgb[i] = with_alpha(rgb, eroded_mask(alpha_at(out.normals[i], rgb_size)));
    }
    // As the view set's 8-bit files hold them (the official code hands 8-bit images on too), so that a
    // run resumed from the kept view set, or `reconstruct` of the folder `normals` writes, starts from
    // the very images this run goes on with.
    out.rgb[i] = quantized_8bit(out.rgb[i]);
    out.normals[i] = quantized_8bit(out.normals[i]);
  }
  return out;
}

NetworkStageSummary predict_view_normals(const NormalRequest& request, ProgressListener* listener) {
  std::optional<ProgressScope> scope;
  if (listener) scope.emplace(listener);
  require(request.options.steps >= 1, "normal steps must be at least 1");
  require(request.options.size >= 8 && request.options.size % 8 == 0, "normal-map size must be a multiple of 8");
  std::array<Image, 4> views;
  std::optional<Image> photo;  // `front` before its preparation
  for (View v : kAllViews) {
    const bool photo_front = v == View::Front && request.front;
    const std::filesystem::path path = photo_front ? *request.front : request.views_dir / view_file_name(v, false);
    if (photo_front && !request.prepared_front) {
      photo = load_photo(path);
      continue;
    }
    Image image = load_image(path);
    require(image.width == image.height, path.string() + ": views must be square (it is " +
                                             std::to_string(image.width) + "x" + std::to_string(image.height) +
                                             (photo_front ? "; without --prepared the photo is prepared first)" : ")"));
    require(image.channels >= 3, path.string() + ": views must be colour images");
    views[size_t(v)] = std::move(image);
  }

  NetworkStageSummary summary;
  if (photo) {
    require_networks(ModelFolder(request.network.models), {Network::kNormals});  // before the preparation runs
    views[size_t(View::Front)] = run_prepare_stage(*photo, request.network, request.raw_matte, summary);
  }
  const ViewSetImages result = run_normal_stage(views, request.network, request.options, summary);
  StageTimer write_timer("writing the view set");
  std::array<std::string, 4> rgb_names, normal_names;
  for (View v : kAllViews) {
    rgb_names[size_t(v)] = view_file_name(v, false);
    normal_names[size_t(v)] = view_file_name(v, true);
  }
  write_folder_atomically(request.output_dir, [&](const std::filesystem::path& folder) {
    for (View v : kAllViews) {
      save_image(result.rgb[size_t(v)], folder / rgb_names[size_t(v)]);
      save_image(result.normals[size_t(v)], folder / normal_names[size_t(v)]);
    }
  });
  for (View v : kAllViews) {
    summary.written.push_back(request.output_dir / rgb_names[size_t(v)]);
    summary.written.push_back(request.output_dir / normal_names[size_t(v)]);
  }
  summary.timings.push_back({"write", write_timer.finish()});
  return summary;
}

}  // namespace u3d
