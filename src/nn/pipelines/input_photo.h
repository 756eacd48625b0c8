#pragma once
// Unique3D's preparation of the front photo before the multi-view model, as the official app does it
// (app/gradio_3dgen.py generate3dv2, app/custom_models/mvimg_prediction.py run_mvprediction,
// scripts/utils.py simple_preprocess): an image at most 512 px wide is first super-resolved x4; the
// background is removed (rembg's cut-out) when asked, and always when the image has no alpha or an alpha
// that is 255 everywhere, with the network's mask made solid inside the subject's outline
// (core/solid_matte.h; not in the official app, which feeds a pale subject half transparent to the
// multi-view model) unless the raw matte is asked for; the colours are put on white with the alpha kept;
// then simple_preprocess.
// There is no margin: the object touches the square's border along its larger extent
// (docs/conventions.md, section 2.4).
#include <torch/torch.h>

#include <functional>
#include <memory>

#include "nn/pipelines/matting.h"
#include "nn/pipelines/upscale.h"

namespace u3d::nn {

inline constexpr int64_t kSuperResolveMaxWidth = 512;  // generate3dv2: width <= 512 -> run_sr_fast
inline constexpr int64_t kInputPhotoMaxSide = 2048;    // simple_preprocess: thumbnail([2048, 2048])
inline constexpr int kForegroundAlpha = 60;            // simple_preprocess: bounding box of alpha > 60

// Pillow's thumbnail size: the largest size within max_side x max_side with the image's aspect ratio
// (its rounding rule), or the size itself when it already fits. {width, height}.
std::pair<int64_t, int64_t> thumbnail_size(int64_t width, int64_t height, int64_t max_side);

// RGB over white with the alpha kept (change_rgba_bg(image, "white")): PIL's alpha paste, rounded as
// PIL rounds. rgba: uint8 [H, W, 4].
torch::Tensor colours_on_white(const torch::Tensor& rgba);

// simple_preprocess on uint8 RGBA [H, W, 4]: shrink to fit 2048 px (PIL Lanczos at the thumbnail size;
// Pillow first box-reduces images over 4096 px by an integer factor, which is not reproduced), crop to
// the rows and columns holding an alpha > 60 (the official slice drops the last row and column of that
// box), pad to a centred square with (255, 255, 255, 0). An Error when no pixel has alpha > 60.
torch::Tensor simple_preprocess(const torch::Tensor& rgba);

// rembg's remove as the app calls it, on uint8 [H, W, 3|4]: the model's mask of the RGB channels, made
// solid (core/solid_matte.h) unless raw_matte, and rembg's cut-out of the whole image (premultiplied:
// nn/pipelines/matting.h). Returns uint8 RGBA [H, W, 4].
torch::Tensor matte_photo(const torch::Tensor& image, MattingModel& model, bool raw_matte);

// The networks the chain may need, got from these functions only when it does and let go right after
// (freed, unless the caller keeps them too: pipeline/network_cache.h).
struct InputPhotoModels {
  std::function<std::shared_ptr<UpscaleModel>()> upscaler;
  std::function<std::shared_ptr<MattingModel>()> matting;
};

// The whole chain on uint8 [H, W, 3|4]; returns the square uint8 RGBA the multi-view stage starts from.
torch::Tensor prepare_input_photo(const torch::Tensor& image, const InputPhotoModels& models, bool remove_background,
                                  bool raw_matte);

}  // namespace u3d::nn
