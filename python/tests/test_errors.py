"""Bad input raises luxtally.SceneError with exactly the CLI's one-line message (what
`luxtally run` prints after `luxtally: `), from a file and from the same dict."""

import sys

import pytest

import luxtally
from conftest import SCENES

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOM = """
[materials.wall]
reflectance = 0.5
[[objects]]
shape = "box"
min = [0, 0, 0]
max = [4, 4, 3]
material = "wall"
[[lights]]
type = "point"
position = [2, 2, 2.5]
intensity_cd = 100
[[receivers]]
name = "floor"
corner = [0.5, 0.5, 0.01]
u = [3, 0, 0]
v = [0, 3, 0]
cells = [4, 4]
"""

# Each case: the room with one line replaced (old → new), or lines added.
BAD = {
    "unknown key": ("reflectance = 0.5", "reflectance = 0.5\nshine = 1"),
    "negative reflectance": ("reflectance = 0.5", "reflectance = -0.1"),
    "reflectance over one": ("reflectance = 0.5", "reflectance = 0.8\ntransmittance = 0.5"),
    "string for a number": ("reflectance = 0.5", 'reflectance = "half"'),
    "unknown material": ('material = "wall"', 'material = "steel"'),
    "short vector": ("max = [4, 4, 3]", "max = [4, 4]"),
    "empty box": ("max = [4, 4, 3]", "max = [0, 4, 3]"),
    "unknown shape": ('shape = "box"', 'shape = "cone"'),
    "key of another shape": ("min = [0, 0, 0]", "min = [0, 0, 0]\nradius = 2"),
    "unknown light type": ('type = "point"', 'type = "laser"'),
    "negative intensity": ("intensity_cd = 100", "intensity_cd = -5"),
    "two amounts": ("intensity_cd = 100", "intensity_cd = 100\nflux_lm = 10"),
    "zero cells": ("cells = [4, 4]", "cells = [0, 4]"),
    "parallel u and v": ("v = [0, 3, 0]", "v = [6, 0, 0]"),
    "missing receiver name": ('name = "floor"', ""),
    "not finite": ("intensity_cd = 100", "intensity_cd = nan"),
    "missing mesh": ('shape = "box"\nmin = [0, 0, 0]\nmax = [4, 4, 3]', 'file = "nope.obj"'),
    "duplicate receiver": ("cells = [4, 4]", 'cells = [4, 4]\n[[receivers]]\nname = "floor"\ncorner = [0, 0, 1]\nu = [1, 0, 0]\nv = [0, 1, 0]\ncells = [2, 2]'),
}


def scene_text(case):
    old, new = BAD[case]
    assert old in ROOM, case
    return ROOM.replace(old, new, 1)


def cli_message(cli, path):
    out = cli("run", path, "--photons", 1000, "--out", path.parent / "out", "--quiet", check=False)
    assert out.returncode == 1, out.stderr
    line = out.stderr.strip()
    assert line.startswith("luxtally: ") and "\n" not in line, line
    return line[len("luxtally: "):]


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_scene_raises_scene_error_with_the_cli_message(cli, tmp_path, case):
    path = tmp_path / "bad.toml"
    path.write_text(scene_text(case))
    expected = cli_message(cli, path)
    with pytest.raises(luxtally.SceneError) as from_file:
        luxtally.Scene.load(path)
    assert str(from_file.value) == expected
    document = tomllib.loads(scene_text(case))
    with pytest.raises(luxtally.SceneError) as from_dict:
        luxtally.Scene.from_dict(document, base_dir=tmp_path, origin=str(path))
    assert str(from_dict.value) == expected


def test_syntax_error_names_line_and_column(cli, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(ROOM.replace("reflectance = 0.5", "reflectance = 0.5.1"))
    expected = cli_message(cli, path)
    with pytest.raises(luxtally.SceneError) as e:
        luxtally.Scene.load(path)
    assert str(e.value) == expected and "line 3" in expected


def test_missing_file_raises_scene_error(cli, tmp_path):
    path = tmp_path / "absent.toml"
    expected = cli_message(cli, path)
    with pytest.raises(luxtally.SceneError) as e:
        luxtally.Scene.load(path)
    assert str(e.value) == expected


@pytest.mark.parametrize(
    "flag, kwargs",
    [
        (["--target", "receiver:nowhere"], {"target": "receiver:nowhere"}),
        (["--target-error", "-1"], {"target_error": -1.0}),
        (["--time-limit", "0"], {"time_limit": 0.0}),
        (["--backend", "nope"], {"backend": "nope"}),
    ],
)
def test_bad_run_options_raise_the_cli_message(cli, tmp_path, flag, kwargs):
    path = tmp_path / "room.toml"
    path.write_text(ROOM)
    out = cli("run", path, "--out", tmp_path / "out", "--quiet", *flag, check=False)
    assert out.returncode != 0
    with pytest.raises(luxtally.SceneError) as e:
        luxtally.Scene.load(path).run(photons=1000, **kwargs)
    if flag[0] == "--backend":
        # clap refuses it before the engine sees it: the engine's own message.
        assert "unknown backend `nope`" in str(e.value)
    else:
        assert "luxtally: " + str(e.value) == out.stderr.strip()


def test_a_value_without_toml_form_names_its_key():
    with pytest.raises(luxtally.SceneError, match=r"materials\.wall\.reflectance"):
        luxtally.Scene.from_dict({"materials": {"wall": {"reflectance": object()}}})


def test_numpy_arrays_and_scalars_read_as_lists_and_numbers():
    import numpy as np

    document = tomllib.loads(ROOM)
    document["receivers"][0]["cells"] = np.array([4, 4])
    document["receivers"][0]["u"] = np.array([3.0, 0.0, 0.0])
    document["materials"]["wall"]["reflectance"] = np.float32(0.5)
    scene = luxtally.Scene.from_dict(document)
    assert scene.receivers == ["floor"]
    assert scene.to_dict()["receivers"][0]["cells"] == [4, 4]
