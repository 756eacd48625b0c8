#!/usr/bin/python3
# Writes inputs.safetensors and outputs.safetensors of this folder: Unique3D's refinement call (refine_rgb in
# scripts/multiview_inference.py -> refine_lr_with_sd in scripts/refine_lr_to_sr.py) on the tiny refinement
# models, run by diffusers 0.27.2's StableDiffusionControlNetImg2ImgPipeline built as Unique3D's
# load_common_sd15_pipe builds it (scripts/sd_model_zoo.py: ControlNet from ckpt/controlnet-tile, IP-Adapter
# ip-adapter_sd15 at scale 1.0, EulerAncestral from the base model's scheduler config), with every Gaussian
# draw injected (inputs noise.0..3) and the intermediate latents recorded. tests/nn/test_unique3d_refine.cpp
# (RefineTrace) reproduces it with nn::RefineEncoders / nn::RefineModel.
#
# The tiny models are the folders the C++ tests write (tests/nn/refine_folders.h, write_tiny_refine_folders):
# the golden UNet, VAE, CLIP image encoder and IP-Adapter plus a text encoder and ControlNet seeded in C++.
# The project's make_tiny_models tool (tests/python/make_tiny_models.cpp) writes them; this script reads them
# from its MODELS_DIR and records a fingerprint of the seeded ones (weights.* in outputs) that the C++ test
# checks against the folders it writes, so a change to the seeding shows as such and not as a wrong trace.
#
# Needs the Python reference of /work/shared/golden/generators (Debian's python3-torch 1.13, then
# MIRROR=... setup_env.sh: diffusers v0.27.2, transformers 4.45.0.dev0, huggingface_hub v0.24.6). Run:
#   ninja -C build make_tiny_models && build/tests/make_tiny_models /tmp/tiny /tmp/tiny_photo.png
#   GOLDEN_GENERATORS=/work/shared/golden/generators /usr/bin/python3 make_trace.py /tmp/tiny
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.environ["GOLDEN_GENERATORS"])
os.environ.setdefault("HF_HUB_OFFLINE", "1")

import common as C  # noqa: E402  (sys.path for the reference libraries; torch 1.13's baddbmm(beta=0) fix)
import numpy as np  # noqa: E402
import torch  # noqa: E402
from PIL import Image  # noqa: E402

torch.set_num_threads(2)

# The files the C++ tests write carry no safetensors metadata; transformers' from_pretrained wants the
# {"format": "pt"} that the Hugging Face files carry.
import safetensors  # noqa: E402  (the pure-Python shim of the generators)
_metadata = safetensors.safe_open.metadata
safetensors.safe_open.metadata = lambda self: _metadata(self) or {"format": "pt"}

VIEW = 24     # each of the four views; the grid is 48 px
SIZE = 64     # output_size of the call (official: 1024); the grid is resized up to it
STEPS = 10    # num_inference_steps (official: 50); strength 0.2 runs the last int(10 * 0.2) = 2
STRENGTH = 0.2
GUIDANCE = 5.0
PROMPT = "4views, multiview"
# scripts/utils.NEG_PROMPT: passed as `neg_prompt=`, which the pipeline swallows in **kwargs (see the case).
NEG_PROMPT = ("sketch, sculpture, hand drawing, outline, single color, NSFW, lowres, bad anatomy,bad hands, "
              "text, error, missing fingers, yellow sleeves, extra digit, fewer digits, cropped, worst quality, "
              "low quality, normal quality, jpeg artifacts, signature, watermark, username, blurry,(worst quality:1.4),"
              "(low quality:1.4)")


def bytes_to_unicode():
    bs = list(range(ord("!"), ord("~") + 1)) + list(range(ord("¡"), ord("¬") + 1)) + list(range(ord("®"), ord("ÿ") + 1))
    cs = bs[:]
    n = 0
    for b in range(256):
        if b not in bs:
            bs.append(b)
            cs.append(256 + n)
            n += 1
    return [chr(c) for c in cs]


def make_tokenizer(merges_path, work):
    """openai/clip-vit-large-patch14's slow CLIPTokenizer: its vocab.json is built from the merges as CLIP builds it."""
    from transformers import CLIPTokenizer
    import transformers.tokenization_utils_base as tub
    # Without the Rust `tokenizers` package transformers falls back on its own AddedToken, a dataclass with eq=True
    # and so no __hash__, and without the __setstate__ that the Rust one has; the slow tokenizer's constructor
    # needs both.
    if tub.AddedToken.__hash__ is None:
        tub.AddedToken.__hash__ = lambda self: hash(self.content)
    if not hasattr(tub.AddedToken, "__setstate__"):
        tub.AddedToken.__setstate__ = lambda self, state: self.__dict__.update(state)
    merges = open(merges_path, encoding="utf-8").read().strip().split("\n")[1:49152 - 256 - 2 + 1]
    syms = bytes_to_unicode()
    syms = syms + [s + "</w>" for s in syms] + ["".join(m.split()) for m in merges] + ["<|startoftext|>", "<|endoftext|>"]
    assert len(syms) == 49408
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "vocab.json"), "w", encoding="utf-8") as f:
        json.dump({s: i for i, s in enumerate(syms)}, f)
    return CLIPTokenizer(os.path.join(work, "vocab.json"), merges_path, model_max_length=77)


def build_pipe(models):
    """scripts/sd_model_zoo.load_common_sd15_pipe(ip_adapter=True, plus_model=False, controlnet=ckpt/controlnet-tile,
    pipeline_class=StableDiffusionControlNetImg2ImgPipeline), in fp32 on the CPU."""
    from diffusers import (AutoencoderKL, ControlNetModel, EulerAncestralDiscreteScheduler,
                           StableDiffusionControlNetImg2ImgPipeline, UNet2DConditionModel, PNDMScheduler)
    from transformers import CLIPImageProcessor, CLIPTextModel
    base = os.path.join(models, "stable-diffusion-v1-5")
    pipe = StableDiffusionControlNetImg2ImgPipeline(
        vae=AutoencoderKL.from_pretrained(base, subfolder="vae"),
        text_encoder=CLIPTextModel.from_pretrained(os.path.join(base, "text_encoder"), attn_implementation="eager"),
        tokenizer=make_tokenizer(os.path.join(base, "tokenizer", "merges.txt"), os.path.join("/tmp", "refine_trace_tok")),
        unet=UNet2DConditionModel.from_pretrained(base, subfolder="unet"),
        controlnet=ControlNetModel.from_pretrained(os.path.join(models, "controlnet-tile")),
        scheduler=PNDMScheduler.from_pretrained(base, subfolder="scheduler"),
        safety_checker=None, feature_extractor=CLIPImageProcessor.from_pretrained(base, subfolder="feature_extractor"),
        image_encoder=None, requires_safety_checker=False)
    pipe.load_ip_adapter(os.path.join(models, "IP-Adapter"), subfolder="models", weight_name="ip-adapter_sd15.safetensors")
    pipe.set_ip_adapter_scale(1.0)
    pipe.scheduler = EulerAncestralDiscreteScheduler.from_config(pipe.scheduler.config)
    pipe.set_progress_bar_config(disable=True)
    for m in (pipe.unet, pipe.vae, pipe.text_encoder, pipe.controlnet, pipe.image_encoder):
        m.eval()
    return pipe


def run(pipe, inputs, dtype=torch.float32):
    """One call as refine_lr_with_sd makes it, with the noise injected and the trace recorded."""
    import diffusers.models.autoencoders.vae as vae_mod
    import diffusers.pipelines.controlnet.pipeline_controlnet_img2img as pipe_mod
    import diffusers.schedulers.scheduling_euler_ancestral_discrete as ea_mod
    noises = [inputs[f"noise.{i}"] for i in range(4)]
    drawn = []

    def fake_randn(shape, generator=None, device=None, dtype=None, layout=None):
        n = noises[len(drawn)]
        assert tuple(n.shape) == tuple(shape), (n.shape, shape)
        drawn.append(tuple(shape))
        return n.to(dtype=dtype)

    rec = {}
    originals = []

    def patch(obj, name, wrapper):
        orig = getattr(obj, name)
        originals.append((obj, name, orig))
        setattr(obj, name, wrapper(orig))

    def w_encode_prompt(orig):
        def f(*a, **kw):
            pos, neg = orig(*a, **kw)
            rec["prompt_embeds"] = torch.cat([neg, pos]).clone()
            return pos, neg
        return f

    def w_ip(orig):
        def f(*a, **kw):
            out = orig(*a, **kw)
            rec["image_embeds"] = out[0].reshape(out[0].shape[0], -1).clone()  # [2, 1, E] -> [2, E]
            return out
        return f

    def w_control(orig):
        def f(*a, **kw):
            out = orig(*a, **kw)
            rec["control_image"] = out[:1].clone()  # the pipeline doubles it for guidance
            return out
        return f

    def w_preprocess(orig):
        def f(*a, **kw):
            out = orig(*a, **kw)
            rec.setdefault("init_image", out.clone())  # the first call: the img2img image
            return out
        return f

    def w_add_noise(orig):
        def f(original_samples, noise, timesteps):
            rec["init_latents"] = original_samples.clone()
            out = orig(original_samples, noise, timesteps)
            rec["latents.0"] = out.clone()
            return out
        return f

    steps = []

    def w_step(orig):
        def f(model_output, timestep, sample, *a, **kw):
            out = orig(model_output, timestep, sample, *a, **kw)
            i = len(steps)
            steps.append(timestep.clone())
            rec[f"noise_pred.{i}"] = model_output.clone()
            rec[f"latents.{i + 1}"] = (out[0] if isinstance(out, tuple) else out.prev_sample).clone()
            return out
        return f

    patch(vae_mod, "randn_tensor", lambda o: fake_randn)
    patch(pipe_mod, "randn_tensor", lambda o: fake_randn)
    patch(ea_mod, "randn_tensor", lambda o: fake_randn)
    patch(pipe, "encode_prompt", w_encode_prompt)
    patch(pipe, "prepare_ip_adapter_image_embeds", w_ip)
    patch(pipe, "prepare_control_image", w_control)
    patch(pipe.image_processor, "preprocess", w_preprocess)
    patch(pipe.scheduler, "add_noise", w_add_noise)
    patch(pipe.scheduler, "step", w_step)
    try:
        views = [Image.fromarray(v.numpy()) for v in inputs["views"]]
        # app/utils.make_image_grid(rgb_pils, rows=2): views 0 1 on top, 2 3 below.
        grid = Image.new("RGB", (2 * VIEW, 2 * VIEW))
        for i, v in enumerate(views):
            grid.paste(v, ((i % 2) * VIEW, (i // 2) * VIEW))
        control = grid.resize((SIZE, SIZE))  # refine_rgb: rgb_pil.resize((1024, 1024)), PIL's default filter
        front = Image.fromarray(inputs["front"].numpy())  # rgba_to_rgb(front_pil): already RGB on white
        # refine_lr_with_sd's call, with num_inference_steps STEPS instead of 50 and the output size SIZE.
        with torch.no_grad():
            images = pipe(
                image=[grid], ip_adapter_image=[front], prompt=[PROMPT], neg_prompt=[NEG_PROMPT],
                num_inference_steps=STEPS, strength=STRENGTH, height=SIZE, width=SIZE, control_image=[control],
                guidance_scale=GUIDANCE, controlnet_conditioning_scale=1.0, generator=torch.manual_seed(233),
                output_type="np").images
    finally:
        for obj, name, orig in reversed(originals):
            setattr(obj, name, orig)
    assert drawn == [(1, 4, SIZE // 2, SIZE // 2)] * 4, drawn  # VAE sample, img2img noise, one per step
    rec["timesteps"] = torch.stack(steps)
    rec["images"] = torch.from_numpy(images[0])  # [SIZE, SIZE, 3], (x / 2 + 0.5) clamped to [0, 1]
    rec["grid"] = torch.from_numpy(np.array(grid))
    return rec


def fingerprint(model, prefix, out):
    """The sum and the sum of squares of each parameter (float64), in sorted key order."""
    sd = model.state_dict()
    keys = sorted(sd)
    out[prefix + ".sum"] = torch.tensor([sd[k].double().sum().item() for k in keys], dtype=torch.float64)
    out[prefix + ".sumsq"] = torch.tensor([sd[k].double().pow(2).sum().item() for k in keys], dtype=torch.float64)
    return keys


def main():
    models = sys.argv[1]
    g = torch.Generator().manual_seed(4343)
    inputs = {"views": torch.randint(0, 256, (4, VIEW, VIEW, 3), generator=g, dtype=torch.uint8),
              "front": torch.randint(0, 256, (40, 30, 3), generator=g, dtype=torch.uint8)}
    # Smooth the views a little (a coarse random image upsampled), so the resizes see image-like content.
    coarse = torch.randint(0, 256, (4, 3, 6, 6), generator=g).float()
    smooth = torch.nn.functional.interpolate(coarse, size=(VIEW, VIEW), mode="bilinear", align_corners=False)
    inputs["views"] = ((smooth.permute(0, 2, 3, 1) + inputs["views"].float()) / 2).round().clamp(0, 255).to(torch.uint8)
    for i in range(4):
        inputs[f"noise.{i}"] = C.seeded((1, 4, SIZE // 2, SIZE // 2), 4300 + i)

    pipe = build_pipe(models)
    ref = run(pipe, inputs)
    rerun = run(pipe, inputs)
    for k in ref:
        assert torch.equal(ref[k], rerun[k]), k  # the reference is deterministic
    outputs = dict(ref)
    fp_keys = {"text_encoder": fingerprint(pipe.text_encoder, "weights.text_encoder", outputs),
               "controlnet": fingerprint(pipe.controlnet, "weights.controlnet", outputs)}

    # Rounding noise: the same call in float64 (every weight and the noise), for the tolerances in case.md.
    pipe64 = pipe.to(torch.float64)
    inputs64 = {k: (v.double() if v.is_floating_point() else v) for k, v in inputs.items()}
    torch.set_default_dtype(torch.float64)  # transformers' causal mask is made in the default dtype
    ref64 = run(pipe64, inputs64)
    torch.set_default_dtype(torch.float32)
    rows = []
    for k in sorted(ref):
        if k == "grid":
            continue
        err = (ref[k].double() - ref64[k].double()).abs().max().item()
        rows.append(f"| {k} | {list(ref[k].shape)} | {ref[k].double().abs().max().item():.3e} | {err:.3e} |")

    meta = {"libraries": str(C.library_versions()),
            "fingerprint_keys": json.dumps(fp_keys)}
    C.write_safetensors(os.path.join(HERE, "inputs.safetensors"), inputs, metadata={"libraries": meta["libraries"]})
    C.write_safetensors(os.path.join(HERE, "outputs.safetensors"), outputs, metadata=meta)
    with open(os.path.join(HERE, "errors.md"), "w") as f:
        f.write("| tensor | shape | max abs value | max abs fp32 vs fp64 |\n|---|---|---|---|\n")
        f.write("\n".join(rows) + "\n")
    print("libraries", C.library_versions())
    print("\n".join(rows))


if __name__ == "__main__":
    main()
