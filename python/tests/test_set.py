"""scene.set changes a material's reflectance or a light's flux and keeps the built
ray casters; the results equal a fresh load of the changed scene, bit for bit."""

import sys

import pytest

import luxtally
from conftest import SCENES, assert_same_bits

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

OFFICE = SCENES / "office.toml"
PHOTONS = 100_000


def fresh(document):
    return luxtally.Scene.from_dict(document, base_dir=SCENES, origin=str(OFFICE))


def same_run(a, b, seed=7):
    ra = a.run(photons=PHOTONS, seed=seed).receivers["desk"]
    rb = b.run(photons=PHOTONS, seed=seed).receivers["desk"]
    assert_same_bits(ra.values, rb.values)
    assert_same_bits(ra.sigma, rb.sigma)
    return ra


def test_set_reflectance_equals_a_fresh_load_and_keeps_the_casters():
    scene = luxtally.Scene.load(OFFICE)
    before = scene.run(photons=PHOTONS, seed=7).receivers["desk"].mean
    assert scene.casters_built == 1
    scene.set("materials.wall.reflectance", 0.8)
    document = tomllib.loads(OFFICE.read_text())
    document["materials"]["wall"]["reflectance"] = 0.8
    after = same_run(scene, fresh(document))
    assert scene.casters_built == 1
    # More light comes back from brighter walls.
    assert after.mean > before


def test_set_light_flux_equals_a_fresh_load():
    scene = luxtally.Scene.load(OFFICE)
    scene.set("lights[0].intensity_cd", 2000)
    document = tomllib.loads(OFFICE.read_text())
    document["lights"][0]["intensity_cd"] = 2000
    same_run(scene, fresh(document))
    assert scene.to_dict()["lights"][0]["intensity_cd"] == 2000


def test_set_refuses_geometry_and_unknown_entries():
    scene = luxtally.Scene.load(OFFICE)
    with pytest.raises(luxtally.SceneError, match="only keys under materials and lights"):
        scene.set("objects[0].max", [7, 5, 3])
    with pytest.raises(luxtally.SceneError, match="no such entry"):
        scene.set("materials.steel.reflectance", 0.5)
    with pytest.raises(luxtally.SceneError, match="not a key path"):
        scene.set("lights[x].flux_lm", 5)


def test_a_bad_value_raises_the_loader_s_message_and_keeps_the_scene():
    scene = luxtally.Scene.load(OFFICE)
    with pytest.raises(luxtally.SceneError, match=r"materials\.wall"):
        scene.set("materials.wall.reflectance", 1.5)
    assert scene.to_dict()["materials"]["wall"]["reflectance"] == 0.5
