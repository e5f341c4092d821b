from os import PathLike
from typing import Iterable, Optional, Union

from ._luxtally import (
    LuxtallyError as LuxtallyError,
    Photometry as Photometry,
    Scene as Scene,
    SceneError as SceneError,
    __version__ as __version__,
    backends as backends,
)
from ._result import Receiver as Receiver, Result as Result

def merge(
    dirs: Iterable[Union[str, PathLike[str]]],
    scene: Optional[Union[Scene, str, PathLike[str]]] = None,
    threads: Optional[int] = None,
) -> Result: ...
