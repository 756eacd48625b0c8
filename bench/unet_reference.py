#!/usr/bin/python3
# Python reference for bench/bench_unet: times the forward of the full-size sd-image-variations UNet
# (diffusers 0.27.2 UNet2DConditionModel, ~860M random weights N(0, 0.02^2), seeded) on the CPU with every
# core, batch 8 at 32x32 latents and batch 2 at 64x64, encoder_hidden_states [batch, 1, 768], timestep 500.
# Reports per case the median and min wall seconds, the median process CPU seconds (all threads) of one
# forward, and the process's peak RSS (getrusage ru_maxrss, since process start) in GB.
#
# Environment: Debian's python3-torch 1.13 (/usr/bin/python3) plus the library sources the golden-data
# generators use, extracted (not installed) by
#     MIRROR=DIR bash ../shared/golden/generators/setup_env.sh    # -> /tmp/golden_env
# (DIR holds the repository snapshots named in that script). diffusers needs `safetensors` to import; the
# generators' pure-Python stand-in (../shared/golden/generators/shims) is put on sys.path when the real
# package is missing (--shims). Run:
#     /usr/bin/python3 bench/unet_reference.py [--dtype fp32|bf16] [--repetitions 3] [--case 8x32|2x64|all]
import argparse
import json
import os
import resource
import statistics
import sys
import time

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MANIFEST = os.path.join(REPO_ROOT, "tests", "data", "nn", "manifests", "unet_sd_image_variations_plain.json")
GENERATORS = os.path.join(REPO_ROOT, "..", "shared", "golden", "generators")
CASES = {"8x32": (8, 32), "2x64": (2, 64)}


def parse_args():
    p = argparse.ArgumentParser(description="diffusers UNet2DConditionModel CPU forward timing (reference for bench_unet)")
    p.add_argument("--dtype", choices=["fp32", "bf16"], default="fp32",
                   help="bf16: the whole model .to(torch.bfloat16) and bf16 inputs")
    p.add_argument("--repetitions", type=int, default=3, help="timed forwards per case (no separate warm-up)")
    p.add_argument("--case", choices=sorted(CASES) + ["all"], default="all")
    p.add_argument("--env", default=os.environ.get("GOLDEN_ENV", "/tmp/golden_env"),
                   help="folder that setup_env.sh extracted diffusers etc. into (default: $GOLDEN_ENV or /tmp/golden_env)")
    p.add_argument("--shims", default=os.environ.get("GOLDEN_SHIMS", os.path.join(GENERATORS, "shims")),
                   help="folder with the import-only safetensors stand-in, used when safetensors is not installed")
    args = p.parse_args()
    if args.repetitions < 1:
        p.error("--repetitions must be at least 1")
    return args


def import_unet_class(env_dir, shims_dir):
    """UNet2DConditionModel from the extracted sources in env_dir; exits with a hint if they are not there."""
    hint = ("run `MIRROR=DIR bash ../shared/golden/generators/setup_env.sh` (DIR holds the repository "
            "snapshots it names), or point --env / $GOLDEN_ENV at the folder it made")
    if not os.path.isdir(os.path.join(env_dir, "diffusers")):
        sys.exit(f"unet_reference: no diffusers sources in {env_dir}: {hint}")
    sys.path.insert(0, env_dir)
    try:
        import safetensors  # noqa: F401
    except ImportError:
        if os.path.isdir(os.path.join(shims_dir, "safetensors")):
            sys.path.append(shims_dir)  # after env_dir: only fills in what is missing
    # never reach for the network
    for var in ("HF_HUB_OFFLINE", "TRANSFORMERS_OFFLINE", "DIFFUSERS_OFFLINE"):
        os.environ.setdefault(var, "1")
    try:
        from diffusers import UNet2DConditionModel
        import diffusers
    except (ImportError, RuntimeError) as e:  # diffusers' lazy modules wrap import errors in RuntimeError
        sys.exit(f"unet_reference: cannot import diffusers from {env_dir} ({type(e).__name__}: {e}).\n"
                 f"If it is missing or incomplete, {hint}; if `safetensors` is missing, pass --shims "
                 f"(the golden generators' shims folder).")
    return UNet2DConditionModel, diffusers.__version__


def load_config():
    with open(MANIFEST) as f:
        config = json.load(f)["constructor_config"]
    # keys such as _use_default_values / _class_name are bookkeeping, not constructor arguments
    return {k: v for k, v in config.items() if not k.startswith("_")}


def peak_rss_gb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / (1024.0 * 1024.0)  # Linux: KiB


def main():
    args = parse_args()
    import torch

    UNet, diffusers_version = import_unet_class(args.env, args.shims)
    torch.set_num_threads(os.cpu_count())
    # as bench_unet: random weights can drive values into denormals, which would time the FPU's slow path
    torch.set_flush_denormal(True)
    dtype = torch.bfloat16 if args.dtype == "bf16" else torch.float32

    built = time.perf_counter()
    unet = UNet(**load_config())
    torch.manual_seed(0)
    with torch.no_grad():
        for param in unet.parameters():
            param.normal_(0.0, 0.02)
    unet = unet.to(dtype).eval()
    built = time.perf_counter() - built
    n_params = sum(p.numel() for p in unet.parameters())
    processors = sorted({type(proc).__name__ for proc in unet.attn_processors.values()})
    print(f"torch {torch.__version__}, diffusers {diffusers_version}, threads {torch.get_num_threads()}, "
          f"dtype {args.dtype}, {n_params / 1e6:.1f}M parameters, attention {','.join(processors)}, "
          f"built in {built:.1f} s", flush=True)

    names = list(CASES) if args.case == "all" else [args.case]
    rows = []
    for name in names:
        batch, size = CASES[name]
        torch.manual_seed(1)
        sample = torch.randn(batch, 4, size, size).to(dtype)
        embedding = torch.randn(batch, 1, 768).to(dtype)
        timestep = torch.tensor(500.0)
        walls, cpus, finite = [], [], True
        with torch.inference_mode():
            for _ in range(args.repetitions):
                w0, c0 = time.perf_counter(), time.process_time()
                out = unet(sample, timestep, encoder_hidden_states=embedding, return_dict=False)[0]
                walls.append(time.perf_counter() - w0)
                cpus.append(time.process_time() - c0)
                finite = finite and bool(torch.isfinite(out).all())
                print(f"  {name} rep {len(walls)}: {walls[-1]:.2f} s wall, {cpus[-1]:.2f} s CPU", flush=True)
                del out
        rows.append((name, batch, size, args.dtype, args.repetitions, statistics.median(walls), min(walls),
                     statistics.median(cpus), peak_rss_gb(), "yes" if finite else "NO"))

    header = ("case", "batch", "latent", "dtype", "reps", "median_wall_s", "min_wall_s", "cpu_s", "peak_rss_GB",
              "finite")
    table = [header] + [(r[0], str(r[1]), str(r[2]), r[3], str(r[4]), f"{r[5]:.2f}", f"{r[6]:.2f}", f"{r[7]:.2f}",
                         f"{r[8]:.2f}", r[9]) for r in rows]
    widths = [max(len(row[i]) for row in table) for i in range(len(header))]
    print()
    for row in table:
        print("  ".join(cell.rjust(width) for cell, width in zip(row, widths)))
    print("cpu_s: median process CPU seconds (all threads) of one forward; peak_rss_GB: ru_maxrss since process "
          "start (includes building the model)")


if __name__ == "__main__":
    main()
