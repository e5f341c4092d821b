"""Same scene, seed and photons: the package gives the CLI's numbers, bit for bit."""

import filecmp
import json
import sys

import numpy as np
import pytest

import luxtally
from conftest import SCENES, assert_same_bits, summary_arrays

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

OFFICE = SCENES / "office.toml"
PHOTONS = 200_000


def test_load_and_run_give_the_cli_summary_and_exr_bits(cli, tmp_path):
    result = luxtally.Scene.load(OFFICE).run(photons=PHOTONS, seed=3)
    cli("run", OFFICE, "--photons", PHOTONS, "--seed", 3, "--out", tmp_path / "cli", "--quiet")
    desk = result.receivers["desk"]
    for key in ("values", "sigma", "hits"):
        expected = summary_arrays(tmp_path / "cli", "desk", key).astype(getattr(desk, key).dtype)
        assert_same_bits(getattr(desk, key), expected)
    assert desk.values.shape == (32, 64)
    result.save(tmp_path / "py")
    for name in ("desk.exr", "desk.csv", "desk_figures.csv"):
        assert filecmp.cmp(
            tmp_path / "cli" / "receivers" / name,
            tmp_path / "py" / "receivers" / name,
            shallow=False,
        ), name


def test_from_dict_gives_the_file_bits(tmp_path):
    document = tomllib.loads(OFFICE.read_text())
    from_dict = luxtally.Scene.from_dict(document, base_dir=SCENES)
    from_file = luxtally.Scene.load(OFFICE)
    a = from_dict.run(photons=PHOTONS, seed=5).receivers["desk"]
    b = from_file.run(photons=PHOTONS, seed=5).receivers["desk"]
    assert from_dict.name == "office"
    assert_same_bits(a.values, b.values)
    assert_same_bits(a.sigma, b.sigma)
    assert_same_bits(a.hits, b.hits)


def test_luminaire_scene_gives_the_cli_bits(cli, tmp_path):
    scene = SCENES / "luminaires.toml"
    result = luxtally.Scene.load(scene).run(photons=PHOTONS, seed=2)
    cli("run", scene, "--photons", PHOTONS, "--seed", 2, "--out", tmp_path, "--quiet")
    for name, r in result.receivers.items():
        assert_same_bits(r.values, summary_arrays(tmp_path, name, "values"))


def test_result_load_reads_the_cli_run_back(cli, tmp_path):
    cli("run", OFFICE, "--photons", PHOTONS, "--seed", 4, "--out", tmp_path, "--quiet")
    loaded = luxtally.Result.load(tmp_path)
    desk = loaded.receivers["desk"]
    assert_same_bits(desk.values, summary_arrays(tmp_path, "desk", "values"))
    assert loaded.photons == PHOTONS and loaded.seed == 4
    assert loaded.stop_reason == "photons"
    ran = luxtally.Scene.load(OFFICE).run(photons=PHOTONS, seed=4)
    assert_same_bits(ran.receivers["desk"].values, desk.values)
    assert ran.receivers["desk"].mean == desk.mean


def test_threads_do_not_change_the_bits():
    scene = luxtally.Scene.load(OFFICE)
    one = scene.run(photons=PHOTONS, seed=6, threads=1).receivers["desk"]
    two = scene.run(photons=PHOTONS, seed=6, threads=2).receivers["desk"]
    assert_same_bits(one.values, two.values)


def test_result_carries_the_run_s_record():
    result = luxtally.Scene.load(OFFICE).run(photons=PHOTONS, seed=1, target="receiver:desk")
    assert result.stop_reason == "photons"
    assert len(result.history) >= 1 and result.history[-1]["photons"] == PHOTONS
    assert set(result.timings) == {"setup_s", "elapsed_s", "stats_s", "merge_s", "direct_s"}
    desk = result.receivers["desk"]
    assert desk.reliable.dtype == np.bool_ and desk.reliable.shape == desk.values.shape
    assert 0 < desk.rel_error["arithmetic"] < 1
    # σ is NaN exactly where the cell's error is unknown (no score).
    assert np.isnan(desk.sigma).sum() == desk.summary["unknown_cells"]
    m = result.scene_map()
    assert m["triangles"].shape == (luxtally.Scene.load(OFFICE).triangles, 3)
    assert m["illuminance_lx"].shape == (m["triangles"].shape[0],)
    assert result.transfer_s >= 0 and result.summary_s >= 0


def test_backends_listed_include_embree():
    assert "embree" in luxtally.backends()


def test_obvhs_backend_gives_the_cli_s_obvhs_bits(cli, tmp_path):
    # scripts/test.sh builds both the package and the CLI with the obvhs feature.
    assert "obvhs" in luxtally.backends(), "the package was built without --features obvhs"
    result = luxtally.Scene.load(OFFICE).run(photons=PHOTONS, seed=3, backend="obvhs")
    out = cli("run", OFFICE, "--photons", PHOTONS, "--seed", 3, "--backend", "obvhs",
              "--out", tmp_path, "--quiet", check=False)
    assert out.returncode == 0, (
        f"{out.stderr.strip()} (scripts/test_python.sh builds the CLI with "
        "`cargo build --release --features obvhs` first)"
    )
    assert_same_bits(result.receivers["desk"].values, summary_arrays(tmp_path, "desk", "values"))
    assert result.summary["backend"] == "obvhs"


def test_to_dataframe_has_a_row_per_cell():
    pd = pytest.importorskip("pandas")
    result = luxtally.Scene.load(OFFICE).run(photons=20_000, seed=1)
    frame = result.to_dataframe()
    desk = result.receivers["desk"]
    assert isinstance(frame, pd.DataFrame) and len(frame) == desk.values.size
    row = frame[(frame.i == 5) & (frame.j == 3)].iloc[0]
    assert row.value == desk.values[3, 5] and row.hits == desk.hits[3, 5]


def test_until_decided_stops_as_the_cli_does(cli, tmp_path):
    scene = SCENES / "en12464_office.toml"
    result = luxtally.Scene.load(scene).run(until="decided", photons=2_000_000, seed=1)
    cli("run", scene, "--until", "decided", "--photons", 2_000_000, "--seed", 1,
        "--out", tmp_path, "--quiet", "--outputs", "none")
    # Where it stops depends on the epochs' sizes, which follow the measured rate: only
    # the reason is the same.
    cli_summary = json.loads((tmp_path / "summary.json").read_text())
    assert result.stop_reason == cli_summary["stop_reason"] == "decided"
    assert result.summary["verdicts"]["overall"] == cli_summary["verdicts"]["overall"]
