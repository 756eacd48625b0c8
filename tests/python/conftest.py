"""Shared set-up of the Python module's tests (docs/python.md, "Tests").

The module is imported from the build tree: PYTHONPATH=build/python, as scripts/test.sh sets it. The CLI
the tests compare against is $UNIQUE3D_CLI, or build/unique3d beside the module.
"""
import os
import pathlib
import subprocess

import pytest

import unique3d

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "spot" / "views"
VIEWS = ("front", "right", "back", "left")

# Options that reconstruct the bundled example in a few seconds (fewer steps are slower: the clean-up
# has more to do).
FAST = dict(coarse_steps=40, refine_steps=20, texture_size=512, faces=5000)
FAST_CLI = ["--coarse-steps", "40", "--refine-steps", "20", "--texture-size", "512", "--faces", "5000"]


def cli_path():
    if "UNIQUE3D_CLI" in os.environ:
        return pathlib.Path(os.environ["UNIQUE3D_CLI"])
    return pathlib.Path(unique3d.__file__).resolve().parent.parent / "unique3d"


def run_cli(*args):
    """Runs the CLI; returns its stderr (the progress lines)."""
    done = subprocess.run([str(cli_path()), *map(str, args)], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return done.stderr


def example_arrays(dtype="float32"):
    """The bundled example's images as arrays: float32 as read, or uint8 as an 8-bit file holds them."""
    import numpy as np

    def load(name):
        a = unique3d.read_image(EXAMPLE / name)
        return a if dtype == "float32" else np.round(a * 255).astype(np.uint8)

    return [load(f"{v}_rgb.png") for v in VIEWS], [load(f"{v}_normal.png") for v in VIEWS]


@pytest.fixture(scope="session")
def cli_glb(tmp_path_factory):
    """The CLI's mesh of the bundled example with the fast options, and its progress lines."""
    out = tmp_path_factory.mktemp("cli") / "spot.glb"
    stderr = run_cli("reconstruct", EXAMPLE, "-o", out, *FAST_CLI)
    return out, stderr


@pytest.fixture(scope="session")
def spot_mesh():
    """The bundled example reconstructed from its folder with the fast options."""
    return unique3d.reconstruct(EXAMPLE, **FAST)
