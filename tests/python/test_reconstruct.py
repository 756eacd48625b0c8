"""unique3d.reconstruct and unique3d.Mesh: the CLI's mesh from a folder and from arrays, the arrays."""
import numpy as np
import pytest

import unique3d
from conftest import EXAMPLE, FAST, example_arrays


def test_folder_gives_the_clis_glb(cli_glb, spot_mesh, tmp_path):
    expected = cli_glb[0].read_bytes()
    spot_mesh.save(tmp_path / "saved.glb")
    assert (tmp_path / "saved.glb").read_bytes() == expected
    # The facade writes the same file itself with output=.
    unique3d.reconstruct(str(EXAMPLE), output=tmp_path / "written.glb", **FAST)
    assert (tmp_path / "written.glb").read_bytes() == expected


@pytest.mark.parametrize("dtype", ["float32", "uint8"])
def test_arrays_give_the_clis_glb(cli_glb, tmp_path, dtype):
    rgb, normals = example_arrays(dtype)
    assert rgb[0].dtype == np.dtype(dtype) and rgb[0].shape == (512, 512, 4)
    views = unique3d.ViewSet(rgb, normals)
    assert views.rgb_resolution == 512 and views.normal_resolution == 512
    mesh = unique3d.reconstruct(views, **FAST)
    mesh.save(tmp_path / "arrays.glb")
    assert (tmp_path / "arrays.glb").read_bytes() == cli_glb[0].read_bytes()


def test_textured_mesh_arrays(spot_mesh):
    mesh = spot_mesh
    v, f, uv, tex = mesh.vertices, mesh.faces, mesh.uv, mesh.texture
    assert v.dtype == np.float32 and v.ndim == 2 and v.shape[1] == 3 and len(v) > 1000
    assert f.dtype == np.int32 and f.shape == (5000, 3)
    assert f.min() >= 0 and f.max() < len(v)
    assert uv.dtype == np.float32 and uv.shape == (len(v), 2) and 0 <= uv.min() and uv.max() <= 1
    assert tex.dtype == np.uint8 and tex.shape == (512, 512, 3)
    assert mesh.vertex_colors is None
    # The object fits the views' frame: [-1, 1]^3.
    assert np.abs(v).max() <= 1.0 and np.ptp(v, axis=0).min() > 0.5
    # Views of the mesh's own memory, read-only, valid after the Mesh object is gone.
    assert not v.flags.writeable and not f.flags.writeable
    with pytest.raises(ValueError):
        v[0, 0] = 1.0
    assert np.shares_memory(v, mesh.vertices)


def test_vertex_colours_and_summary():
    mesh = unique3d.reconstruct(EXAMPLE, colour="vertex", coarse_steps=40, refine_steps=20, faces=3000)
    assert mesh.texture is None and mesh.uv is None
    c = mesh.vertex_colors
    assert c.shape == mesh.vertices.shape and c.dtype == np.float32 and 0 <= c.min() and c.max() <= 1
    s = mesh.summary
    assert s["mesh"]["vertices"] == len(mesh.vertices) and s["mesh"]["faces"] == 3000
    assert all(iou > 0.9 for iou in s["mesh"]["silhouette_iou"])
    assert s["written"] == []
    assert "3000 faces" in repr(mesh)
