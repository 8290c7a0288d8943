"""What happens while a run works: the progress callback, the GIL released, the thread
count, warnings."""

import threading
import time
import warnings

import numpy as np
import pytest

import tptd
from conftest import assert_same, assert_valid, ring


def test_progress_receives_stages_and_fractions(scan):
    calls = []
    m = tptd.mesh(scan, 120.3, quality=True, check=True,
                  progress=lambda stage, f: calls.append((stage, f)))
    assert_valid(m)
    stages = [s for s, f in calls if f == 0.0]
    assert stages[:2] == ["meshing", "improving elements"]
    assert "checking the mesh" in stages
    assert ("meshing", 1.0) in calls
    fractions = [f for s, f in calls if s == "meshing"]
    assert fractions == sorted(fractions)


def test_an_exception_of_progress_is_raised_after_the_run(scan):
    def stop(stage, f):
        raise KeyError(stage)

    with pytest.raises(KeyError, match="meshing"):
        tptd.mesh(scan, 120.3, progress=stop)


def test_the_gil_is_released_while_meshing():
    img = ring((100, 100, 90), np.float32)
    ticks, stop = [], threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    t0 = time.perf_counter()
    m = tptd.mesh(img, 120.3, 180.7, threads=1, check=True)
    t1 = time.perf_counter()
    stop.set()
    t.join()
    assert t1 - t0 > 0.2, "too fast to tell"
    during = [x for x in ticks if t0 + 0.05 < x < t1 - 0.05]
    # with the GIL held the thread would not run at all during the call
    assert len(during) > 0.2 * (t1 - t0 - 0.1) / 0.001
    assert_valid(m)


def test_threads_are_honoured_and_change_nothing(scan):
    one = tptd.mesh(scan, 120.3, 180.7, threads=1)
    two = tptd.mesh(scan, 120.3, 180.7, threads=2)
    assert one.info["threads"] == 1 and two.info["threads"] == 2
    assert_same(one, two)


def test_warnings_are_issued_and_reported(scan):
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m = tptd.mesh(scan, 120)
    lines = [str(x.message) for x in w if issubclass(x.category, tptd.MeshWarning)]
    assert lines and lines == m.info["warnings"]
    assert lines[0].startswith("volume: alpha 120 equals the value of")


def gyroid(n=36):
    x, y, z = np.mgrid[:n, :n, :n] * 0.35
    g = np.sin(x) * np.cos(y) + np.sin(y) * np.cos(z) + np.sin(z) * np.cos(x)
    return g.astype(np.float32)


def test_ctrl_c_stops_a_run_and_raises_keyboard_interrupt():
    import _thread

    img = gyroid()
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", tptd.MeshWarning)
        whole = tptd.mesh(img, -0.3013, 0.2987, quality=True)
    took = time.perf_counter() - t0
    assert took > 0.5, "too fast to interrupt"
    # Interrupted a quarter of the way in, whatever the machine's speed.
    at = 0.25 * took
    timer = threading.Timer(at, _thread.interrupt_main)
    t0 = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        tptd.mesh(img, -0.3013, 0.2987, quality=True)
    stopped = time.perf_counter() - t0
    timer.join()
    assert stopped < at + 0.5 * took, (stopped, took)
    # the next run is not affected
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", tptd.MeshWarning)
        again = tptd.mesh(img, -0.3013, 0.2987, quality=True)
    assert np.array_equal(again.cells_dict["tetra"], whole.cells_dict["tetra"])
