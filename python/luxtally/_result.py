"""``luxtally.Result``: a run's numbers (what summary.json holds) with each receiver's
per-cell values as numpy arrays shaped like its grid: ``[j, i]`` is cell i along u,
j along v (summary.json's index ``j * cells[0] + i``)."""

from . import _luxtally


class Receiver:
    """One receiver's result. Arrays are ``cells[1] × cells[0]``: ``values`` (lx or
    cd/m²), ``sigma`` (absolute standard error, NaN where unknown), ``hits``
    (photon crossings scored), ``direct`` and ``direct_sigma`` (the direct light's
    part, None when the estimator has none), ``vov``, ``dof`` (effective degrees of
    freedom), ``scoring_histories``, ``upper_bound`` (dark cells' bound), ``reliable``
    and ``dark`` (flags). ``summary`` holds the rest of the
    receiver's summary.json entry (mean, rel_error, figures, ...)."""

    def __init__(self, name, summary, arrays):
        self.name = name
        self.summary = summary
        self.values = arrays["values"]
        self.sigma = arrays["sigma"]
        self.hits = arrays["hits"]
        self.direct = arrays["direct"]
        self.direct_sigma = arrays["direct_sigma"]
        self.vov = arrays["vov"]
        self.upper_bound = arrays["upper_bound"]
        self.dof = arrays["dof"]
        self.scoring_histories = arrays["scoring_histories"]
        self.reliable = arrays["reliable"]
        self.dark = arrays["dark"]

    @property
    def mean(self):
        """The receiver's mean value over its cells (summary.json's ``mean``)."""
        return self.summary["mean"]

    @property
    def mean_sigma(self):
        """The mean's standard error (figures.mean_sigma), in the receiver's unit;
        NaN when unknown."""
        sigma = self.summary["figures"]["mean_sigma"]
        return float("nan") if sigma is None else sigma

    @property
    def rel_error(self):
        """The mean's relative error: ``{"arithmetic": ..., "quadratic": ...}``."""
        return self.summary["rel_error"]

    @property
    def unit(self):
        """lx or cd/m²."""
        return self.summary["unit"]

    @property
    def quantity(self):
        return self.summary["quantity"]

    @property
    def cells(self):
        """``(along u, along v)``, as the scene file's ``cells``."""
        return tuple(self.summary["cells"])

    def __repr__(self):
        return (
            f"Receiver({self.name!r}: {self.cells[0]}×{self.cells[1]} cells, "
            f"mean {self.mean:.4g} {self.unit})"
        )


class Result:
    """A run's result: ``Scene.run``, ``luxtally.merge`` or ``Result.load``."""

    def __init__(self, summary, arrays, handle=None):
        self.summary = summary
        self._handle = handle
        #: Seconds of the summary's statistics after the run (what the CLI computes
        #: for summary.json), and of handing them to Python (arrays, dict); None for
        #: a result read back from files.
        self.summary_s = None
        self.transfer_s = None
        self.receivers = {
            name: Receiver(name, summary["receivers"][name], a) for name, a in arrays.items()
        }

    @staticmethod
    def load(out_dir):
        """A CLI run's outputs read back from ``out_dir`` (its summary.json); such a
        result has no tallies: ``save`` and ``scene_map`` need a run's."""
        return _luxtally.load_result(str(out_dir))

    @property
    def stop_reason(self):
        """Why the run stopped: photons, time, target_error, min_hits, interrupted,
        unreachable or decided."""
        return self.summary["stop_reason"]

    @property
    def photons(self):
        return self.summary["photons_emitted"]

    @property
    def seed(self):
        return self.summary["seed"]

    @property
    def forecast(self):
        """The error target's forecast (dict), None without a target."""
        return self.summary["forecast"]

    @property
    def history(self):
        """One dict per epoch: elapsed_s, photons, rel_error, forecast_s, ..."""
        return self.summary["history"]

    @property
    def timings(self):
        """Seconds: the set-up (BVH, pilot), the photon pass, and its parts."""
        s = self.summary
        keys = ("setup_s", "elapsed_s", "stats_s", "merge_s", "direct_s")
        return {k: s[k] for k in keys}

    @property
    def global_map(self):
        """summary.json's ``global``: the scene map's mean and errors."""
        return self.summary["global"]

    def save(self, out_dir, outputs=None):
        """Writes the outputs ``luxtally run --out out_dir`` writes (summary.json,
        receivers' EXR/CSV/PNG, scene_map.ply, report.html, indirect_map.bin);
        ``outputs`` as ``--outputs`` (e.g. ``"receivers"``; default all)."""
        self._needs_tallies("save")
        self._handle.save(str(out_dir), outputs)

    def scene_map(self):
        """The scene map as arrays: ``vertices`` (n × 3, world m), ``triangles``
        (m × 3), per triangle ``illuminance_lx``, ``indirect_lx`` and ``rel_error``
        (1 where unknown, as in scene_map.ply)."""
        self._needs_tallies("scene_map")
        return self._handle.scene_map()

    def to_dataframe(self):
        """One row per receiver cell: receiver, i, j, value, sigma, hits, direct,
        reliable (pandas, an optional dependency)."""
        try:
            import pandas as pd
        except ImportError as e:
            raise ImportError("to_dataframe needs pandas: pip install pandas") from e
        import numpy as np

        frames = []
        for name, r in self.receivers.items():
            rows, cols = r.values.shape
            j, i = np.indices((rows, cols))
            data = {
                "receiver": name,
                "i": i.ravel(),
                "j": j.ravel(),
                "value": r.values.ravel(),
                "sigma": r.sigma.ravel(),
                "hits": r.hits.ravel(),
                "reliable": r.reliable.ravel(),
            }
            if r.direct is not None:
                data["direct"] = r.direct.ravel()
            frames.append(pd.DataFrame(data))
        return pd.concat(frames, ignore_index=True)

    def _needs_tallies(self, what):
        if self._handle is None:
            raise _luxtally.LuxtallyError(
                f"{what}: a result read back from summary.json has no tallies"
            )

    def __repr__(self):
        return (
            f"Result({self.summary['scene']!r}: {self.photons} photons, stopped on "
            f"{self.stop_reason}, receivers {list(self.receivers)})"
        )
