"""The progress display of ``Scene.run(progress=True)``: a tqdm bar where tqdm is
installed, else one line rewritten on stderr. Called on the calling thread."""

import sys


def default_bar():
    try:
        from tqdm import tqdm
    except ImportError:
        return _Line()
    return _Tqdm(tqdm)


def _describe(p):
    error = p["rel_error"]
    goal = p["target_error"]
    text = f"error {100 * error:.3f} %"
    if goal is not None:
        text += f" → {100 * goal:.3f} %"
    if p["forecast_s"] is not None:
        text += f", forecast {p['forecast_s']:.1f} s"
    return text


class _Line:
    def __call__(self, p):
        end = "\n" if p["stop_reason"] else ""
        stopped = f", stopped on {p['stop_reason']}" if p["stop_reason"] else ""
        sys.stderr.write(
            f"\r{p['elapsed_s']:.1f} s  {p['photons']} photons  {_describe(p)}{stopped}"
            + end
        )
        sys.stderr.flush()


class _Tqdm:
    def __init__(self, tqdm):
        self._tqdm = tqdm
        self._bar = None

    def __call__(self, p):
        if self._bar is None:
            self._bar = self._tqdm(total=p["max_photons"], unit="photon", unit_scale=True)
        self._bar.n = p["photons"]
        self._bar.set_postfix_str(_describe(p), refresh=True)
        if p["stop_reason"]:
            self._bar.close()
