"""Long calls behave: the GIL is released while photons are traced, progress comes on
the calling thread, and Ctrl-C raises KeyboardInterrupt leaving a checkpoint that
resume continues to the uninterrupted run's numbers."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import luxtally
from conftest import SCENES, assert_same_bits

OFFICE = SCENES / "office.toml"


def test_another_thread_progresses_during_a_run():
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    scene = luxtally.Scene.load(OFFICE)
    counter = threading.Thread(target=count)
    counter.start()
    began = time.perf_counter()
    scene.run(photons=1_500_000, seed=1)
    ended = time.perf_counter()
    stop.set()
    counter.join()
    during = [t for t in ticks if began < t < ended]
    # A thread held off by the GIL would not tick at all while the run traces.
    assert len(during) > 0.25 * (ended - began) / 0.001, (len(during), ended - began)


def test_progress_is_called_on_the_calling_thread_after_every_epoch():
    calls = []
    caller = threading.get_ident()
    result = luxtally.Scene.load(OFFICE).run(
        photons=500_000, seed=1, progress=lambda p: calls.append((threading.get_ident(), p))
    )
    assert calls and all(ident == caller for ident, _ in calls)
    assert calls[-1][1]["photons"] == 500_000
    assert calls[-1][1]["stop_reason"] == "photons"
    assert len(calls) == len(result.history)


def test_progress_true_draws_a_bar_or_a_line(capsys):
    luxtally.Scene.load(OFFICE).run(photons=100_000, seed=1, progress=True)
    err = capsys.readouterr().err
    assert "100" in err


def test_an_exception_in_the_callback_stops_the_run_and_propagates():
    def fail(p):
        raise ValueError("enough")

    try:
        luxtally.Scene.load(OFFICE).run(photons=50_000_000, seed=1, progress=fail)
    except ValueError as e:
        assert str(e) == "enough"
    else:
        raise AssertionError("no exception")


CHILD = textwrap.dedent(
    """
    import json, sys, time, luxtally
    scene = luxtally.Scene.load(sys.argv[1])
    seen = []
    def progress(p):
        if not seen:
            print("started", flush=True)
        seen.append(p["photons"])
    try:
        scene.run(photons=10**10, seed=9, checkpoint=sys.argv[2], progress=progress)
    except KeyboardInterrupt:
        print(json.dumps({"interrupted_at": time.time(), "photons": seen[-1]}), flush=True)
        sys.exit(0)
    sys.exit(3)
    """
)


def test_ctrl_c_raises_keyboard_interrupt_and_leaves_a_resumable_checkpoint(tmp_path):
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(OFFICE), str(tmp_path)],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout.readline().strip() == "started"
    time.sleep(1.0)
    sent = time.time()
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=30)
    assert child.returncode == 0, out
    report = json.loads(out.strip().splitlines()[-1])
    # The run stops after the chunks it is tracing (generous: a loaded machine).
    assert report["interrupted_at"] - sent < 3.0
    assert (tmp_path / "checkpoint.bin").exists()
    done = report["photons"]
    total = done + 300_000
    scene = luxtally.Scene.load(OFFICE)
    resumed = scene.run(photons=total, seed=9, resume=tmp_path)
    whole = scene.run(photons=total, seed=9)
    assert resumed.photons == total
    assert_same_bits(resumed.receivers["desk"].values, whole.receivers["desk"].values)
    assert_same_bits(resumed.receivers["desk"].sigma, whole.receivers["desk"].sigma)


CHILD_NO_CHECKPOINT = textwrap.dedent(
    """
    import json, sys, luxtally
    scene = luxtally.Scene.load(sys.argv[1])
    def progress(p):
        if p["photons"] and not getattr(progress, "said", False):
            progress.said = True
            print("started", flush=True)
    try:
        scene.run(photons=10**10, seed=5, progress=progress)
    except KeyboardInterrupt as e:
        print(json.dumps({"message": str(e)}), flush=True)
        sys.exit(0)
    sys.exit(3)
    """
)


def test_ctrl_c_without_a_checkpoint_directory_saves_one_and_names_it():
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD_NO_CHECKPOINT, str(OFFICE)],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert child.stdout.readline().strip() == "started"
    time.sleep(0.5)
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=30)
    assert child.returncode == 0, out
    message = json.loads(out.strip().splitlines()[-1])["message"]
    # "interrupted after N photons; checkpoint saved in DIR: run(..., resume=...) ..."
    photons = int(message.split("interrupted after ")[1].split(" photons")[0])
    folder = message.split("checkpoint saved in ")[1].split(": run(")[0]
    assert os.path.exists(os.path.join(folder, "checkpoint.bin")), message
    total = photons + 200_000
    scene = luxtally.Scene.load(OFFICE)
    resumed = scene.run(photons=total, seed=5, resume=folder)
    whole = scene.run(photons=total, seed=5)
    assert resumed.photons == total
    assert_same_bits(resumed.receivers["desk"].values, whole.receivers["desk"].values)
