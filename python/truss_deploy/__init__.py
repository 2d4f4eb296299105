"""truss_deploy: the truss-deploy simulator from Python (docs/python.md).

    import truss_deploy as td
    r = td.simulate(td.Scene.from_toml("campaigns/scenes/table1.toml"))
    print(r.status, r.deploy_time_s, r.peak_drive_force_N, r.bays.lock_time_s.max())

Scenes are read and checked as truss-sim reads them (the same key table, the same messages: bad
input raises ValueError with truss-sim's message); a run is the same sim::simulate the command line
calls, and a Result carries every field of `truss-sim --json` under the same name (units in the
names, and in run_units / bay_units / history_units). simulate_many runs many scenes on parallel
threads (the GIL released) into a pandas DataFrame, one row per run. Campaign files written by
truss-campaign are read by truss_report.read_campaign (postproc/).
"""
import os as _os

try:
    from . import _core
except ImportError as _e:  # the package folder without its compiled part
    _here = _os.path.dirname(_os.path.abspath(__file__))
    raise ImportError(
        f"truss_deploy: its compiled part _core is not built in {_here} ({_e}); build it with "
        "`cmake --build build --target truss_deploy_core` (scripts/run_main.sh builds the "
        "programs only), then import with PYTHONPATH=build/python") from None
from ._core import (Result, RunStatus, Scene, bay_units, history_units, run_units, scene_keys,
                    simulate)

__version__ = _core.version  # the binaries' version (truss-sim --version)
__git_revision__ = _core.git_revision  # the commit they were built from

__all__ = ["Scene", "Result", "RunStatus", "simulate", "simulate_many", "scene_keys", "run_units",
           "bay_units", "history_units", "__version__"]


def _threads(threads):
    if threads is None:
        return len(_os.sched_getaffinity(0))
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads: must be a positive integer, got {threads!r}")
    return threads


def _override_rows(overrides):
    """(rows as dicts, the inputs as a DataFrame) of a DataFrame (its index kept), a dict of
    columns or a list of dicts (each row its own keys; index: the run number)."""
    import pandas as pd
    if isinstance(overrides, pd.DataFrame):
        return overrides.to_dict("records"), overrides
    if isinstance(overrides, dict):
        frame = pd.DataFrame(overrides)
        rows = frame.to_dict("records")
    else:
        rows = [dict(r) for r in overrides]
        frame = pd.DataFrame(rows)
    return rows, frame.set_axis(pd.RangeIndex(len(rows), name="run"))


def simulate_many(scenes, overrides=None, *, threads=None, bays=True):
    """Runs many scenes on `threads` threads (default: the cores this process may use), the GIL
    released, and returns a pandas DataFrame with one row per run: `status` (categorical, the
    RunStatus names), `message`, every field of the run summary, and with bays=True the per-bay
    fields as `FIELD[bay J]` (the column names of truss_report.read_campaign). Units in
    df.attrs["units"]. No time histories are computed. Each row is the run simulate() gives.

        simulate_many([scene_a, scene_b, ...])
        simulate_many(base, {"mast.n_bays": [10, 20], "drive.speed_m_per_s": [0.1, 0.2]})
        simulate_many(base, overrides_dataframe)   # one column per key, one row per run
        simulate_many(base, [{"mast.n_bays": 10}, {"drive.mode": "motor"}])

    With overrides, each row's keys are set on the base scene as truss-sim's --set sets them, and
    the values appear as `input:KEY` columns (the index is the DataFrame's, if one is given). A
    bad row raises ValueError naming the run and giving truss-sim's message; nothing is returned.
    """
    import pandas as pd
    n_threads = _threads(threads)
    if overrides is None:
        if isinstance(scenes, Scene):
            raise TypeError("simulate_many(scenes): give a list of scenes, or a base scene and the overrides")
        scene_list = list(scenes)
        for i, s in enumerate(scene_list):
            if not isinstance(s, Scene):
                raise TypeError(f"simulate_many(scenes): element {i} is {type(s).__name__} "
                                f"{s!r:.40}, not a Scene (Scene.from_toml(PATH), Scene.table1(), "
                                "scene.with_(...)); or simulate_many(base, overrides)")
        cols = _core.simulate_many_scenes(scene_list, n_threads, bool(bays))
        inputs, index = None, pd.RangeIndex(len(scene_list), name="run")
    else:
        if not isinstance(scenes, Scene):
            raise TypeError("simulate_many(base, overrides): base must be one Scene")
        rows, inputs = _override_rows(overrides)
        cols = _core.simulate_many_settings(scenes, rows, n_threads, bool(bays))
        index = inputs.index
    return _frame(cols, inputs, index)


def _frame(cols, inputs, index):
    import pandas as pd
    units = {}
    data = {}
    if inputs is not None:
        key_units = {k["key"]: k["unit"] for k in scene_keys()}
        for key in inputs.columns:
            data[f"input:{key}"] = inputs[key].to_numpy()
            units[f"input:{key}"] = key_units.get(key, "1")
    data["status"] = pd.Categorical.from_codes(cols.pop("status"), categories=_core.run_status_names)
    units["status"] = units["message"] = "1"
    for name, values in cols.items():
        data[name] = values
        base = name.split("[", 1)[0]
        units[name] = run_units.get(name) or bay_units.get(base, "1")
    # copy=False: the columns are fresh arrays of this call; copying them into consolidated blocks
    # cost 12 us a run (30 bays, 411 columns), more than the simulation's overhead budget.
    df = pd.DataFrame(data, index=index, copy=False)
    df.attrs["units"] = units
    return df
