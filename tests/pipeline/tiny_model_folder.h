#pragma once
// A --models folder in the official layout (pipeline/model_folder.h) made of the tiny golden models of
// tests/data/nn (every stage: multi-view, refinement, Real-ESRGAN, normals, background removal), and a
// small object photo, and the sizes they run at, for tests of the network stages and commands.
#include <filesystem>

#include "core/image.h"
#include "nn/golden.h"
#include "pipeline/generate.h"
#include "nn/refine_folders.h"

namespace u3d::testing {

inline void write_tiny_model_folder(const std::filesystem::path& models) {
  using nn::test::copy_into_folder;
  using nn::test::golden_dir;
  using nn::test::write_image_variations_folder;
  write_image_variations_folder(models / "img2mvimg", /*unet_weights=*/false);
  copy_into_folder(models, {{golden_dir("unet_mv") / "weights.pth", "img2mvimg/unet_state_dict.pth"}});
  write_image_variations_folder(models / "sd-image-variations-diffusers", /*unet_weights=*/true);
  copy_into_folder(models, {{golden_dir("unet_ref") / "weights.pth", "image2normal/unet_state_dict.pth"},
                            {golden_dir("realesrgan_tiny") / "rrdbnet_tiny_op17.onnx", "realesrgan-x4.onnx"},
                            {golden_dir("u2net_tiny") / "u2net_div8" / "u2net_div8_op17.onnx", "u2net.onnx"}});
  nn::test::write_tiny_refine_folders({models / "stable-diffusion-v1-5", models, models / "IP-Adapter"});
}

// The small sizes and few steps the tiny networks run at in the tests (2 denoising steps each).
inline void use_tiny_sizes(GenerateRequest& r) {
  r.refine_options.size = 64;
  r.refine_options.steps = 10;  // strength 0.2: the last 2 run
  r.multiview.size = 32;
  r.multiview.steps = 2;
  r.normals.size = 32;
  r.normals.steps = 2;
  r.reconstruct.coarse.steps = 5;
  r.reconstruct.refine.steps = 5;
  // The tiny random networks draw noise, whose masks disagree: the silhouette fit would run its
  // 256^3 grid on every reconstruction here (it has its own tests in tests/isomer).
  r.reconstruct.silhouette_fit.enabled = false;
  // A coarse mesh and texture: the reconstruction's quality has its own tests (tests/isomer, tests/cli).
  r.reconstruct.faces = 500;
  r.reconstruct.texture.atlas.texture_size = 128;
}

// An object photo: a disk 60 px across with a vertical colour ramp, centred on a transparent 520 px
// square. Wider than 512 px, so the preparation does not super-resolve it (input_photo.h), and the
// prepared front image is the disk's 60 px crop, x4 in the upscale stage: the tiny runs stay small.
inline constexpr int kDiskPhotoSide = 520;
inline constexpr int kDiskCentreX = 260, kDiskCentreY = 262;
inline void write_disk_photo(const std::filesystem::path& path) {
  Image photo(kDiskPhotoSide, kDiskPhotoSide, 4, 0.f);
  for (int y = 0; y < photo.height; ++y)
    for (int x = 0; x < photo.width; ++x)
      if ((x - kDiskCentreX) * (x - kDiskCentreX) + (y - kDiskCentreY) * (y - kDiskCentreY) < 30 * 30) {
        float* p = photo.pixel(x, y);
        p[0] = 0.8f, p[1] = 0.2f + 0.004f * (y - kDiskCentreY + 50), p[2] = 0.1f, p[3] = 1.f;
      }
  save_image(photo, path);
}

}  // namespace u3d::testing
