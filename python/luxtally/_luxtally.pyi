"""Type stubs of the extension module (python/src/); docstrings there and in
docs/python.md."""

from os import PathLike
from typing import Any, Callable, Iterable, Optional, Union

import numpy as np
import numpy.typing as npt

from ._result import Result

StrPath = Union[str, PathLike[str]]
Progress = Callable[[dict[str, Any]], object]

__version__: str

class LuxtallyError(Exception):
    """An error of the engine, with the CLI's one-line message."""

class SceneError(LuxtallyError):
    """Bad input: the file, key path or option at fault, as the CLI names it."""

class Scene:
    """A loaded scene and its ray casters (built once per backend, kept by set)."""

    @staticmethod
    def load(path: StrPath) -> Scene: ...
    @staticmethod
    def from_dict(
        d: dict[str, Any], base_dir: Optional[StrPath] = None, origin: str = "<dict>"
    ) -> Scene: ...
    def set(self, path: str, value: Any) -> None: ...
    def run(
        self,
        *,
        photons: Optional[int] = None,
        time_limit: Optional[float] = None,
        target_error: Optional[float] = None,
        target: Optional[str] = None,
        absolute: bool = False,
        min_hits: Optional[int] = None,
        stop_if_unreachable: bool = False,
        until: Optional[str] = None,
        seed: Optional[int] = None,
        threads: Optional[int] = None,
        estimator: Optional[str] = None,
        backend: Optional[str] = None,
        bvh: Optional[str] = None,
        progress: Union[Progress, bool, None] = None,
        checkpoint: Optional[StrPath] = None,
        checkpoint_every: float = 60.0,
        resume: Optional[StrPath] = None,
        shard: Optional[str] = None,
    ) -> Result: ...
    def to_dict(self) -> dict[str, Any]: ...
    @property
    def name(self) -> str: ...
    @property
    def receivers(self) -> list[str]: ...
    @property
    def materials(self) -> list[str]: ...
    @property
    def triangles(self) -> int: ...
    @property
    def casters_built(self) -> int: ...

class RunHandle:
    """A finished run's tallies (Result.save, Result.scene_map)."""

    def save(self, out: StrPath, outputs: Optional[str] = None) -> None: ...
    def scene_map(self) -> dict[str, npt.NDArray[Any]]: ...

class Photometry:
    """An IES LM-63 or EULUMDAT file, read by the engine's reader."""

    @staticmethod
    def load(path: StrPath) -> Photometry: ...
    @property
    def flux_lm(self) -> float: ...
    @property
    def peak_cd(self) -> float: ...
    @property
    def lamp_flux_lm(self) -> Optional[float]: ...
    @property
    def light_output_ratio(self) -> Optional[float]: ...
    def intensity_cd(self, c_deg: float, gamma_deg: float) -> float: ...
    def intensities_cd(
        self, c_deg: npt.NDArray[np.float64], gamma_deg: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]: ...
    def summary_lines(self) -> list[str]: ...
    def polar_png(self, path: StrPath) -> None: ...

def merge(dirs: Iterable[str], scene: Optional[Union[Scene, str]] = None, threads: Optional[int] = None) -> Result: ...
def load_result(out_dir: str) -> Result: ...
def backends() -> list[str]: ...
