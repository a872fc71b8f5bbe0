"""Planning campaigns: the file format and its errors, runs derived from (seed, index), the
statistics, and the Dask runner on real clusters (a local cluster with two worker processes;
a scheduler and a worker started as separate processes), with a killed worker, an interrupted
campaign resumed, and a run reproduced alone."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from app.campaign import report, runner, store
from app.cli import app
from missions import campaign as cm
from missions import schema

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent

HOLD_MISSION = """
format_version = 1
name = "campaign-test-hold"
description = "test: hold the tree for a few seconds"

[setup]
params = "model-scale"
depth_m = 100.0
feedback = "ekf"
seed = 0

[setup.current]
speed_mps = 0.02
direction_deg = 45.0

[[legs]]
type = "hold"
duration_s = {duration}
score = true
"""

DOCK_MISSION = """
format_version = 1
name = "campaign-test-dock"
description = "test: a short model-scale landing"

[setup]
params = "model-scale"
depth_m = 100.0
feedback = "ekf"
seed = 0

[setup.current]
speed_mps = 0.02
direction_deg = 45.0

[setup.docking_frame]
center_ne_m = [1.0, 1.0]
heading_deg = 0.0
landing_depth_m = 101.5

[[legs]]
type = "hold"
duration_s = 3.0

[[legs]]
type = "dock"
hover_m = 0.1
lower_rate_mps = 0.03
align_tolerance_m = 0.05
settle_s = 3.0
timeout_s = 300.0
score = true
"""


def write_campaign(folder: Path, body: str, mission: str = HOLD_MISSION, duration=3.0) -> Path:
    (folder / "base.toml").write_text(mission.replace("{duration}", str(duration)))
    path = folder / "campaign.toml"
    path.write_text('format_version = 1\nname = "test"\nmission = "base.toml"\n' + body)
    return path


# ------------------------------------------------------------------------------------------
# the file format
# ------------------------------------------------------------------------------------------

BAD_CAMPAIGNS = [
    # (body after the three first lines, words the one-line error must hold)
    (
        "[grid]\ncurrent_speed_mps = [0.1, 4.0]\n",
        ["line 5", "grid.current_speed_mps", "[0, 3] m/s"],
    ),
    ("runs_per_point = 0\n", ["line 4", "runs_per_point", "[1, 100000]"]),
    ("seed = -1\n", ["line 4", "seed", "[0, 4294967295]"]),
    (
        '[random.tree_mass_scale]\ndistribution = "uniform"\nlow = 0.5\nhigh = 9.0\n',
        ["line 7", "random.tree_mass_scale.high", "[0.1, 5]"],
    ),
    (
        '[random.depth_m]\ndistribution = "normal"\nmean = 2.0\nstd = 1.0\n',
        ["line 6", "random.depth_m.mean", "[6, 4000] m"],
    ),
    (
        '[random.current_direction_deg]\ndistribution = "uniform"\nlow = 90.0\nhigh = 10.0\n',
        ["line 7", "random.current_direction_deg.high", ">= low"],
    ),
    (
        '[random.wind_speed]\ndistribution = "uniform"\nlow = 0.5\nhigh = 9.0\n',
        ["line 4", "random.wind_speed", "unknown parameter", "current_speed_mps"],
    ),
    (
        '[random.allocation]\ndistribution = "choice"\nvalues = ["pinv", "magic"]\n',
        ["line 6", "random.allocation.values", "pinv, priority, qp"],
    ),
    (
        '[random.params]\ndistribution = "uniform"\nlow = 0.0\nhigh = 1.0\n',
        ["line 5", "random.params.distribution", "choice"],
    ),
    ("[[cases]]\ntree_weight_scale = 7.0\n", ["line 5", "cases[1].tree_weight_scale", "[0.1, 5]"]),
    ("[grid]\nsurvey_error_north_m = [0.1]\n", ["line 5", "survey_error_north_m", "docking frame"]),
    ('[grid]\nparams = ["no-such-set"]\n', ["line 5", "grid.params", "full-scale, model-scale"]),
    (
        '[random.current_speed_mps]\ndistribution = "gauss"\n',
        ["line 4", "random.current_speed_mps", "uniform", "normal", "choice"],
    ),
    ("[grid]\ncurrent_speed_mps = 0.3\n", ["line 5", "grid.current_speed_mps", "list"]),
    ("runs_per_point = 2\nrunz = 3\n", ["line 5", "runz", "not permitted"]),
    ("[grid\n", ["cannot parse", "line 4"]),
]


@pytest.mark.parametrize(("body", "words"), BAD_CAMPAIGNS)
def test_a_malformed_campaign_gives_one_line_naming_the_line_field_and_range(tmp_path, body, words):
    path = write_campaign(tmp_path, body)
    with pytest.raises(cm.CampaignError) as err:
        cm.load_campaign(path)
    message = str(err.value)
    assert "\n" not in message, message
    assert message.startswith(str(path)), message
    for word in words:
        assert word in message, (word, message)


def test_the_cli_prints_the_error_without_a_traceback(tmp_path):
    path = write_campaign(tmp_path, "[grid]\ncurrent_speed_mps = [0.1, 4.0]\n")
    result = CliRunner().invoke(app, ["campaign", str(path), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert result.output.strip() == (
        f"error: {path} line 5: grid.current_speed_mps: value 2 must be in [0, 3] m/s (got 4.0)"
    )
    assert not (tmp_path / "o").exists()


def test_a_missing_base_mission_is_named(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('format_version = 1\nname = "t"\nmission = "no-such-mission"\n')
    with pytest.raises(cm.CampaignError, match=r"line 3: mission: unknown mission 'no-such"):
        cm.load_campaign(path)


def test_the_library_campaigns_load():
    names = cm.library_names()
    assert {"thesis-table-4.2", "full-docking-vs-current", "model-sea-trial-vs-current"} <= set(
        names
    )
    for name in names:
        campaign, base, _ = cm.load_campaign(name)
        assert campaign.runs >= 1 and base.legs
    table, _, _ = cm.load_campaign("thesis-table-4.2")
    # the nine cases of thesis table 4.2, one change at a time
    changes = {tuple(sorted(case.items())) for case in table.cases}
    assert len(changes) == 9
    assert (("tree_weight_scale", 0.5),) in changes and (("tree_mass_scale", 1.5),) in changes
    current, _, _ = cm.load_campaign("full-docking-vs-current")
    assert current.grid["current_speed_mps"] == [0.1, 0.2, 0.3, 0.4, 0.5]
    sea, base, _ = cm.load_campaign("model-sea-trial-vs-current")
    assert base.name == "sea-trial-appendix-c"
    assert min(sea.grid["current_speed_mps"]) == 0.014
    assert max(sea.grid["current_speed_mps"]) == 0.1


# ------------------------------------------------------------------------------------------
# runs from (seed, index)
# ------------------------------------------------------------------------------------------


def test_points_run_over_cases_and_grid_last_key_fastest(tmp_path):
    path = write_campaign(
        tmp_path,
        "runs_per_point = 2\n[grid]\ndepth_m = [50.0, 80.0]\n"
        'allocation = ["pinv", "priority", "qp"]\n'
        "[[cases]]\ntree_mass_scale = 0.5\n[[cases]]\ntree_weight_scale = 1.5\n",
    )
    c, base, _ = cm.load_campaign(path)
    assert (c.points, c.runs) == (12, 24)
    # point 8 = case 2 (8 // 6), then depth 50 (2 // 3 = 0), then qp (2 % 3 = 2)
    inputs = cm.run_inputs(c, base, 2 * 8 + 1)
    assert (inputs.point, inputs.repetition) == (8, 1)
    assert inputs.values["tree_weight_scale"] == 1.5
    assert inputs.values["tree_mass_scale"] == 1.0  # the base mission's
    assert (inputs.values["depth_m"], inputs.values["allocation"]) == (50.0, "qp")


def test_a_run_derives_from_seed_and_index_alone(tmp_path):
    body = (
        "seed = 11\nruns_per_point = 50\n"
        '[random.current_speed_mps]\ndistribution = "uniform"\nlow = 0.0\nhigh = 0.1\n'
        '[random.sensor_noise_scale]\ndistribution = "normal"\nmean = 1.0\nstd = 2.0\n'
        "min = 0.5\nmax = 2.0\n"
    )
    c, base, _ = cm.load_campaign(write_campaign(tmp_path, body))
    a = [cm.run_inputs(c, base, i) for i in range(50)]
    assert cm.run_inputs(c, base, 37) == a[37]  # alone, without the others
    assert len({x.sim_seed for x in a}) == 50
    noise = [float(x.values["sensor_noise_scale"]) for x in a]
    assert min(noise) >= 0.5 and max(noise) <= 2.0
    assert any(v == 0.5 for v in noise) and any(v == 2.0 for v in noise)  # std 2: clipped
    # the same file with another seed draws other values
    c2, _, _ = cm.load_campaign(write_campaign(tmp_path, body.replace("seed = 11", "seed = 12")))
    assert cm.run_inputs(c2, base, 37).values != a[37].values
    with pytest.raises(cm.CampaignError, match="0 to 49"):
        cm.run_inputs(c, base, 50)


def test_uniform_draws_cover_their_range_evenly(tmp_path):
    body = (
        "runs_per_point = 4000\n"
        '[random.current_direction_deg]\ndistribution = "uniform"\nlow = 100.0\nhigh = 200.0\n'
    )
    c, base, _ = cm.load_campaign(write_campaign(tmp_path, body))
    draws = np.array(
        [cm.run_inputs(c, base, i).values["current_direction_deg"] for i in range(c.runs)]
    )
    assert draws.min() >= 100.0 and draws.max() <= 200.0
    # mean of U(100, 200) is 150, its standard error 100/sqrt(12 n) = 0.46: 4 sigma = 1.8
    assert abs(draws.mean() - 150.0) < 1.8


def test_a_runs_values_go_into_its_mission_and_parameter_set(tmp_path):
    body = (
        "[[cases]]\ndepth_m = 60.0\nsurvey_error_north_m = 0.2\nsensor_noise_scale = 3.0\n"
        "kd_scale = 0.5\ncurrent_speed_mps = 0.07\n"
    )
    c, base, _ = cm.load_campaign(write_campaign(tmp_path, body, DOCK_MISSION))
    inputs, mission, sim = cm.prepare_run(c, base, 0)
    f = mission.setup.docking_frame
    assert mission.setup.depth_m == 60.0
    assert f is not None and f.landing_depth_m == pytest.approx(61.5)  # clearance kept
    assert f.survey_error_ne_m == [0.2, 0.0]
    assert mission.setup.current.speed_mps == 0.07
    assert mission.setup.seed == inputs.sim_seed
    plain = schema.load_mission(tmp_path / "base.toml")
    from sim import params

    ps = params.load(plain.setup.params)
    assert sim.ps.sensors.position.noise_std == pytest.approx(3.0 * ps.sensors.position.noise_std)
    assert sim.ps.gains.kd == pytest.approx([0.5 * g for g in ps.gains.kd])
    assert sim.ps.gains.kp == pytest.approx(ps.gains.kp)


# ------------------------------------------------------------------------------------------
# statistics
# ------------------------------------------------------------------------------------------


def test_wilson_interval_closed_forms():
    z2 = cm.Z95**2
    # no success in n: [0, z^2 / (n + z^2)]; all successes: [n / (n + z^2), 1]
    assert cm.wilson_interval(0, 10) == pytest.approx((0.0, z2 / (10 + z2)))
    assert cm.wilson_interval(10, 10) == pytest.approx((10 / (10 + z2), 1.0))
    # 8 of 10: (0.4902, 0.9433), the textbook example (Newcombe 1998, method 3)
    assert cm.wilson_interval(8, 10) == pytest.approx((0.4902, 0.9433), abs=1e-4)
    lo, hi = cm.wilson_interval(3, 20)
    assert cm.wilson_interval(17, 20) == pytest.approx((1 - hi, 1 - lo))


def _rows(spec):
    rows = []
    for params, depth, current, ok, n in spec:
        rows += [
            {
                "params": params,
                "depth_m": depth,
                "current_speed_mps": current,
                "success": k < ok,
            }
            for k in range(n)
        ]
    return rows


def test_envelope_is_the_largest_current_up_to_which_95_percent_succeed():
    rows = _rows(
        [
            ("full-scale", 100.0, 0.1, 20, 20),
            ("full-scale", 100.0, 0.2, 19, 20),  # 95 %: still inside
            ("full-scale", 100.0, 0.3, 18, 20),  # 90 %: outside
            ("full-scale", 100.0, 0.4, 20, 20),  # inside again, but beyond a failing current
            ("full-scale", 400.0, 0.1, 20, 20),
            ("full-scale", 400.0, 0.2, 20, 20),
            ("model-scale", 100.0, 0.1, 10, 20),
        ]
    )
    env = {(e.params, e.depth_m): e for e in report.envelope(rows)}
    assert env[("full-scale", 100.0)].largest_mps == 0.2
    assert env[("full-scale", 400.0)].largest_mps == 0.2
    assert "all tested" in env[("full-scale", 400.0)].verdict()
    assert env[("model-scale", 100.0)].largest_mps is None
    assert "below 95 % from the lowest" in env[("model-scale", 100.0)].verdict()


def test_the_report_writes_its_tables_and_figure(tmp_path):
    path = write_campaign(
        tmp_path, "runs_per_point = 20\n[grid]\ncurrent_speed_mps = [0.1, 0.2, 0.3]\n"
    )
    c, base, _ = cm.load_campaign(path)
    rows = []
    for i in range(c.runs):
        row = cm.input_row(cm.run_inputs(c, base, i))
        ok = {0: 20, 1: 19, 2: 12}[row["point"]] > row["repetition"]
        rows.append(
            {**row, **dict.fromkeys(cm.OUTCOMES), "success": ok, "landed": None}
            | {"diverged": False, "simulated_s": 3.0}
        )
    rep = report.make_report(c, rows, tmp_path)
    assert (rep.overall.successes, rep.overall.runs) == (51, 60)
    assert [e.largest_mps for e in rep.envelope] == [0.2]
    text = (tmp_path / "report.md").read_text()
    lo, hi = cm.wilson_interval(19, 20)
    assert f"95.0 % [{100 * lo:.1f}, {100 * hi:.1f}]" in text
    assert (
        "| model-scale | 100 | up to 0.2 m/s | 0.1: 20/20 (84-100 %); 0.2: 19/20 (76-99 %); "
        in text
    )
    assert rep.figure is not None and rep.figure.stat().st_size > 10_000


def test_failure_causes_come_from_the_row():
    base = {"simulated_s": 100.0, "diverged": False, "timed_out": False, "landed": None}
    assert report.failure_cause({**base, "simulated_s": None, "error": "ValueError: x"}) == (
        "run raised: ValueError"
    )
    assert report.failure_cause({**base, "diverged": True, "error": ""}) == "diverged"
    missed = {**base, "landed": False, "rests_on": "posts", "error": ""}
    assert report.failure_cause(missed) == "landing: a funnel missed its post"
    fast = {**base, "landed": False, "rests_on": "frame", "error": ""}
    assert report.failure_cause(fast) == "landing: too fast"
    refused = {**base, "error": "leg 2 (dock) failed: not feasible in 0.494 m/s"}
    assert report.failure_cause(refused) == "leg failed: leg # (dock) failed: not feasible in # m/s"
    table = report.failure_table(
        [{**missed, "success": False, "saturated_time_s": 80.0, "max_thruster_utilisation": 1.0}]
        + [{**base, "success": True, "saturated_time_s": 2.0, "max_thruster_utilisation": 0.5}]
    )
    assert table[0][:3] == ["landing: a funnel missed its post", "1", "80"]
    assert table[-1][:3] == ["(succeeded)", "1", "2"]


def test_random_currents_are_binned_for_the_envelope():
    values = [0.1 + 0.4 * k / 99 for k in range(100)]
    lv = report.levels(values)
    assert len(set(lv)) == report.BINS
    assert min(lv) == pytest.approx(0.1 + 0.4 / 16) and max(lv) == pytest.approx(0.5 - 0.4 / 16)


# ------------------------------------------------------------------------------------------
# Dask: a local cluster, a separate scheduler and worker, a killed worker, resume and rerun
# ------------------------------------------------------------------------------------------


class Interrupt(Exception):
    pass


@pytest.fixture(scope="module")
def local_cluster():
    """A local cluster of two single-threaded worker processes, shared by the tests that need
    no embedded one (starting a cluster takes seconds)."""
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        yield cluster


def test_local_cluster_of_two_processes_interrupt_and_resume(tmp_path, local_cluster):
    path = write_campaign(tmp_path, "runs_per_point = 8\nseed = 5\n", duration=4.0)
    c, base, text = cm.load_campaign(path)
    out = tmp_path / "results"
    seen: list[dict] = []

    def stop_after_three(row, client):
        seen.append(row)
        if len(seen) == 3:
            raise Interrupt

    with pytest.raises(Interrupt):
        runner.run_campaign(
            c, base, text, out, workers=2, show_progress=False, on_row=stop_after_three, batch=1
        )
    first = store.read_rows(out)
    assert sorted(r["run"] for r in first) == sorted(r["run"] for r in seen)
    # a second start without --resume refuses to mix into the results
    with pytest.raises(cm.CampaignError, match="--resume"):
        runner.run_campaign(c, base, text, out, workers=2, show_progress=False)
    before = set((out / store.RUNS_DIR).glob("*.parquet"))
    p = runner.run_campaign(
        c,
        base,
        text,
        out,
        scheduler=local_cluster.scheduler_address,
        show_progress=False,
        resume=True,
    )
    new_parts = set((out / store.RUNS_DIR).glob("*.parquet")) - before
    resumed = sorted(r["run"] for part in new_parts for r in store.pq.read_table(part).to_pylist())
    assert resumed == sorted(set(range(8)) - {r["run"] for r in first})  # only the missing
    rows = store.read_rows(out)
    assert [r["run"] for r in rows] == list(range(8))
    assert p.done == 8 and p.failed == 0
    assert all(r["success"] and r["simulated_s"] == pytest.approx(4.0, abs=0.05) for r in rows)
    workers = {r["worker"] for r in rows}
    assert len(workers) >= 2  # two worker processes ran them
    assert cm.worker_name() not in workers  # none in this process
    # same inputs give the same figures, whichever process ran them
    again = cm.run_one(c, base, 5)
    assert cm.same_figures(again, rows[5])
    assert not cm.same_figures(again, {**rows[5], "rms_east_m": rows[5]["rms_east_m"] * 1.01})


def test_a_killed_workers_runs_are_retried_and_counted_once(tmp_path, local_cluster):
    # runs of 600 simulated s (some 0.2 s each): a 60 s run took 20 ms once the loop got
    # fast, and the other worker had often finished by the time the first row came back
    path = write_campaign(tmp_path, "runs_per_point = 4\nseed = 9\n", duration=600.0)
    c, base, text = cm.load_campaign(path)
    killed: dict[str, object] = {}

    def kill_a_busy_worker(row, client):
        if killed:
            return
        for _ in range(100):  # the scheduler may not have handed out the next run yet
            for address, keys in client.processing().items():
                if keys:
                    pid = client.run(os.getpid, workers=[address])[address]
                    killed.update(pid=pid, keys=list(keys))
                    os.kill(pid, signal.SIGKILL)
                    return
            time.sleep(0.01)

    p = runner.run_campaign(
        c,
        base,
        text,
        tmp_path / "out",
        scheduler=local_cluster.scheduler_address,
        show_progress=False,
        on_row=kill_a_busy_worker,
        batch=1,
    )
    rows = store.read_rows(tmp_path / "out")
    assert killed, "no worker was busy to kill"
    lost_runs = {int(str(k).rsplit("-", 1)[1]) for k in killed["keys"]}
    assert [r["run"] for r in rows] == list(range(4))
    assert p.done == 4
    parts = list((tmp_path / "out" / store.RUNS_DIR).glob("*.parquet"))
    total = sum(store.pq.read_table(part).num_rows for part in parts)
    assert total == 4  # nothing written twice
    for r in rows:
        assert r["success"] and r["error"] == ""
        if r["run"] in lost_runs:  # ran again, in another process
            assert r["worker"] != f"{r['worker'].split(':')[0]}:{killed['pid']}"


@pytest.fixture
def dask_cluster(tmp_path):
    """A scheduler and one worker, each its own process (as on a real cluster)."""
    sched_file = tmp_path / "scheduler.json"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    procs = [
        subprocess.Popen(
            [str(BIN / "dask"), "scheduler", "--scheduler-file", str(sched_file), "--port", "0"]
            + ["--no-dashboard"],
            cwd=ROOT,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    ]
    try:
        deadline = time.monotonic() + 60
        while not sched_file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(
            subprocess.Popen(
                [str(BIN / "dask"), "worker", "--scheduler-file", str(sched_file)]
                + ["--nthreads", "1", "--no-nanny", "--no-dashboard"],
                cwd=ROOT,
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(1, timeout=60)
        yield address
    finally:
        for proc in reversed(procs):  # single processes (no nanny): nothing is left behind
            proc.kill()
            proc.wait(timeout=20)


def test_scheduler_option_runs_on_a_separate_cluster_and_rerun_reproduces(tmp_path, dask_cluster):
    path = write_campaign(
        tmp_path,
        "runs_per_point = 2\nseed = 4\n"
        '[random.current_direction_deg]\ndistribution = "uniform"\nlow = 0.0\nhigh = 90.0\n',
        DOCK_MISSION,
    )
    out = tmp_path / "results"
    cli = CliRunner()
    result = cli.invoke(
        app,
        ["campaign", str(path), "--out", str(out), "--scheduler", dask_cluster, "--no-progress"],
    )
    assert result.exit_code == 0, result.output
    assert "2/2 runs have rows" in result.output
    rows = store.read_rows(out)
    assert [r["run"] for r in rows] == [0, 1]
    assert all(r["landings"] == 1 and r["miss_m"] is not None for r in rows)
    assert cm.worker_name() not in {r["worker"] for r in rows}
    assert (out / "envelope.png").is_file() and "Wilson" in (out / "report.md").read_text()
    # one run again, alone, here, with its log
    log = tmp_path / "run1.mcap"
    again = cli.invoke(app, ["campaign", "rerun", str(out), "1", "--log", str(log), "--json"])
    assert again.exit_code == 0, again.output
    answer = json.loads(again.output)
    assert answer["reproduced"] is True
    assert answer["figures"]["miss_m"] == rows[1]["miss_m"]
    assert answer["figures"]["rms_north_m"] == rows[1]["rms_north_m"]
    from app.recording import load_session

    rec = load_session(log)
    assert rec.complete
    assert rec.t_s[-1] == pytest.approx(rows[1]["simulated_s"], abs=0.05)
    # a run that is not there is named
    missing = cli.invoke(app, ["campaign", "rerun", str(out), "7"])
    assert missing.exit_code == 2 and "run 7 has no row" in missing.output
    assert "0 to 1" in missing.output
    # and the report regenerates from the folder alone
    rep = cli.invoke(app, ["campaign", "report", str(out)])
    assert rep.exit_code == 0 and "Wilson" in rep.output


def test_a_rerun_differs_when_its_stored_figures_were_changed(tmp_path):
    """The rerun's check compares real figures: a stored row that is not what the run gives
    is reported as not reproduced (exit 1)."""
    path = write_campaign(tmp_path, "runs_per_point = 1\n", duration=2.0)
    c, base, text = cm.load_campaign(path)
    out = tmp_path / "r"
    store.create(out, text, base, resume=False)
    row = cm.run_one(c, base, 0)
    row["rms_north_m"] = row["rms_north_m"] + 1e-6
    writer = store.PartWriter(out)
    writer.add(row)
    writer.close()
    result = CliRunner().invoke(app, ["campaign", "rerun", str(out), "0"])
    assert result.exit_code == 1
    assert "DIFFERS" in result.output and "NOT reproduced" in result.output
    assert math.isfinite(row["rms_north_m"])


def _worker_settings(dask_worker) -> tuple[str | None, bool, float]:
    """The worker's trim threshold, whether it samples its tasks' stacks, and how often its
    event loop's tick runs [ms]."""
    return (
        os.environ.get("MALLOC_TRIM_THRESHOLD_"),
        "profile" in dask_worker.periodic_callbacks,
        dask_worker.periodic_callbacks["tick"].callback_time,
    )


def test_the_embedded_clusters_workers_run_without_the_profiler_trim_threshold_or_fast_tick(
    monkeypatch,
):
    """Dask's defaults (a stack sample every 10 ms, glibc told to hand back freed memory above
    64 KiB, the event loop's tick every 20 ms) cost a campaign worker some 15 % in all
    (runner.LOCAL_WORKER_CONFIG); a worker the nanny starts again after a crash must get the
    same settings, and this process keeps Dask's."""
    import dask

    # a nanny with Dask's settings exports the threshold into its own process too, and every
    # process started later inherits it: an earlier test's cluster in this process did so in
    # a full run (a user's own setting is kept the same way, as Dask keeps it)
    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    client, cluster = runner._cluster_client(None, 1)
    try:
        assert list(client.run(_worker_settings).values()) == [(None, False, 1000.0)]
        client.restart()
        assert list(client.run(_worker_settings).values()) == [(None, False, 1000.0)]
    finally:
        client.close()
        cluster.close()
    assert dask.config.get("distributed.worker.profile.enabled") is True
    assert dask.config.get("distributed.admin.tick.interval") == "20ms"
    assert dask.config.get("distributed.nanny.pre-spawn-environ")["MALLOC_TRIM_THRESHOLD_"] == 65536


# the embedded cluster's blocks and workers


def test_blocks_shrink_to_single_runs_so_the_workers_finish_together():
    todo = list(range(200))
    blocks = runner.shrinking_blocks(todo, 2)
    assert [i for b in blocks for i in b] == todo  # every run once, in order
    sizes = [len(b) for b in blocks]
    assert sizes[0] == cm.MAX_RUNS_PER_TASK  # 200 / (2 x 2) = 50, capped
    assert sizes == sorted(sizes, reverse=True)
    # each block is the runs left over twice the workers, rounded up: 32, 32, 32, 26, ...
    assert sizes[:6] == [32, 32, 32, 26, 20, 15]
    assert sizes[-4:] == [1, 1, 1, 1]
    # a few runs on many workers: one run a task
    assert runner.shrinking_blocks([7, 8, 9], 4) == [[7], [8], [9]]
    assert runner.shrinking_blocks([], 2) == []


def _probe() -> object:
    return getattr(cm, "_parent_only_probe", None)


@pytest.mark.skipif(runner.LOCAL_START_METHOD != "fork", reason="no fork on this system")
def test_embedded_cluster_workers_are_forked_from_the_calling_process(monkeypatch):
    """A value set in this process at run time, never imported, reaches the workers only if
    they are forks of it (a spawned worker imports ``missions.campaign`` afresh)."""
    from distributed import Client

    monkeypatch.setattr(cm, "_parent_only_probe", 4711, raising=False)
    with runner.local_cluster(1) as address, Client(address) as client:
        assert client.submit(_probe, pure=False).result() == 4711
