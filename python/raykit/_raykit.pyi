"""Type stubs of the extension module ``raykit._raykit`` (Rust, pyo3).

The public interface is the Python package around it (``raykit``); these
low-level calls take arrays already converted to the dtypes named here.
"""

import os
from typing import Any, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

__version__: str
INVALID_ID: int
MAX_COORDINATE: float

Transform = Tuple[float, float, float, float, float, float]

class Scene:
    """A triangle mesh (geometries concatenated) with its acceleration structure."""

    def __init__(
        self,
        vertices: npt.NDArray[np.float32],
        triangles: npt.NDArray[np.uint32],
        offsets: npt.NDArray[np.uint32],
        accel: str = "bvh8",
        test: str = "moller",
        threads: int = 0,
        structure: Optional[str | os.PathLike[str]] = None,
    ) -> None: ...
    def save(self, path: str | os.PathLike[str]) -> None: ...
    def refit(
        self, vertices: npt.NDArray[np.float32], threads: int = 0, max_degradation: float = 1.5
    ) -> Optional[dict[str, Any]]: ...
    def cast_rays(
        self, rays: npt.NDArray[np.float32], threads: int = 0, width: int = 0
    ) -> Tuple[
        npt.NDArray[np.float32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.float32],
        npt.NDArray[np.float32],
    ]: ...
    def test_occlusions(
        self,
        rays: npt.NDArray[np.float32],
        tnear: float = 0.0,
        tfar: float = ...,
        threads: int = 0,
        width: int = 0,
        moved: Optional[npt.NDArray[np.float64]] = None,
    ) -> npt.NDArray[np.bool_]: ...
    @property
    def num_triangles(self) -> int: ...
    @property
    def accel(self) -> str: ...
    @property
    def test(self) -> str: ...
    def stats(self) -> dict[str, Any]: ...

class InstancedScene:
    """Geometries stored once, placed by instances under a two-level BVH."""

    def __init__(
        self,
        geometries: list[Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], int]],
        instances: list[Tuple[int, npt.NDArray[np.float64], int]],
        threads: int = 0,
    ) -> None: ...
    def cast_rays(
        self, rays: npt.NDArray[np.float32], mask: int = ..., threads: int = 0, width: int = 0
    ) -> Tuple[
        npt.NDArray[np.float32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.float32],
        npt.NDArray[np.float32],
    ]: ...
    def test_occlusions(
        self,
        rays: npt.NDArray[np.float32],
        tnear: float = 0.0,
        tfar: float = ...,
        mask: int = ...,
        threads: int = 0,
        width: int = 0,
        moved: Optional[npt.NDArray[np.float64]] = None,
    ) -> npt.NDArray[np.bool_]: ...
    def count_intersections(
        self, rays: npt.NDArray[np.float32], mask: int = ..., threads: int = 0
    ) -> npt.NDArray[np.int32]: ...
    def list_intersections(
        self, rays: npt.NDArray[np.float32], max_hits: int = ..., mask: int = ..., threads: int = 0
    ) -> Tuple[
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.float32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.float32],
    ]: ...
    @property
    def stored_triangles(self) -> int: ...
    @property
    def placed_triangles(self) -> int: ...

def near_rays(
    rays: npt.NDArray[np.float64],
    shift: npt.ArrayLike,
    centre: npt.ArrayLike,
    radius: float,
) -> Tuple[npt.NDArray[np.float32], Optional[npt.NDArray[np.float64]]]: ...
def closest_points(
    scene: Scene, query_points: npt.NDArray[np.float32], max_distance: float = ..., threads: int = 0
) -> Tuple[
    npt.NDArray[np.float32],
    npt.NDArray[np.uint32],
    npt.NDArray[np.uint32],
    npt.NDArray[np.float32],
    npt.NDArray[np.float32],
    npt.NDArray[np.float32],
]: ...
def distance(scene: Scene, query_points: npt.NDArray[np.float32], threads: int = 0) -> npt.NDArray[np.float32]: ...
def signed_distance(
    scene: Scene, query_points: npt.NDArray[np.float32], threads: int = 0
) -> npt.NDArray[np.float32]: ...
def occupancy(scene: Scene, query_points: npt.NDArray[np.float32], threads: int = 0) -> npt.NDArray[np.float32]: ...
def winding_number(
    scene: Scene, query_points: npt.NDArray[np.float32], beta: float = 2.0, threads: int = 0
) -> npt.NDArray[np.float32]: ...
def count_intersections(scene: Scene, rays: npt.NDArray[np.float32], threads: int = 0) -> npt.NDArray[np.int32]: ...
def list_intersections(
    scene: Scene, rays: npt.NDArray[np.float32], max_hits: int = ..., threads: int = 0
) -> Tuple[
    npt.NDArray[np.uint32],
    npt.NDArray[np.uint32],
    npt.NDArray[np.float32],
    npt.NDArray[np.uint32],
    npt.NDArray[np.uint32],
    npt.NDArray[np.float32],
]: ...
def load_mesh(
    path: str | os.PathLike[str],
) -> Tuple[
    npt.NDArray[np.float32], npt.NDArray[np.uint32], npt.NDArray[np.uint32], Tuple[float, float, float]
]: ...
def load_gltf_instances(
    path: str | os.PathLike[str],
) -> Tuple[
    List[Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32]]],
    List[Tuple[int, npt.NDArray[np.float64], int, str]],
    List[str],
]: ...
def load_dem(
    path: str | os.PathLike[str],
) -> Tuple[npt.NDArray[np.float32], Transform, bool, Optional[float]]: ...
def shadow(
    heights: npt.NDArray[np.float32],
    transform: Transform,
    geographic: bool = False,
    sun: Optional[Tuple[float, float]] = None,
    light: Optional[Tuple[float, float, float]] = None,
    light_elevation: bool = False,
    method: str = "fast",
    threads: int = 0,
    observer: bool = False,
) -> npt.NDArray[np.uint8]: ...
def check_lights(
    heights: npt.NDArray[np.float32],
    transform: Transform,
    lights: Sequence[Tuple[float, float, float]],
    geographic: bool = False,
    light_elevation: bool = False,
    observer: bool = False,
) -> None: ...
def default_views(
    heights: npt.NDArray[np.float32],
    transform: Transform,
    geographic: bool = False,
) -> Tuple[Tuple[float, float, float], Tuple[float, float, float], Tuple[float, float, float]]: ...
def cast(
    heights: npt.NDArray[np.float32],
    transform: Transform,
    eye: Tuple[float, float, float] | list[float],
    target: Tuple[float, float, float] | list[float],
    geographic: bool = False,
    fov: float = 50.0,
    width: int = 1600,
    height: int = 900,
    caster: str = "boxes",
    tau: float = 16.0,
    threads: int = 0,
) -> dict[str, Any]: ...
def render(
    scene: Scene,
    width: int = 800,
    height: int = 600,
    eye: Optional[Tuple[float, float, float]] = None,
    target: Optional[Tuple[float, float, float]] = None,
    up: Tuple[float, float, float] = (0.0, 1.0, 0.0),
    fov: float = 40.0,
    samples_per_pixel: int = 1,
    shadows: bool = True,
    threads: int = 0,
    window: Optional[Tuple[int, int, int, int]] = None,
) -> npt.NDArray[np.uint8]: ...
def write_geotiff(
    path: str | os.PathLike[str],
    values: npt.NDArray[np.uint8] | npt.NDArray[np.float32],
    transform: Optional[Transform] = None,
    geographic: bool = False,
    nodata: Optional[float] = None,
    like: Optional[str | os.PathLike[str]] = None,
) -> None: ...
def cull(
    vertices: npt.NDArray[np.float32],
    triangles: npt.NDArray[np.uint32],
    parts: Optional[npt.NDArray[np.uint32]] = None,
    resolution: int = 128,
    conservative: bool = True,
    threads: int = 0,
) -> Tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_], dict[str, Any]]: ...
