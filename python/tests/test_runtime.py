"""The module as a long-lived part of a Python program: its version is the binaries', a run's
wall-time cap holds when called from Python (also on simulate_many's threads), the GIL is released
while a run computes (other Python threads go on), and 100,000 calls leave resident memory flat."""
import re
import signal
import subprocess
import sys
import threading
import time
import warnings

import numpy as np

import truss_deploy as td
from conftest import run_cli

# A run far longer than its caps here: 30,000 motor-driven bays at rtol 1e-12 take about 6 s.
LONG = {"drive.mode": "motor", "mast.n_bays": 30000, "run.rtol": 1e-12, "run.atol": 1e-14, "run.max_steps": 10**9}


def long_scene(cap_s):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 30,000 bays is outside the typical range: warned, allowed
        return td.Scene.table1().with_(**LONG, **{"run.max_wall_time_s": cap_s})


def test_version_is_the_binaries(truss_sim):
    rc, out, _ = run_cli(truss_sim, "--version")
    assert rc == 0
    m = re.fullmatch(r"truss-sim (\S+) \((\S+)\)\n", out)
    assert m, out
    assert td.__version__ == m.group(1) and td.__git_revision__ == m.group(2)


def test_wall_time_cap_holds():
    cap = 0.2
    t0 = time.perf_counter()
    r = td.simulate(long_scene(cap))
    elapsed = time.perf_counter() - t0
    assert r.status == td.RunStatus.wall_time_limit and str(r.status) == "wall-time limit"
    assert 0 < r.bays_completed < 30000 and cap <= r.wall_time_s
    assert elapsed < 10 * cap + 1.0  # the cap's check runs between steps; the call ends with the run
    df = td.simulate_many([long_scene(cap), long_scene(2 * cap)], threads=2, bays=False)
    assert list(df["status"]) == ["wall-time limit"] * 2
    assert (df["wall_time_s"] >= [cap, 2 * cap]).all() and (df["bays_completed"] < 30000).all()


def ticks_during(call):
    """How often the main thread ran Python code while `call` ran on another thread, away from the
    call's first and last 50 ms (the GIL changes hands every 5 ms around the call itself)."""
    span, ticks = [], []
    worker = threading.Thread(target=lambda: (span.append(time.perf_counter()), call(),
                                              span.append(time.perf_counter())))
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    return sum(span[0] + 0.05 < t < span[1] - 0.05 for t in ticks)


def test_gil_released_while_running():
    # Held, the GIL would keep this thread from running at all during the 0.15 s runs.
    assert ticks_during(lambda: td.simulate(long_scene(0.15))) > 100
    # (bays=False: the DataFrame of 30,000 bays' columns would take longer to build than the run; the
    # empty call first imports pandas, which would let the main thread run during the call.)
    td.simulate_many([], bays=False)
    assert ticks_during(lambda: td.simulate_many([long_scene(0.15)], threads=1, bays=False)) > 100


def test_ctrl_c_stops_a_batch():
    """SIGINT during simulate_many: KeyboardInterrupt once the runs under way end (each capped at
    0.5 s here), not after the whole batch (40 runs on 2 threads: 10 s)."""
    code = ("import sys, warnings; warnings.simplefilter('ignore'); import truss_deploy as td; "
            f"s = td.Scene.table1().with_(**{LONG!r}, **{{'run.max_wall_time_s': 0.5}}); "
            "td.simulate_many([], bays=False); print('start', flush=True); "
            "td.simulate_many([s] * 40, threads=2, bays=False); print('finished', flush=True)")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline() == "start\n"
    time.sleep(0.3)
    t0 = time.perf_counter()
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    assert p.returncode != 0 and "KeyboardInterrupt" in err and "finished" not in out
    assert time.perf_counter() - t0 < 4.0


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


def test_no_leak_over_100k_calls():
    """100,000 calls (runs, one in 10 with histories, one in 100 also reading the bays and the
    summary dict or failing on a bad setting, one in 1000 a batch on 2 threads); resident memory
    after the first 20,000 (allocator pools warm) and after all must agree within 2 MiB: a leak of
    32 bytes a call would show as 2.4 MiB."""
    s = td.Scene.table1().with_(**{"mast.n_bays": 1, "run.output_step_s": 1.0})

    def calls(n):
        for i in range(n):
            if i % 10 == 0:
                td.simulate(s, histories=True).history["t_s"]
            elif i % 100 == 1:
                r = td.simulate(s)
                r.bays, r.to_dict()
            elif i % 100 == 2:
                try:
                    s.with_(**{"rail.beta_deg": 95})
                except ValueError:
                    pass
            elif i % 1000 == 3:
                td.simulate_many([s] * 20, threads=2)
            else:
                td.simulate(s).peak_drive_force_N

    calls(20_000)
    before = rss_bytes()
    calls(80_000)
    grown = rss_bytes() - before
    assert grown < 2 * 2**20, f"resident memory grew by {grown / 2**20:.1f} MiB over 80,000 calls"
