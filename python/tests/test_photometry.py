"""luxtally.Photometry reads the bundled IES file as `luxtally photometry` does."""

import numpy as np
import pytest

import luxtally
from conftest import SCENES

IES = SCENES / "photometry" / "examp1.ies"


def test_photometry_prints_what_the_cli_prints(cli, tmp_path):
    p = luxtally.Photometry.load(IES)
    out = cli("photometry", IES, "--out", tmp_path / "cli.png")
    lines = out.stdout.strip().splitlines()
    assert lines[:-1] == p.summary_lines()
    p.polar_png(tmp_path / "py.png")
    assert (tmp_path / "py.png").read_bytes() == (tmp_path / "cli.png").read_bytes()


def test_intensities_and_flux_agree():
    p = luxtally.Photometry.load(IES)
    assert p.flux_lm > 0 and p.peak_cd > 0
    c = np.array([[0.0, 90.0], [180.0, 270.0]])
    gamma = np.full_like(c, 30.0)
    cd = p.intensities_cd(c, gamma)
    assert cd.shape == c.shape
    assert cd[0, 1] == p.intensity_cd(90.0, 30.0)
    assert np.all(cd <= p.peak_cd)


def test_a_missing_file_raises_scene_error(tmp_path):
    with pytest.raises(luxtally.SceneError):
        luxtally.Photometry.load(tmp_path / "none.ies")
