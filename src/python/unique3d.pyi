"""Unique3D from Python: one photo to a textured 3D mesh (docs/python.md).

Every run releases the GIL, reports to an optional ``progress`` callable, and stops when that callable
raises, when a ``CancelToken`` given as ``cancel`` is cancelled (from any thread), or on Ctrl-C.
Failures of the library raise ``unique3d.Error`` with the command line's message; bad arguments raise
``ValueError`` (or ``TypeError`` for an argument of the wrong kind).
"""
import os
from typing import Any, Callable, Literal, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, os.PathLike]
ImageArray = Union[npt.NDArray[np.uint8], npt.NDArray[np.float32]]
Progress = Optional[Callable[["ProgressEvent"], Any]]

class Error(Exception):
    """A failure of the library: bad files, bad data, a model folder that cannot run (the CLI's message)."""

class Cancelled(Error):
    """The run was stopped by CancelToken.cancel()."""

class CancelToken:
    """Pass as ``cancel=`` to a run; ``cancel()`` from any thread stops it at its next check (well
    within a second)."""
    def __init__(self) -> None: ...
    def cancel(self) -> None: ...
    @property
    def cancelled(self) -> bool: ...

class ProgressEvent:
    """One event of a run, as the ``progress=`` callable gets it."""
    @property
    def kind(self) -> Literal["stage_begin", "stage_end", "message", "step"]: ...
    @property
    def text(self) -> str:
        """The stage's name (stage_begin, stage_end, step) or the message."""
    @property
    def seconds(self) -> float:
        """stage_end: the stage's time."""
    @property
    def step(self) -> int:
        """step: the 1-based step of ``steps``."""
    @property
    def steps(self) -> int: ...
    @property
    def seconds_left(self) -> Optional[float]:
        """step: the rest of the loop, extrapolated from its steps so far."""

class ViewSet:
    """The four views (front, right, back, left) ISOMER reconstructs from, checked like a views folder.

    ``rgb``: four H x W x 3 or 4 images (alpha = mask); ``normals``: four normal maps encoding a unit
    normal n as (n + 1) / 2, in world space or in each view's camera space. Arrays are uint8 (as an
    8-bit PNG holds them) or float32 in [0, 1], C-contiguous, square, one size per kind.
    """
    def __init__(self, rgb: Sequence[ImageArray], normals: Sequence[ImageArray], *,
                 normal_space: Literal["world", "camera"] = "world") -> None: ...
    @staticmethod
    def load(folder: PathLike, *, normal_space: Literal["world", "camera"] = "world") -> "ViewSet":
        """Loads {front,right,back,left}_{rgb,normal}.png from a folder."""
    @property
    def rgb_resolution(self) -> int: ...
    @property
    def normal_resolution(self) -> int: ...
    @property
    def rgb(self) -> list[npt.NDArray[np.float32]]:
        """The four RGBA images, float32 in [0, 1], alpha = mask weight (a copy)."""
    @property
    def normals(self) -> list[npt.NDArray[np.float32]]:
        """The four normal maps decoded to world-space unit vectors, plus the mask (a copy)."""

class Mesh:
    """A triangle mesh with its colours. The array properties are read-only views of the mesh's memory
    (no copy); they keep the mesh alive."""
    @property
    def vertices(self) -> npt.NDArray[np.float32]:
        """N x 3 positions, in the views' frame ([-1, 1]^3)."""
    @property
    def faces(self) -> npt.NDArray[np.int32]:
        """M x 3 vertex indices, counter-clockwise seen from outside."""
    @property
    def uv(self) -> Optional[npt.NDArray[np.float32]]:
        """N x 2 texture coordinates ((0, 0) = the texture's bottom-left), or None."""
    @property
    def texture(self) -> Optional[npt.NDArray[np.uint8]]:
        """H x W x 3 sRGB texture, row 0 at the top (a new array each time), or None."""
    @property
    def vertex_colors(self) -> Optional[npt.NDArray[np.float32]]:
        """N x 3 sRGB colours in [0, 1], or None."""
    @property
    def summary(self) -> Optional[dict[str, Any]]:
        """The summary of the run that made it: {"mesh": {vertices, faces, topology, silhouette_iou, ...},
        "colouring", "texture", "timings", "total_seconds", "written"} (docs/server.md lists the fields);
        None for a mesh read from a file."""
    def save(self, path: PathLike, *, texture_format: Literal["png", "jpg"] = "png") -> None:
        """Writes GLB, OBJ or PLY by the extension, atomically."""

class Result:
    """What ``generate`` made."""
    @property
    def mesh(self) -> Mesh: ...
    @property
    def intermediates(self) -> dict[str, npt.NDArray[np.float32]]:
        """With keep_intermediates: every stage's images by their path in the intermediates folder
        without the extension, e.g. "views/front_normal"; float32 in [0, 1]. Empty otherwise."""
    @property
    def summary(self) -> dict[str, Any]:
        """Precision, per stage (seconds, peak memory, resumed), total, the mesh's summary."""

def reconstruct(views: Union[PathLike, ViewSet], *, output: Optional[PathLike] = None, faces: Optional[int] = None,
                colour: Literal["texture", "vertex"] = "texture", texture_size: Optional[int] = None,
                texture_format: Literal["png", "jpg"] = "png", coarse_steps: Optional[int] = None,
                refine_steps: Optional[int] = None, silhouette_fit: bool = True, normal_space: Optional[Literal["world", "camera"]] = None,
                previews: bool = False, official_scale: bool = False, progress: Progress = None,
                cancel: Optional[CancelToken] = None) -> Mesh:
    """ISOMER: a mesh from four views, as ``unique3d reconstruct`` makes it.

    views: a views folder or a ViewSet. faces: the final face count (default 40000 with a texture, the
    mesh as reconstructed with vertex colours). texture_size: texels per side (default 2048; texture
    only). coarse_steps, refine_steps: the two optimisation stages' steps (default: their schedules).
    silhouette_fit: False never fits the mesh to the visual hull of the masks (--no-silhouette-fit).
    normal_space: of a folder's normal maps (default "world"). output: also write the mesh file (and,
    with previews, <stem>_views.png and <stem>_turntable.png), after everything else succeeded.
    """

def generate(image: Union[PathLike, ImageArray, Any], *, models: PathLike, output: Optional[PathLike] = None,
             seed: Optional[int] = None, steps: Optional[int] = None,
             dtype: Optional[Literal["auto", "fp32", "bf16", "fp16"]] = None, refine: bool = True,
             keep_intermediates: Union[None, bool, PathLike] = None, from_intermediates: Optional[PathLike] = None,
             multiview_size: Optional[int] = None, refine_size: Optional[int] = None,
             normal_size: Optional[int] = None, faces: Optional[int] = None,
             colour: Literal["texture", "vertex"] = "texture", texture_size: Optional[int] = None,
             texture_format: Literal["png", "jpg"] = "png", coarse_steps: Optional[int] = None,
             refine_steps: Optional[int] = None, silhouette_fit: bool = True, official_scale: bool = False, progress: Progress = None,
             cancel: Optional[CancelToken] = None) -> Result:
    """The whole method, as ``unique3d generate``: a photo to a mesh.

    image: a PNG/JPEG path, an H x W x 3 or 4 array (uint8 or float32 in [0, 1]) or a PIL image
    (grey and palette images are converted to RGB, or RGBA when they have transparency).
    models: the model folder (docs/models.md). seed: of the diffusion noise (default 1145, the
    official app's). steps: denoising steps of the multi-view and normal models (default 30 each).
    dtype: precision of the networks (default: the CPU's). refine: False resizes the views instead of
    refining them. keep_intermediates: True keeps every stage's images in Result.intermediates, a path
    also writes them there. multiview_size, refine_size, normal_size: the networks' working sizes
    (defaults 256, 1024, 512: what the models were trained at). The other options as for reconstruct.
    """

def render(mesh: Union[Mesh, PathLike], *, resolution: int = 512, ssaa: int = 2,
           normal_space: Literal["world", "camera"] = "world", flat: bool = False, normalize: bool = True,
           fill: float = 0.9) -> dict[str, npt.NDArray[np.float32]]:
    """The four canonical views of a mesh, as ``unique3d render`` draws them (without writing files):
    {"front_rgb", "front_normal", "right_rgb", ...}, each H x W x 4 float32 in [0, 1] (sRGB colour or the
    normal encoded as (n + 1) / 2; alpha = coverage). normalize: centre the mesh and scale its longest side
    to [-fill, fill] first. The lists [d[v + "_rgb"] for v in views] and [d[v + "_normal"] ...] make a
    ViewSet."""

def load_mesh(path: PathLike) -> Mesh:
    """Reads a GLB, glTF, OBJ or PLY file."""

def evaluate(pred: Union[Mesh, PathLike], gt: Union[Mesh, PathLike], *, normalize: bool = True,
             appearance: bool = True, surface_samples: int = 100000, seed: int = 0) -> dict[str, Any]:
    """Metrics of a predicted mesh against ground truth (Chamfer, F-score, volume IoU, PSNR/SSIM), the
    document ``unique3d eval --json`` writes (docs/evaluation.md)."""

def doctor(models: PathLike, *, load: bool = False) -> dict[str, Any]:
    """The machine as the networks see it and the check of every network of a model folder, as
    ``unique3d doctor`` reports them; load=True loads every network for real."""

def read_image(path: PathLike) -> npt.NDArray[np.float32]:
    """A PNG or JPEG file as an H x W x C float32 array in [0, 1], as the library reads it."""
