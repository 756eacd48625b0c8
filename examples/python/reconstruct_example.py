"""Reconstructs the bundled example into a textured mesh: PYTHONPATH=build/python python3 THIS_FILE"""
import pathlib

import unique3d

views = pathlib.Path(__file__).resolve().parents[1] / "spot" / "views"
mesh = unique3d.reconstruct(views, faces=20000, texture_size=1024)
mesh.save("spot.glb")
print(f"spot.glb: {len(mesh.vertices)} vertices, {len(mesh.faces)} faces, a {mesh.texture.shape[0]} px texture")
