"""Runs behave as Python expects: the GIL is free while a search runs, Ctrl-C cancels it and
raises KeyboardInterrupt, the limits stop it with an incomplete result, progress is reported."""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest

import linkspace
from conftest import urdf

# A two-dimensional continuum at a fine precision: minutes of work unless stopped.
LONG = urdf("five_bar.urdf")
LONG_PRECISION = 1e-5


@pytest.fixture
def sigint() -> Iterator[None]:
    """SIGINT as an interactive Python has it (a parent may have set it to be ignored)."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_ctrl_c_cancels_a_run_and_raises_keyboard_interrupt(sigint: None) -> None:
    m = linkspace.load(LONG)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        m.solve(precision=LONG_PRECISION)
    elapsed = time.monotonic() - start
    timer.join()
    # The run would take minutes; cancelled, it stops within the kernel's cancel latency.
    assert elapsed < 20, elapsed
    # The mechanism still answers afterwards.
    assert m.solve(precision=1e-2, max_boxes=50).completeness.reason == "boxes"


def test_timeout_stops_a_run_with_an_incomplete_result() -> None:
    start = time.monotonic()
    r = linkspace.load(LONG).solve(precision=LONG_PRECISION, timeout=0.3)
    assert time.monotonic() - start < 20
    assert not r.completeness and r.completeness.reason == "time" and r.completeness.limit == "time"
    assert str(r.completeness) == "incomplete (time)"
    assert r.to_dict()["status"] == "incomplete" and r.to_dict()["limit"] == "time"
    assert len(r.undecided) > 0


def test_max_boxes_and_max_memory_are_the_cli_limits() -> None:
    m = linkspace.load(LONG)
    r = m.solve(precision=LONG_PRECISION, max_boxes=200)
    assert r.completeness.reason == "boxes" and r.to_dict()["stats"]["processed"] == 200
    assert r.to_dict()["settings"]["max_boxes"] == 200
    # Breadth first (two threads), the pending boxes of a fine cover outgrow one MiB quickly.
    r = m.solve(precision=LONG_PRECISION, max_memory=1, max_boxes=10_000_000, timeout=120, threads=2)
    assert r.to_dict()["settings"]["max_memory"] == 1 << 20
    assert r.completeness.reason == "memory"


def test_load_options_are_defaults_of_every_question() -> None:
    m = linkspace.load(LONG, max_boxes=100)
    assert m.solve(precision=LONG_PRECISION).to_dict()["stats"]["processed"] == 100
    assert m.solve(precision=LONG_PRECISION, max_boxes=150).to_dict()["stats"]["processed"] == 150
    with pytest.raises(TypeError):
        linkspace.load(LONG, kind="cusps")


def test_the_gil_is_released_while_a_search_runs() -> None:
    ticks = 0
    stop = threading.Event()

    def count() -> None:
        nonlocal ticks
        while not stop.is_set():
            ticks += 1
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    try:
        start = time.monotonic()
        linkspace.load(LONG).solve(precision=LONG_PRECISION, timeout=1.0)
        elapsed = time.monotonic() - start
    finally:
        stop.set()
        t.join()
    # Held by the run (one call into the extension for the whole second), the GIL would let the
    # counter tick once or twice; released, it ticks about once per millisecond, fewer on a
    # loaded machine but still dozens.
    assert elapsed >= 0.9 and ticks > 20, (elapsed, ticks)


def test_progress_is_reported_and_a_failing_callback_stops_the_run() -> None:
    seen: list[linkspace.Progress] = []
    linkspace.load(LONG).solve(precision=LONG_PRECISION, timeout=1.0, progress=seen.append)
    assert seen and all(isinstance(p, linkspace.Progress) for p in seen)
    assert all(p.processed >= 0 and p.pending >= 0 for p in seen)
    assert [p.processed for p in seen] == sorted(p.processed for p in seen)

    class Stop(Exception):
        pass

    def stop(p: linkspace.Progress) -> None:
        raise Stop

    start = time.monotonic()
    with pytest.raises(Stop):
        linkspace.load(LONG).solve(precision=LONG_PRECISION, progress=stop)
    assert time.monotonic() - start < 20


def test_threads_give_the_same_boxes() -> None:
    m = linkspace.load(urdf("double_butterfly.urdf"))
    one = m.solve(fix={"joint6": 1.1760052070951352}, precision=1e-4)
    two = m.solve(fix={"joint6": 1.1760052070951352}, precision=1e-4, threads=2)
    # The same cells, whatever order the threads finish them in.
    def rows(r: linkspace.SolveResult) -> list[tuple[float, ...]]:
        return sorted(tuple(row) for row in np.hstack([r.boxes.lo, r.boxes.hi]).tolist())

    assert len(one.boxes) == 6 and rows(one) == rows(two)


def test_progress_true_draws_the_clis_line_without_tqdm(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    monkeypatch.setitem(sys.modules, "tqdm", None)  # as if tqdm were not installed
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    r = linkspace.load(LONG).solve(precision=LONG_PRECISION, timeout=0.5, progress=True)
    err = capsys.readouterr().err
    assert r.completeness.reason == "time"
    assert "% decided," in err and "boxes processed" in err and err.endswith("\n")
