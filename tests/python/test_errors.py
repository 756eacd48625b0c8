"""Bad input: each case a Python exception with a clear message (ValueError or TypeError for a bad
argument, unique3d.Error with the CLI's message for bad files and data), never a crash."""
import numpy as np
import pytest

import unique3d
from conftest import EXAMPLE, example_arrays


@pytest.fixture(scope="module")
def arrays():
    return example_arrays("float32")


def with_view(images, index, image):
    out = list(images)
    out[index] = image
    return out


def viewset_cases(rgb, normals):
    nan = normals[1].copy()
    nan[256, 256, 0] = np.nan
    blank = np.zeros_like(normals[2])
    bright = rgb[0] * 2
    return [
        ("three views", lambda: unique3d.ViewSet(rgb[:3], normals), ValueError, "four arrays"),
        ("not a sequence", lambda: unique3d.ViewSet(rgb[0], normals), ValueError, "four arrays"),
        ("a string", lambda: unique3d.ViewSet("front_rgb.png", normals), TypeError, "sequence of four"),
        ("not an array", lambda: unique3d.ViewSet(with_view(rgb, 0, [[1, 2]]), normals), TypeError, "numpy array"),
        ("2-D image", lambda: unique3d.ViewSet(with_view(rgb, 1, rgb[1][..., 0]), normals), ValueError,
         r"rgb\[1\] \(right\): expected an H x W x 3 or 4 array, got shape \(512, 512\)"),
        ("5 channels", lambda: unique3d.ViewSet(rgb, with_view(normals, 0, np.zeros((512, 512, 5), np.float32))),
         ValueError, "got shape"),
        ("float64", lambda: unique3d.ViewSet(with_view(rgb, 2, rgb[2].astype(np.float64)), normals), ValueError,
         "dtype uint8 or float32, got float64"),
        ("int32", lambda: unique3d.ViewSet(rgb, with_view(normals, 3, normals[3].astype(np.int32))), ValueError,
         "got int32"),
        ("not contiguous", lambda: unique3d.ViewSet(with_view(rgb, 0, rgb[0].transpose(1, 0, 2)), normals), ValueError,
         "not C-contiguous"),
        ("NaN normals", lambda: unique3d.ViewSet(rgb, with_view(normals, 1, nan)), ValueError,
         r"normals\[1\] \(right\): contains NaN"),
        ("out of range", lambda: unique3d.ViewSet(with_view(rgb, 0, bright), normals), ValueError, r"in \[0, 1\]"),
        ("empty image", lambda: unique3d.ViewSet(with_view(rgb, 0, np.zeros((0, 0, 4), np.float32)), normals),
         ValueError, "empty"),
        ("not square", lambda: unique3d.ViewSet(with_view(rgb, 0, np.ascontiguousarray(rgb[0][:400])), normals),
         unique3d.Error, "rgb"),
        ("sizes differ", lambda: unique3d.ViewSet(with_view(rgb, 3, np.ascontiguousarray(rgb[3][::2, ::2])), normals),
         unique3d.Error, "rgb"),
        ("blank normal map", lambda: unique3d.ViewSet(rgb, with_view(normals, 2, blank)), unique3d.Error,
         r"normals\[2\] \(back\)"),
        ("bad normal space", lambda: unique3d.ViewSet(rgb, normals, normal_space="moon"), ValueError, "normal_space"),
    ]


def reconstruct_cases(tmp):
    (tmp / "not_views").mkdir(exist_ok=True)
    (tmp / "not_views" / "notes.txt").write_text("not a view set")
    return [
        ("missing folder", lambda: unique3d.reconstruct(tmp / "nowhere"), unique3d.Error, "nowhere"),
        ("not a view set", lambda: unique3d.reconstruct(tmp / "not_views"), unique3d.Error, "front_rgb.png"),
        ("views of a number", lambda: unique3d.reconstruct(42), TypeError, "str or os.PathLike"),
        ("output extension", lambda: unique3d.reconstruct(EXAMPLE, output=tmp / "x.stl"), unique3d.Error,
         r"unsupported extension \(use .glb, .obj or .ply\)"),
        ("output folder missing", lambda: unique3d.reconstruct(EXAMPLE, output=tmp / "no" / "x.glb"), unique3d.Error,
         "does not exist"),
        ("previews without output", lambda: unique3d.reconstruct(EXAMPLE, previews=True), unique3d.Error, "previews"),
        ("colour", lambda: unique3d.reconstruct(EXAMPLE, colour="rainbow"), ValueError, "colour"),
        ("texture size", lambda: unique3d.reconstruct(EXAMPLE, texture_size=10), ValueError,
         r"texture_size must be in \[64, 8192\], got 10"),
        ("texture without texture", lambda: unique3d.reconstruct(EXAMPLE, colour="vertex", texture_size=512),
         ValueError, "texture_size needs colour"),
        ("texture format", lambda: unique3d.reconstruct(EXAMPLE, texture_format="bmp"), ValueError, "texture_format"),
        ("faces too few", lambda: unique3d.reconstruct(EXAMPLE, faces=5), ValueError, "faces"),
        ("faces as text", lambda: unique3d.reconstruct(EXAMPLE, faces="many"), TypeError, "faces must be an int"),
        ("negative steps", lambda: unique3d.reconstruct(EXAMPLE, coarse_steps=-1), ValueError, "coarse_steps"),
        ("normal space", lambda: unique3d.reconstruct(EXAMPLE, normal_space="moon"), ValueError, "normal_space"),
        ("progress not callable", lambda: unique3d.reconstruct(EXAMPLE, progress=3), TypeError, "progress"),
        ("cancel not a token", lambda: unique3d.reconstruct(EXAMPLE, cancel=True), TypeError, "CancelToken"),
        ("missing image", lambda: unique3d.read_image(tmp / "none.png"), unique3d.Error, "none.png"),
        ("not an image", lambda: unique3d.read_image(tmp / "not_views" / "notes.txt"), unique3d.Error, "notes.txt"),
    ]


def check_cases(cases):
    for name, call, error, message in cases:
        try:
            with pytest.raises(error, match=message):
                call()
        except BaseException as failure:  # pytest's own failure is not an Exception
            raise AssertionError(f"case {name!r}: {failure}") from None


def test_bad_view_arrays(arrays):
    cases = viewset_cases(*arrays)
    assert len(cases) >= 15
    check_cases(cases)


def test_bad_reconstruct_arguments(tmp_path):
    cases = reconstruct_cases(tmp_path)
    assert len(cases) >= 15
    check_cases(cases)
    # Nothing was written by any of them.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["not_views"]


def test_bad_save(tmp_path):
    rgb, normals = example_arrays("uint8")
    mesh = unique3d.reconstruct(unique3d.ViewSet(rgb, normals), coarse_steps=40, refine_steps=20, texture_size=256,
                                faces=2000)
    with pytest.raises(unique3d.Error, match="unsupported extension"):
        mesh.save(tmp_path / "x.xyz")
    with pytest.raises(ValueError, match="texture_format"):
        mesh.save(tmp_path / "x.glb", texture_format="gif")
    assert list(tmp_path.iterdir()) == []
