"""50 reconstructions in a loop: the process's resident memory stays within a bound (no leak of meshes,
view sets, summaries or the arrays that view them)."""
import gc
import weakref

import numpy as np

import unique3d
from conftest import example_arrays

# The bundled example at a quarter of its size, and options that make a run about a second (the
# silhouette fit's 256^3 grid would take most of the time).
SMALL = dict(coarse_steps=10, refine_steps=5, colour="vertex", silhouette_fit=False, faces=500)


def resident_mib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20


def test_arrays_keep_their_mesh_alive_and_no_longer():
    rgb, normals = example_arrays("uint8")
    small = [np.ascontiguousarray(a[::4, ::4]) for a in rgb], [np.ascontiguousarray(a[::4, ::4]) for a in normals]
    mesh = unique3d.reconstruct(unique3d.ViewSet(*small), **SMALL)
    alive = weakref.ref(mesh)
    vertices = mesh.vertices
    del mesh
    assert alive() is not None and np.isfinite(vertices).all()
    del vertices
    gc.collect()
    assert alive() is None


def test_fifty_reconstructions_do_not_grow_memory():
    rgb, normals = example_arrays("uint8")
    rgb = [np.ascontiguousarray(a[::4, ::4]) for a in rgb]
    normals = [np.ascontiguousarray(a[::4, ::4]) for a in normals]
    def once():
        mesh = unique3d.reconstruct(unique3d.ViewSet(rgb, normals), **SMALL)
        return mesh.vertices.sum() + mesh.vertex_colors.sum() + len(mesh.summary["timings"])

    for _ in range(5):  # allocator pools, libraries' caches
        once()
    before = resident_mib()
    for _ in range(50):
        once()
    grown = resident_mib() - before
    # One run's view set alone is 2 MiB (eight 128 px float images): a leak of it, or of any larger
    # buffer of the run, would pass 100 MiB.
    assert grown < 25, f"resident memory grew by {grown:.1f} MiB over 50 runs"
