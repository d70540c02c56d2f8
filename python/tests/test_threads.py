"""The GIL is released while the physics runs; Ctrl-C stops a run; parallel
runs give the same results on any number of threads."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np

import anholonomy
from conftest import REPO, SCENARIOS


def test_another_thread_runs_during_a_long_physics_run(disk):
    # disk_paper settling long enough for seconds of physics on a fast
    # machine (1.2 s per 200 s of settling on CI's, 2.1 s on the laptop's).
    long = disk.replace({"sim.settle": 500.0})
    ticks: list = []
    stop = threading.Event()

    def counter():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    th = threading.Thread(target=counter)
    th.start()
    try:
        t0 = time.perf_counter()
        r = anholonomy.run(long)
        t1 = time.perf_counter()
    finally:
        stop.set()
        th.join()
    # The check below needs a run far longer than a thread's time slice.
    assert r.timings["physics"] >= 1.0, r.timings
    during = [t for t in ticks if t0 <= t <= t1]
    gaps = np.diff([t0] + during + [t1])
    # Holding the GIL, the thread would not tick for the whole run.
    assert gaps.max() < r.timings["physics"] / 4, gaps.max()
    assert len(during) > 100 * (t1 - t0) / 4


# The child installs Python's Ctrl-C handler itself: a process started in
# the background by a non-interactive shell (`cmd &`, as a CI runner may
# start .ci/run) inherits SIGINT ignored, and Python then installs none, so
# the signal would never reach the run.
CHILD = textwrap.dedent(
    """
    import signal, sys, time
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import anholonomy
    s = anholonomy.load(sys.argv[1]).replace({"sim.settle": 1500.0})
    print("started", flush=True)
    t0 = time.perf_counter()
    try:
        anholonomy.run(s)
        print("finished")
    except KeyboardInterrupt:
        print(f"interrupted {time.perf_counter() - t0:.3f}", flush=True)
    r = anholonomy.run(sys.argv[1])
    print("usable", r.passed, flush=True)
    """
)


def test_ctrl_c_interrupts_a_long_run_cleanly():
    p = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(SCENARIOS / "disk_paper.toml")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert p.stdout.readline().strip() == "started"
        time.sleep(1.0)
        sent = time.perf_counter()
        p.send_signal(signal.SIGINT)
        line = p.stdout.readline().split()
        reacted = time.perf_counter() - sent
        assert line[0] == "interrupted", (line, p.stderr.read())
        # 1.5 M steps take far longer than this; the run stopped at a step.
        assert reacted < 2.0, reacted
        assert p.stdout.readline().split() == ["usable", "True"]
        assert p.wait(timeout=60) == 0
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()


PARALLEL = textwrap.dedent(
    """
    import json, sys
    import anholonomy
    names = sys.argv[1:]
    rs = anholonomy.run_many(names)
    print(json.dumps([{k: float(v).hex() for k, v in r.metrics.items()} for r in rs]))
    print(json.dumps([r.sim.q[-1].tolist() for r in rs]))
    """
)

MANY = ["disk_paper", "sphere_triangle_paper", "space_robot_paper", "disk_singular_exact"]


def test_run_many_is_deterministic_on_any_number_of_threads():
    paths = [str(SCENARIOS / f"{n}.toml") for n in MANY]
    outs = []
    for threads in ("1", "2"):
        env = dict(os.environ, RAYON_NUM_THREADS=threads)
        p = subprocess.run(
            [sys.executable, "-c", PARALLEL, *paths], env=env, capture_output=True, text=True, check=True
        )
        outs.append(p.stdout)
    assert outs[0] == outs[1]
    # And the same as one run at a time, in input order.
    metrics = json.loads(outs[0].splitlines()[0])
    for name, m in zip(MANY, metrics):
        r = anholonomy.run(SCENARIOS / f"{name}.toml")
        assert r.name == name
        assert m == {k: float(v).hex() for k, v in r.metrics.items()}


def test_run_many_keeps_going_past_a_failure(disk, tmp_path):
    logs = tmp_path / "logs"
    logs.mkdir()
    # A file where disk_paper's run stages its logs (this process's pid):
    # that run fails at runtime, after the validation pass.
    (logs / f".disk_paper.partial-{os.getpid()}").write_text("in the way")
    other = SCENARIOS / "sphere_triangle_paper.toml"
    rs = anholonomy.run_many([disk, other], logs=logs, return_exceptions=True)
    assert isinstance(rs[0], anholonomy.RuntimeFailure), rs[0]
    assert "writing logs" in str(rs[0])
    assert rs[1].name == "sphere_triangle_paper" and (rs[1].log_dir / "summary.json").is_file()
    (logs / "sphere_triangle_paper" / "summary.json").unlink()
    # Without return_exceptions the failure is raised, after the others ran.
    try:
        anholonomy.run_many([disk, other], logs=logs)
    except anholonomy.RuntimeFailure:
        pass
    else:
        raise AssertionError("no RuntimeFailure")
    assert (logs / "sphere_triangle_paper" / "summary.json").is_file()


def test_two_scenarios_of_one_name_cannot_share_logs(disk, tmp_path):
    try:
        anholonomy.run_many([disk, disk], logs=tmp_path)
    except anholonomy.InputError as e:
        assert e.key == "name"
    else:
        raise AssertionError("no InputError")
    # Without logs they may.
    a, b = anholonomy.run_many([disk, disk])
    assert np.array_equal(a.sim.q, b.sim.q)
