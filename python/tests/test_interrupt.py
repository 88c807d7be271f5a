"""Ctrl-C: a long fit, CV, diagnosis or plan stops within a second and
raises KeyboardInterrupt (a subprocess gets SIGINT while the library
works); and a progress callback that raises stops the work too."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

import robokrige as rk

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process")

#: Each takes 5–25 s here when not interrupted.
CALLS = {
    "fit": 'rk.ErrorModel(method="ejs-ga").fit(lhs)',
    "cv": "rk.cross_validate(rk.ErrorModel(), lhs, folds=10)",
    "diagnose": 'rk.diagnose(rk.read_campaign(data / "comau_tracker_step.csv"))',
    "plan": 'rk.plan("comau-nj220", 100, campaign=lhs)',
}

# The child installs Python's SIGINT handler itself: Python leaves SIGINT
# ignored when it starts with it ignored, as a shell starts a job in the
# background (`.ci/run &`), and then no Ctrl-C reaches the library.
CHILD = """
import pathlib, signal, sys, time, warnings
signal.signal(signal.SIGINT, signal.default_int_handler)
import robokrige as rk
warnings.simplefilter("ignore")
data = pathlib.Path(sys.argv[1])
lhs = rk.read_campaign(data / "comau_lhs.csv")
print("started", flush=True)
t0 = time.time()
try:
    {call}
except KeyboardInterrupt:
    print("interrupted", time.time(), flush=True)
    raise
print("finished", time.time() - t0, flush=True)
"""


@pytest.mark.parametrize("what", sorted(CALLS))
def test_sigint_stops_a_long_call_within_a_second(what, datasets):
    code = textwrap.dedent(CHILD).format(call=CALLS[what])
    child = subprocess.Popen(
        [sys.executable, "-c", code, str(datasets)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout.readline().strip() == "started"
        time.sleep(1.0)  # well inside the work
        sent = time.time()
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=30)
        exited = time.time()
    finally:
        if child.poll() is None:
            child.kill()
    assert "finished" not in out, f"{what} finished before the signal: {out}"
    stopped = float(out.split("interrupted", 1)[1].split()[0])
    assert "KeyboardInterrupt" in err
    assert child.returncode == -signal.SIGINT or child.returncode not in (0, None), child.returncode
    latency = stopped - sent
    assert latency < 1.0, f"{what}: KeyboardInterrupt {latency:.3f} s after SIGINT"
    assert exited - sent < 2.0


def test_a_raising_progress_callback_stops_the_work(datasets):
    lhs = rk.read_campaign(datasets / "comau_lhs.csv", as_frame=False)
    t0 = time.perf_counter()
    rk.ErrorModel().fit(lhs)
    one_fit = time.perf_counter() - t0
    calls = []

    def stop(done, total, message):
        calls.append(done)
        raise RuntimeError("enough")

    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match="enough"):
        rk.cross_validate(rk.ErrorModel(), lhs, folds=10, progress=stop)
    elapsed = time.perf_counter() - t0
    # the first fold's fit, then the second's search stops at once: not ten
    # fits (the callback is not called again after it raised)
    assert calls == [1]
    assert elapsed < 3 * one_fit + 0.5, (elapsed, one_fit)
