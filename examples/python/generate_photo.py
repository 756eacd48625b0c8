"""One photo to a textured mesh with the whole method (PYTHONPATH=build/python):
    python3 examples/python/generate_photo.py PHOTO.png --models ckpt/ [-o mesh.glb] [--seed N]
The model folder is the official release's ckpt/ (docs/models.md); `unique3d doctor --models ckpt/`
checks it. Ctrl-C stops the run cleanly."""
import argparse
import sys

import unique3d

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("photo")
parser.add_argument("--models", required=True, help="the model folder")
parser.add_argument("-o", "--output", default="mesh.glb")
parser.add_argument("--seed", type=int, default=None)
args = parser.parse_args()

report = unique3d.doctor(args.models)
if not report["generate_ready"]:
    failed = [n["name"] + ": " + n["error"] for n in report["networks"] if not n["ok"]]
    sys.exit("the model folder cannot run generate:\n  " + "\n  ".join(failed))


def show(event):
    if event.kind == "stage_begin":
        print(event.text, "...", flush=True)
    elif event.kind == "step" and event.step == event.steps:
        print(f"  {event.text}: {event.steps} steps", flush=True)


try:
    result = unique3d.generate(args.photo, models=args.models, seed=args.seed, keep_intermediates=True, progress=show)
except unique3d.Error as error:
    sys.exit(f"error: {error}")
result.mesh.save(args.output)
for stage in result.summary["stages"]:
    print(f"{stage['name']:12} {stage['seconds']:8.1f} s")
print(f"{len(result.mesh.faces)} faces -> {args.output}; intermediates: {', '.join(sorted(result.intermediates))}")
