"""luxtally: forward Monte Carlo photon tracing that tallies light on scene surfaces
and virtual receivers, and reports, forecasts and controls its own statistical error.

    import luxtally
    scene = luxtally.Scene.load("scenes/office.toml")
    result = scene.run(photons=1_000_000, seed=1)
    print(result.receivers["desk"].values.mean())

The engine is the same crate as the ``luxtally`` command: same seed and photons give
the same numbers, bit for bit. See docs/python.md.
"""

from ._luxtally import (
    LuxtallyError,
    Photometry,
    Scene,
    SceneError,
    __version__,
    backends,
)
from ._luxtally import merge as _merge
from ._result import Receiver, Result

__all__ = [
    "LuxtallyError",
    "Photometry",
    "Receiver",
    "Result",
    "Scene",
    "SceneError",
    "backends",
    "merge",
    "__version__",
]


def merge(dirs, scene=None, threads=None):
    """The shards' checkpoints in ``dirs`` (each the ``checkpoint=`` directory of a
    ``Scene.run(shard="I/N", ...)``) merged into the run they split, as
    ``luxtally merge`` does: the same numbers as one unsharded run. ``scene`` is a
    ``Scene`` (as ``set`` left it) or a scene file's path (default: the one the shards
    recorded); it must be the scene the shards ran."""
    if scene is not None and not isinstance(scene, Scene):
        scene = str(scene)
    return _merge([str(d) for d in dirs], scene, threads)
