"""unique3d.generate, doctor and evaluate on the tiny stand-in models of the C++ tests (written by
make_tiny_models, tests/pipeline/tiny_model_folder.h) at small sizes."""
import os
import pathlib
import subprocess

import numpy as np
import pytest

import unique3d
from conftest import EXAMPLE

# Small sizes for the tiny networks, as tests/pipeline/test_generate.cpp runs them; the tiny networks'
# views disagree, so the silhouette fit (a 256^3 grid) is left out.
SMALL = dict(dtype="fp32", steps=2, multiview_size=32, refine_size=64, normal_size=32, coarse_steps=5,
             refine_steps=5, silhouette_fit=False, faces=500, texture_size=128)
STAGES = ["prepare", "multiview", "refine", "upscale", "normals", "reconstruct"]


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tiny")
    tool = os.environ.get("UNIQUE3D_MAKE_TINY_MODELS",
                          pathlib.Path(unique3d.__file__).resolve().parent.parent / "tests" / "make_tiny_models")
    subprocess.run([str(tool), folder / "models", folder / "photo.png"], check=True)
    return folder / "models", folder / "photo.png"


def stop_at_multiview(event):
    """A progress callback that stops generate once the prepared photo is kept."""
    if event.kind == "stage_begin" and event.text == "multi-view generation":
        raise KeyError("prepared")


def differing_arrays(a, b):
    """The names whose arrays differ (or that only one side has), each with its largest difference."""
    return sorted((k, float(np.abs(a[k].astype(np.float64) - b[k]).max()) if k in a and k in b and a[k].shape == b[k].shape else None)
                  for k in a.keys() | b.keys() if k not in a or k not in b or not np.array_equal(a[k], b[k]))


def test_generate_from_a_path_and_from_an_array(tiny, tmp_path):
    models, photo = tiny
    events = []
    first = unique3d.generate(photo, models=models, seed=7, refine=False, keep_intermediates=True,
                              progress=events.append, **SMALL)
    assert [s["name"] for s in first.summary["stages"]] == STAGES
    assert first.summary["precision"] == "fp32"
    # The listener saw each stage's work begin and end.
    begun = [e.text for e in events if e.kind == "stage_begin"]
    for stage in ["preparing the photo", "multi-view generation", "upscaling x4", "normal prediction", "coarse",
                  "refine", "texture"]:
        assert stage in begun
    assert sorted(begun) == sorted(e.text for e in events if e.kind == "stage_end")
    assert len(first.mesh.faces) > 0 and first.mesh.texture.shape == (128, 128, 3)
    inter = first.intermediates
    assert "front" in inter and "views/left_normal" in inter and "multiview/front_rgb" in inter
    assert inter["multiview/front_rgb"].shape[:2] == (32, 32) and inter["front"].dtype == np.float32

    # The same photo as a uint8 array, the same seed: the same intermediates and mesh; written where asked.
    array = np.round(unique3d.read_image(photo) * 255).astype(np.uint8)
    kept = tmp_path / "kept"
    second = unique3d.generate(array, models=models, seed=7, refine=False, keep_intermediates=kept,
                               output=tmp_path / "m.glb", **SMALL)
    assert differing_arrays(first.intermediates, second.intermediates) == []
    assert np.array_equal(first.mesh.vertices, second.mesh.vertices)
    assert (kept / "views" / "front_normal.png").exists()
    first.mesh.save(tmp_path / "first.glb")
    assert (tmp_path / "first.glb").read_bytes() == (tmp_path / "m.glb").read_bytes()

    # Another seed draws other views; a callback that raises once they are kept stops the run there.
    def stop_after_multiview(event):
        if event.kind == "stage_begin" and event.text == "upscaling x4":
            raise KeyError("enough")

    other = tmp_path / "other"
    with pytest.raises(KeyError, match="enough"):
        unique3d.generate(photo, models=models, seed=8, refine=False, keep_intermediates=other,
                          output=tmp_path / "other.glb", progress=stop_after_multiview, **SMALL)
    assert not (tmp_path / "other.glb").exists() and not (other / "upscaled").exists()
    assert not np.array_equal(unique3d.read_image(other / "multiview" / "front_rgb.png"), inter["multiview/front_rgb"])


def small_cli_options():
    """SMALL as the command's options."""
    flags = []
    for key, value in SMALL.items():
        if key == "silhouette_fit":
            flags.append("--no-silhouette-fit")
        else:
            flags += ["--" + key.replace("_", "-"), str(value)]
    return flags


def test_generate_gives_the_commands_files(tiny, tmp_path):
    """A PIL image in, refinement on: the same intermediates and the byte-identical GLB the command writes
    from the photo's file with the same seed and options."""
    from PIL import Image
    from conftest import run_cli

    models, photo = tiny
    run_cli("generate", photo, "-o", tmp_path / "cli.glb", "--models", models, "--seed", 11,
            "--keep-intermediates", tmp_path / "cli", *small_cli_options())
    with Image.open(photo) as pil:
        assert pil.mode == "RGBA"
        result = unique3d.generate(pil, models=models, seed=11, keep_intermediates=tmp_path / "py",
                                   output=tmp_path / "py.glb", **SMALL)
    assert (tmp_path / "py.glb").read_bytes() == (tmp_path / "cli.glb").read_bytes()
    files = sorted(p.relative_to(tmp_path / "cli") for p in (tmp_path / "cli").rglob("*.png"))
    assert len(files) == 1 + 4 * 4 + 4  # the photo, four stages' four views, and the four normal maps
    assert files == sorted(p.relative_to(tmp_path / "py") for p in (tmp_path / "py").rglob("*.png"))
    for name in files:
        assert np.array_equal(unique3d.read_image(tmp_path / "cli" / name), unique3d.read_image(tmp_path / "py" / name)), name
    assert [s["name"] for s in result.summary["stages"]] == STAGES


def test_generate_takes_grey_and_palette_pil_images(tiny, tmp_path):
    """PIL images in other modes are converted: grey to RGB (a photo without alpha, which is matted), a
    palette with a transparent background index to RGBA; each is prepared as the converted file is (the
    runs stop once the prepared photo is kept)."""
    from PIL import Image

    models, photo = tiny
    with Image.open(photo) as pil:
        rgba = pil.copy()
    grey = rgba.convert("L")
    palette = rgba.convert("RGB").quantize(16)
    palette.info["transparency"] = palette.getpixel((0, 0))
    prepared = {}
    for name, image, mode in [("grey", grey, "RGB"), ("palette", palette, "RGBA")]:
        image.convert(mode).save(tmp_path / f"{name}.png")
        for source in ("pil", "file"):
            kept = tmp_path / f"{name}_{source}"
            with pytest.raises(KeyError, match="prepared"):
                unique3d.generate(image if source == "pil" else tmp_path / f"{name}.png", models=models,
                                  keep_intermediates=kept, progress=stop_at_multiview, **SMALL)
            prepared[name, source] = unique3d.read_image(kept / "front.png")
        assert np.array_equal(prepared[name, "pil"], prepared[name, "file"]), name
    # The palette's transparent index is the background the grey photo had to have matted away.
    assert not np.array_equal(prepared["grey", "pil"][..., 3], prepared["palette", "pil"][..., 3])


def test_generate_raw_matte_is_the_commands(tiny, tmp_path):
    """raw_matte=True keeps the background-removal network's mask as it is, as `generate --raw-matte` does:
    on a photo without alpha (matted), the prepared front image is the command's, and not the default's
    (the mask made solid)."""
    from conftest import run_cli

    from PIL import Image

    models, photo = tiny
    with Image.open(photo) as pil:
        pil.convert("RGB").save(tmp_path / "opaque.png")
    fronts = {}
    for raw in (False, True):
        with pytest.raises(KeyError, match="prepared"):
            unique3d.generate(tmp_path / "opaque.png", models=models, raw_matte=raw,
                              keep_intermediates=tmp_path / f"py_{raw}", progress=stop_at_multiview, **SMALL)
        fronts[raw] = unique3d.read_image(tmp_path / f"py_{raw}" / "front.png")
    assert not np.array_equal(fronts[False], fronts[True])
    run_cli("generate", tmp_path / "opaque.png", "-o", tmp_path / "cli.glb", "--models", models, "--raw-matte",
            "--keep-intermediates", tmp_path / "cli", *small_cli_options())
    assert np.array_equal(unique3d.read_image(tmp_path / "cli" / "front.png"), fronts[True])


def test_generate_cancels_and_checks_its_arguments(tiny, tmp_path):
    models, photo = tiny
    token = unique3d.CancelToken()
    token.cancel()
    with pytest.raises(unique3d.Cancelled):
        unique3d.generate(photo, models=models, output=tmp_path / "m.glb", cancel=token, **SMALL)
    with pytest.raises(ValueError, match="dtype"):
        unique3d.generate(photo, models=models, dtype="fp64")
    with pytest.raises(ValueError, match="seed"):
        unique3d.generate(photo, models=models, seed=-1)
    with pytest.raises(TypeError, match="image must be a path"):
        unique3d.generate(3.5, models=models)
    with pytest.raises(ValueError, match="image: expected an H x W x 3 or 4 array"):
        unique3d.generate(np.zeros((8, 8), np.uint8), models=models)
    with pytest.raises(unique3d.Error, match="nowhere"):
        unique3d.generate(photo, models=tmp_path / "nowhere", **SMALL)
    assert list(tmp_path.iterdir()) == []


def test_doctor(tiny, tmp_path):
    models, _ = tiny
    report = unique3d.doctor(models)
    assert report["system"]["cores"] >= 1 and report["system"]["torch_version"]
    assert len(report["networks"]) == 5 and all(n["ok"] for n in report["networks"]), report["networks"]
    assert report["generate_ready"]
    (tmp_path / "empty").mkdir()
    empty = unique3d.doctor(tmp_path / "empty")
    assert not empty["generate_ready"] and not any(n["ok"] for n in empty["networks"])
    with pytest.raises(unique3d.Error):
        unique3d.doctor(tmp_path / "nowhere")


def test_evaluate_a_reconstruction_against_the_ground_truth(spot_mesh):
    mesh = spot_mesh
    gt = unique3d.load_mesh(EXAMPLE.parent / "spot.obj")
    assert gt.summary is None and len(gt.faces) > 0
    metrics = unique3d.evaluate(mesh, EXAMPLE.parent / "spot.obj", appearance=False, surface_samples=20000)
    itself = unique3d.evaluate(gt, gt, appearance=False, surface_samples=20000)
    assert metrics["pred"]["faces"] == 5000
    # A reconstruction is close to its ground truth, and further from it than the ground truth itself.
    assert 0 <= itself["chamfer"]["l1"] < metrics["chamfer"]["l1"] < 0.02
    assert metrics["volume_iou"]["iou"] > 0.8 and itself["volume_iou"]["iou"] == 1.0


def test_render_draws_the_clis_views(tmp_path):
    from conftest import VIEWS, run_cli

    run_cli("render", EXAMPLE.parent / "spot.obj", "-o", tmp_path / "views", "--res", "128")
    views = unique3d.render(EXAMPLE.parent / "spot.obj", resolution=128)
    assert sorted(views) == sorted(f"{v}_{k}" for v in VIEWS for k in ("rgb", "normal"))
    for name, image in views.items():
        assert image.shape == (128, 128, 4) and image.dtype == np.float32
        # The CLI's 8-bit PNG holds the same image, rounded.
        assert np.abs(unique3d.read_image(tmp_path / "views" / f"{name}.png") - image).max() <= 0.5 / 255 + 1e-6
    # The renders make a view set.
    unique3d.ViewSet([views[f"{v}_rgb"] for v in VIEWS], [views[f"{v}_normal"] for v in VIEWS])
    with pytest.raises(ValueError, match="resolution"):
        unique3d.render(EXAMPLE.parent / "spot.obj", resolution=0)
