#!/usr/bin/python3
# Writes seeded.safetensors: the official image-to-four-views pipeline on this case's tiny models, run as a
# user runs it, with a seeded torch.Generator instead of injected noise (the golden pipeline trace injects
# every draw). tests/nn/test_unique3d_multiview.cpp reproduces it with nn::SeededNoise, which checks that
# the noise is drawn from the same stream in the same order and shapes as diffusers draws it.
#
# Needs the Python reference of ../../../../../shared/golden/generators (Debian's python3-torch, then
# MIRROR=... setup_env.sh); it imports their gen_golden.py and builds the pipeline as its unet_mv case does,
# with the weights of this folder and of ../vae, ../clip_vision and ../unet_base. Run from this folder:
#   GOLDEN_GENERATORS=/path/to/shared/golden/generators /usr/bin/python3 make_seeded.py
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
os.environ["GOLDEN_OUT"] = os.path.dirname(HERE)  # the tiny vae, clip_vision and unet_base are read from here
sys.path.insert(0, os.environ["GOLDEN_GENERATORS"])

import gen_golden as G  # noqa: E402
import common as C  # noqa: E402
import torch  # noqa: E402

SEEDS = (7, 2024)  # one output per seed

G.build_tiny_sdiv()
_, _, cu, _ = G.make_configurable("image2mvimage.yaml")
unet = cu.unet
unet.load_state_dict(C.read_safetensors(os.path.join(HERE, "weights.safetensors")))
from custum_3d_diffusion.custum_pipeline.unifield_pipeline_img2mvimg import StableDiffusionImage2MVCustomPipeline  # noqa: E402

vae, enc, fe, sch = G.make_pipeline_modules()
pipe = StableDiffusionImage2MVCustomPipeline(
    vae=vae, image_encoder=enc, unet=unet, scheduler=sch, safety_checker=None, feature_extractor=fe,
    requires_safety_checker=False, latents_offset=None, noisy_cond_latents=False, condition_offset=True)
pipe.set_progress_bar_config(disable=True)
outputs = {}
for seed in SEEDS:
    runs = []
    for _ in range(2):  # twice: the reference must be deterministic
        res = pipe(image=G.test_image(), height=32, width=32, height_cond=32, width_cond=32, num_inference_steps=2,
                   guidance_scale=1.5, num_images_per_prompt=4, generator=torch.Generator().manual_seed(seed),
                   output_type="np")
        runs.append(torch.from_numpy(res.images))
    assert torch.equal(runs[0], runs[1])
    outputs[f"seed{seed}.images"] = runs[0]
C.write_safetensors(os.path.join(HERE, "seeded.safetensors"), outputs,
                    metadata={"seeds": ",".join(str(s) for s in SEEDS), "libraries": str(C.library_versions())})
print("wrote", os.path.join(HERE, "seeded.safetensors"), {k: tuple(v.shape) for k, v in outputs.items()})
