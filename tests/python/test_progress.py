"""Progress and cancellation: every stage reaches the callback, a raising callback, a CancelToken from
another thread and Ctrl-C each stop the run, and nothing is written."""
import os
import re
import signal
import threading
import time

import pytest

import unique3d
from conftest import EXAMPLE, FAST


def stage_names(events):
    return [e.text for e in events if e.kind == "stage_begin"]


def test_callback_gets_every_stage(cli_glb, tmp_path):
    events = []
    out = tmp_path / "spot.glb"
    unique3d.reconstruct(EXAMPLE, output=out, progress=events.append, **FAST)
    # The CLI prints "[unique3d] <stage> ..." as each stage begins: the same stages, in the same order.
    cli_stages = re.findall(r"^\[unique3d\] (.*) \.\.\.$", cli_glb[1], flags=re.M)
    py_stages = stage_names(events)
    assert len(py_stages) >= 5
    assert [s.split(" ")[0] if s.startswith("writing ") else s for s in py_stages] == [
        s.split(" ")[0] if s.startswith("writing ") else s for s in cli_stages
    ]
    assert py_stages[-1] == f"writing {out}"
    # Each stage ends once, after it began; steps count up within their loop, with a time left.
    ends = [e.text for e in events if e.kind == "stage_end"]
    assert sorted(ends) == sorted(py_stages)
    assert all(e.seconds >= 0 for e in events if e.kind == "stage_end")
    steps = [e for e in events if e.kind == "step"]
    assert steps and all(1 <= e.step <= e.steps and e.seconds_left >= 0 for e in steps)
    assert any(e.step == e.steps == 40 for e in steps)  # the coarse stage's 40 steps


class Stop(Exception):
    pass


def test_raising_callback_cancels_and_writes_nothing(tmp_path):
    out = tmp_path / "spot.glb"
    raised_at = []

    def callback(event):
        if event.kind == "step":
            raised_at.append(time.monotonic())
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        unique3d.reconstruct(EXAMPLE, output=out, previews=True, progress=callback, **FAST)
    # It stopped at its next check, long before the run's end, and wrote neither mesh nor previews.
    assert len(raised_at) == 1 and time.monotonic() - raised_at[0] < 1.0
    assert list(tmp_path.iterdir()) == []


def run_until_first_step(start_stopping, **kwargs):
    """Starts a long reconstruction; start_stopping() is called from another thread once it is in its
    loops. Returns the exception the run ended with and the seconds from start_stopping() to the end."""
    started = threading.Event()
    stopped_at = []

    def stopper():
        started.wait(60)
        stopped_at.append(time.monotonic())
        start_stopping()

    thread = threading.Thread(target=stopper)
    thread.start()
    try:
        with pytest.raises(BaseException) as caught:
            unique3d.reconstruct(EXAMPLE, progress=lambda e: e.kind == "step" and started.set(), **kwargs)
        ended = time.monotonic()
    finally:
        started.set()
        thread.join()
    return caught.value, ended - stopped_at[0]


def test_cancel_from_another_thread_within_a_second(tmp_path):
    token = unique3d.CancelToken()
    out = tmp_path / "spot.glb"
    # The default schedule: well over a minute of work.
    error, seconds = run_until_first_step(token.cancel, output=out, cancel=token)
    assert isinstance(error, unique3d.Cancelled) and isinstance(error, unique3d.Error)
    assert str(error) == "cancelled"
    assert seconds < 1.0
    assert token.cancelled and not out.exists()


def test_ctrl_c_stops_the_run(tmp_path):
    out = tmp_path / "spot.glb"
    # Python's own Ctrl-C handler, also where the tests were started in the background by a shell
    # without job control (which starts them with SIGINT ignored, and then Python installs none).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        error, seconds = run_until_first_step(lambda: os.kill(os.getpid(), signal.SIGINT), output=out)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert isinstance(error, KeyboardInterrupt)
    assert seconds < 1.0 and not out.exists()
    # The module still works afterwards.
    assert len(unique3d.reconstruct(EXAMPLE, **FAST).faces) == 5000
