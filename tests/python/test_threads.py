# Long calls release the GIL, report progress, and stop on Ctrl-C or a raising callback,
# leaving no files behind.
import _thread
import threading
import time

import knotwork
import pytest

from conftest import CASES

CASE = str(CASES / "square_sinsin.toml")
# Big enough to take a good fraction of a second on this machine class, small enough for CI.
# The direct solver: the case's default (CG with fast diagonalization, exact for this
# separable problem) finishes in 0.15 s when the machine is idle, too short to tell.
BIG = dict(degree=3, elements=192, solver="direct")


def test_a_second_thread_runs_during_a_solve():
    stamps = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            stamps.append(time.perf_counter())
            time.sleep(0.002)

    t = threading.Thread(target=ticker)
    t.start()
    time.sleep(0.05)
    start = time.perf_counter()
    r = knotwork.run(CASE, **BIG)
    end = time.perf_counter()
    stop.set()
    t.join()
    assert end - start > 0.2, "the solve was too short to tell"
    inside = [s for s in stamps if start + 0.05 < s < end - 0.05]
    # With the GIL held the ticker could not run at all inside the call; released, it ticks
    # every 2 ms or so (at least a tenth of that on a loaded machine).
    ideal = (end - start - 0.1) / 0.002
    assert len(inside) > 0.1 * ideal, (len(inside), ideal)
    assert r.dofs == 195 * 195


def test_progress_reports_the_phases():
    seen = []
    knotwork.run(CASE, degree=2, elements=8, progress=seen.append)
    assert any("building the space" in s for s in seen)
    assert "assembly" in seen and "error norms" in seen
    levels = []
    knotwork.converge(CASE, levels=2, progress=levels.append)
    assert any(s.startswith("level 1/2: ") for s in levels) and any(s.startswith("level 2/2: ") for s in levels)


def test_a_raising_callback_stops_the_study_and_writes_nothing(tmp_path):
    class Stop(Exception):
        pass

    def callback(what):
        if what.endswith("assembly"):
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        knotwork.converge(CASE, levels=3, output=tmp_path / "out", progress=callback)
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_ctrl_c_raises_keyboard_interrupt_and_writes_nothing(tmp_path):
    # interrupt_main is what the terminal's Ctrl-C does to the main thread: it sets the
    # signal flag, which the study checks between its phases.
    timer = threading.Timer(0.3, _thread.interrupt_main)
    timer.start()
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        knotwork.converge(CASE, levels=8, degree=3, output=tmp_path / "out")
    timer.cancel()
    assert time.perf_counter() - start < 30  # levels 0..7 would take minutes
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
    # The module is still usable afterwards.
    assert knotwork.run(CASE, degree=2, elements=4).dofs == 36
