"""Resume and shards: the same numbers as one uninterrupted, unsharded run (as the
CLI's --resume, --shard and merge)."""

import pytest

import luxtally
from conftest import SCENES, assert_same_bits, summary_arrays

OFFICE = SCENES / "office.toml"


def test_resume_goes_on_to_the_whole_run_s_bits(tmp_path):
    scene = luxtally.Scene.load(OFFICE)
    # A finished run grown to more photons continues bit for bit when it ended on a
    # chunk boundary (a multiple of 4096 photons: docs/distributed.md, "Exactness").
    scene.run(photons=50 * 4096, seed=11, checkpoint=tmp_path)
    resumed = scene.run(photons=500_000, seed=11, resume=tmp_path)
    whole = scene.run(photons=500_000, seed=11)
    assert_same_bits(resumed.receivers["desk"].values, whole.receivers["desk"].values)
    assert resumed.photons == 500_000


def test_shards_merged_give_the_unsharded_bits_and_the_cli_s(cli, tmp_path):
    scene = luxtally.Scene.load(OFFICE)
    dirs = [tmp_path / f"shard{i}" for i in range(3)]
    for i, d in enumerate(dirs):
        scene.run(photons=300_000, seed=12, shard=f"{i}/3", checkpoint=d)
    merged = luxtally.merge(reversed(dirs), scene=OFFICE)
    whole = scene.run(photons=300_000, seed=12)
    assert_same_bits(merged.receivers["desk"].values, whole.receivers["desk"].values)
    assert_same_bits(merged.receivers["desk"].sigma, whole.receivers["desk"].sigma)
    cli("merge", *dirs, "--out", tmp_path / "cli")
    assert_same_bits(merged.receivers["desk"].values, summary_arrays(tmp_path / "cli", "desk", "values"))
    # The loaded scene itself, and the one the shards recorded, give the same run.
    for given in (scene, None):
        again = luxtally.merge(dirs, scene=given)
        assert_same_bits(again.receivers["desk"].values, whole.receivers["desk"].values)


def test_shards_merged_with_another_scene_are_refused(tmp_path):
    scene = luxtally.Scene.load(OFFICE)
    dirs = [tmp_path / f"shard{i}" for i in range(2)]
    for i, d in enumerate(dirs):
        scene.run(photons=100_000, seed=3, shard=f"{i}/2", checkpoint=d)
    scene.set("materials.wall.reflectance", 0.6)
    with pytest.raises(luxtally.SceneError, match="another scene"):
        luxtally.merge(dirs, scene=scene)


def test_a_shard_needs_a_checkpoint_directory():
    with pytest.raises(luxtally.SceneError, match="checkpoint"):
        luxtally.Scene.load(OFFICE).run(photons=300_000, shard="0/2")


def test_resume_refuses_a_changed_scene(tmp_path):
    scene = luxtally.Scene.load(OFFICE)
    scene.run(photons=100_000, seed=1, checkpoint=tmp_path)
    scene.set("materials.wall.reflectance", 0.6)
    with pytest.raises(luxtally.SceneError):
        scene.run(photons=200_000, seed=1, resume=tmp_path)
