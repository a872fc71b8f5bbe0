"""Runs stepped together (``control.batch``) give what each gives alone: every log row and
every figure, bit for bit (the same arithmetic on the same numbers), whatever else is in the
batch: runs of other missions, of other shapes, a run that diverges or raises."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.campaign import runner
from control.batch import run_together
from control.config import ControlSettings
from control.simulation import Simulation, SimulationDiverged
from missions import campaign as cm
from missions.driver import MissionDriver
from sim import params
from tests.test_same_figures import _short, cases

DOCKING = """format_version = 1
name = "batch-docking"
mission = "full-docking-current-0.3"
seed = 3
runs_per_point = 4

[random.current_speed_mps]
distribution = "uniform"
low = 0.1
high = 0.5

[random.current_direction_deg]
distribution = "uniform"
low = 0.0
high = 360.0
"""


def _drivers(c: cm.Campaign, base, indices) -> list[MissionDriver]:
    return [MissionDriver(*cm.prepare_run(c, base, i)[1:]) for i in indices]


def _same_result(alone, together) -> None:
    assert together.failed == alone.failed
    assert np.array_equal(together.log.data, alone.log.data)
    for name in ("rms_north_m", "rms_east_m", "rms_heading_deg", "max_thruster_utilisation"):
        assert getattr(together, name) == getattr(alone, name), name
    assert [x.miss_m for x in together.landings] == [x.miss_m for x in alone.landings]


def _each_as_alone(runs, steps: int) -> list:
    """Each of ``runs()``'s simulations stepped alone, then fresh ones together: every run's
    rows the same both ways. Returns the rows alone."""
    alone = [sim.step(steps) for sim in runs()]
    together = run_together([sim.step_jobs(steps) for sim in runs()])
    for a, o in zip(alone, together, strict=True):
        assert o.error is None
        assert np.array_equal(o.value.data, a.data)
    return alone


def test_docking_runs_in_one_batch_log_every_row_as_alone():
    c, base = cm.parse_text(DOCKING, "<test>")
    solo = _drivers(c, base, range(4))
    alone = [d.run_to_end() for d in solo]
    drivers = _drivers(c, base, range(4))
    outcomes = run_together([d.run_to_end_jobs() for d in drivers])
    assert all(o.error is None for o in outcomes)
    # the runs differ (their currents; run 0's strong current ends it early, the others
    # land), so a mix-up of slots, or a run held up by another's end, would show
    assert len({a.rms_north_m for a in alone}) == 4
    assert sum(len(a.landings) for a in alone) == 3 and sum(a.failed for a in alone) == 1
    for a, o in zip(alone, outcomes, strict=True):
        _same_result(a, o.value)
    for a, b in zip(solo, drivers, strict=True):  # each simulation is left as alone
        assert b.sim.t_s == a.sim.t_s
        assert np.array_equal(b.sim.plant_state, a.sim.plant_state)
        assert np.array_equal(b.sim.xhat, a.sim.xhat)
        assert np.array_equal(b.sim.Q.counters, a.sim.Q.counters)


def test_a_block_of_a_campaign_gives_the_rows_of_its_runs_alone():
    c, base = cm.parse_text(DOCKING, "<test>")
    rows = cm.run_block(c, base, [2, 0, 3])
    assert [r["run"] for r in rows] == [2, 0, 3]
    for row in rows:
        alone = cm.run_one(c, base, row["run"])
        assert cm.same_figures(row, alone), row["run"]
        assert row["wall_s"] > 0.0
    assert not cm.same_figures(rows[0], {**rows[0], "miss_m": rows[0]["miss_m"] * 1.01})


def test_missions_of_other_shapes_and_allocations_share_a_batch_and_stay_as_alone():
    # model scale and full scale (other thruster sets and frames: their chunks run alone in
    # the first run's batch), the QP allocation (never compiled: run in its generator)
    missions = cases()
    qp = _short("model-step-qp", [10.0, 20.0])
    assert qp.setup.allocation == "qp"
    chosen = [missions["full-docking-current-0.3"], missions["model-step-priority-ekf"], qp]

    def drivers():
        from missions.setup import build_simulation

        return [MissionDriver(m, build_simulation(m)) for m in chosen]

    alone = [d.run_to_end() for d in drivers()]
    outcomes = run_together([d.run_to_end_jobs() for d in drivers()])
    for a, o in zip(alone, outcomes, strict=True):
        assert o.error is None
        _same_result(a, o.value)


def test_a_run_that_diverges_or_raises_ends_alone_and_the_others_go_on():
    ps = params.load("full-scale")

    def three():
        sims = [Simulation(ps, tree_depth_m=100.0, seed=s) for s in (1, 2, 3)]
        sims[1].x[7] = math.nan  # the tree's sway speed: the plant's state is not finite
        return sims

    alone = three()
    rows_0 = alone[0].step(250)
    with pytest.raises(SimulationDiverged) as err_alone:
        alone[1].step(250)
    rows_2 = alone[2].step(250)

    def raises():
        yield from ()
        raise RuntimeError("a run's own failure")

    sims = three()
    outcomes = run_together(
        [sims[0].step_jobs(250), sims[1].step_jobs(250), raises(), sims[2].step_jobs(250)]
    )
    assert np.array_equal(outcomes[0].value.data, rows_0.data)
    assert isinstance(outcomes[1].error, SimulationDiverged)
    assert str(outcomes[1].error) == str(err_alone.value)
    assert "tree velocity" in str(outcomes[1].error)
    assert isinstance(outcomes[2].error, RuntimeError)
    # the run after the diverged and the raising ones in the batch goes on as alone
    assert outcomes[3].error is None
    assert np.array_equal(outcomes[3].value.data, rows_2.data)
    assert np.array_equal(sims[0].x, alone[0].x)
    assert np.array_equal(sims[2].x, alone[2].x)


@pytest.mark.parametrize(
    ("todo", "workers", "size"),
    [(1, 2, 1), (4, 2, 1), (8, 2, 2), (40, 2, 10), (200, 2, 32), (1000, 4, 32)],
)
def test_runs_per_task_splits_the_runs_so_the_workers_finish_together(todo, workers, size):
    assert runner.runs_per_task(todo, workers) == size


def test_a_lean_driver_scores_the_same_and_a_result_without_its_log_too():
    # what a campaign's runs keep (many are alive at once in a batch): 19 of the log's 115
    # columns, the same figures to the bit; and a result that keeps no log (its rows joined
    # into a reused array to be scored) the same figures again, run after run
    from missions.driver import LEAN_LAYOUT
    from missions.setup import build_simulation

    for mission in (cases()["model-step-priority-ekf"], cases()["full-docking-current-0.3"]):
        full = MissionDriver(mission, build_simulation(mission)).run_to_end()
        lean = MissionDriver(mission, build_simulation(mission), keep_log=False).run_to_end()
        assert lean.log.data.shape == (len(full.log), LEAN_LAYOUT.width)
        assert LEAN_LAYOUT.width < full.log.data.shape[1] / 5
        for name in LEAN_LAYOUT.starts:  # every kept column, request by request
            assert np.array_equal(lean.log[name], full.log[name])
        assert np.array_equal(lean.log.quality_counters, full.log.quality_counters)
        assert lean.summary() == full.summary()
        assert lean.settling_time_s == full.settling_time_s
        for _ in range(2):  # the second into the array the first was joined into
            bare = MissionDriver(mission, build_simulation(mission), keep_log=False)
            no_log = bare.run_to_end(log=False)
            assert len(bare.parts) > 1 and no_log.log is None
            assert no_log.summary() == full.summary()
            assert no_log.settling_time_s == full.settling_time_s


def test_runs_on_another_plant_step_by_themselves_in_the_batch_and_stay_as_alone():
    # the runs on the batch's own plant (the first run's) step together, the runs innermost
    # (sim.batch_plant); a run whose plant differs (a heavier tree: its Froude-Krylov mass
    # m - W0 / g differs) steps by itself
    from control.batch import _Slots

    spec = params.load_spec("full-scale")
    base = params.build(spec)
    heavy = params.build(
        spec.model_copy(
            update={"tree": spec.tree.model_copy(update={"mass_kg": spec.tree.mass_kg * 1.2})}
        )
    )

    def runs():
        sims = [
            Simulation(base, tree_depth_m=100.0, seed=1),
            Simulation(heavy, tree_depth_m=100.0, seed=2),
            Simulation(base, tree_depth_m=100.0, seed=1),
        ]
        for sim in sims:  # a move, so that the tree's inertia counts
            sim.set_target(3.0, 0.0, 0.0)
        return sims

    alone = _each_as_alone(runs, 300)
    assert np.array_equal(alone[0].data, alone[2].data)  # the same run twice
    assert not np.array_equal(alone[0].data, alone[1].data)
    sims = runs()
    jobs = [next(sim.step_jobs(10)) for sim in sims]
    slots = _Slots(jobs[0], 3)
    assert all(slots.put(r, job) for r, job in enumerate(jobs))
    assert slots.same_plant.tolist() == [True, False, True]


def test_the_plant_pass_narrows_as_runs_end_and_each_run_stays_as_alone():
    """The structure-of-arrays plant step takes only the runs under way, loaded straight
    from their rows into a block's first columns and padded to a multiple of eight
    (``PLANT_LANES``): ten runs take 16 columns, eight take 8. Requests of 30 to 120 steps end
    one after another, so the pass narrows, the later runs move into earlier columns as the
    earlier ones end, and the padding repeats the first column: every run's rows and final
    state are still those of the run alone, bit for bit."""
    from control.batch import PLANT_LANES, _Slots
    from control.batchkernel import plants_into

    assert PLANT_LANES == 8
    base = params.load("full-scale")

    def runs() -> list[Simulation]:
        sims = [Simulation(base, tree_depth_m=100.0, seed=i) for i in range(10)]
        for i, sim in enumerate(sims):
            sim.set_target(0.3 * i, -0.2, math.radians(10.0 * i))
        return sims

    lengths = [120, 30, 110, 40, 100, 50, 90, 60, 80, 70]
    alone = [sim.step(n).data for sim, n in zip(runs(), lengths, strict=True)]
    sims = runs()
    together = run_together([sim.step_jobs(n) for sim, n in zip(sims, lengths, strict=True)])
    for a, o in zip(alone, together, strict=True):
        assert o.error is None
        assert np.array_equal(o.value.data, a)
    assert len({float(a[-1, 0]) for a in alone}) == 10  # ten different runs

    sims = runs()
    jobs = [next(sim.step_jobs(10)) for sim in sims]
    slots = _Slots(jobs[0], 10)
    assert all(slots.put(r, job) for r, job in enumerate(jobs))

    def plant_pass(active: np.ndarray) -> int:
        return plants_into(
            active, slots.same_plant, slots.pos, slots.x, slots.n_rps, slots.env_at, slots.PS,
            slots.P0, slots.dt_s, slots.work, slots.bwork,
        )  # fmt: skip

    active = np.ones(10, np.bool_)
    x_before = slots.x.copy()
    assert plant_pass(active) == 16
    assert list(slots.bwork.runs[:10]) == list(range(10))
    assert np.all(np.abs(slots.x - x_before).max(axis=1) > 0.0)  # every run stepped
    active[[1, 3]] = False  # two runs between chunks: eight under way
    x_before = slots.x.copy()
    assert plant_pass(active) == 8
    assert list(slots.bwork.runs[:8]) == [0, 2, 4, 5, 6, 7, 8, 9]
    assert np.array_equal(slots.x[[1, 3]], x_before[[1, 3]])  # they did not move
    assert not np.array_equal(slots.x[0], x_before[0])
    assert plant_pass(np.zeros(10, np.bool_)) == 0  # none under way: no block


def test_more_runs_than_a_plant_block_each_as_alone():
    """A batch wider than the plant pass's block (``sim.batch_plant.BLOCK`` runs, twice the
    observers' ``control.batch_ekf.BLOCK``) steps its runs in several blocks; each run's rows
    are still the run's alone, bit for bit (the second block's runs are the ones a wrong
    column's bookkeeping would swap)."""
    from sim.batch_plant import BLOCK

    base = params.load("full-scale")
    n_runs = BLOCK + 3
    ekf = ControlSettings(feedback="ekf", feedforward=True)  # the observers' blocks too

    def runs() -> list[Simulation]:
        sims = [Simulation(base, tree_depth_m=100.0, seed=i, settings=ekf) for i in range(n_runs)]
        for i, sim in enumerate(sims):
            sim.set_target(0.01 * i, -0.2, math.radians(0.5 * i))
        return sims

    alone = [sim.step(4).data for sim in runs()]
    together = run_together([sim.step_jobs(4) for sim in runs()])
    for a, o in zip(alone, together, strict=True):
        assert o.error is None
        assert np.array_equal(o.value.data, a)
    assert len({a.tobytes() for a in alone}) == n_runs  # every run its own


def test_a_lean_log_keeps_the_whole_logs_columns_in_a_batch_alone_and_mixed():
    """A campaign's runs log only the columns their scores and legs read (``LEAN_LAYOUT``):
    the batch's kernel makes each step's whole row in a scratch row and writes those columns
    out, the kernels alone make whole rows and the simulation takes them. Either way a lean
    run's rows are its whole log's columns, bit for bit; a batch of lean and whole logs runs
    the whole ones alone beside it (their rows another width)."""
    from control.columns import LAYOUT, Layout
    from missions.driver import LEAN_LAYOUT

    base = params.load("full-scale")
    lengths = [120, 30, 110, 40, 100, 50]

    def runs(lean: list[bool]) -> list[Simulation]:
        sims = [Simulation(base, tree_depth_m=100.0, seed=i) for i in range(len(lean))]
        for i, sim in enumerate(sims):
            sim.set_target(0.3 * i, -0.2, math.radians(10.0 * i))
            if lean[i]:
                sim.keep_log_columns(LEAN_LAYOUT)
        return sims

    whole = [s.step(n) for s, n in zip(runs([False] * 6), lengths, strict=True)]
    keep = runs([True])[0].log_keep
    assert LEAN_LAYOUT.width == len(keep) < LAYOUT.width / 5
    alone = [s.step(n) for s, n in zip(runs([True] * 6), lengths, strict=True)]
    lean = runs([True] * 6)
    batch = run_together([s.step_jobs(n) for s, n in zip(lean, lengths, strict=True)])
    mixed_flags = [True, False, True, False, True, False]
    mixed = run_together([s.step_jobs(n) for s, n in zip(runs(mixed_flags), lengths, strict=True)])
    for i, w in enumerate(whole):
        kept = w.data[:, keep]
        assert alone[i].layout == LEAN_LAYOUT and np.array_equal(alone[i].data, kept)
        assert batch[i].error is None and batch[i].value.layout == LEAN_LAYOUT
        assert np.array_equal(batch[i].value.data, kept)
        m = mixed[i].value
        assert np.array_equal(m.data, kept if mixed_flags[i] else w.data)
        for name in LEAN_LAYOUT.starts:
            assert np.array_equal(batch[i].value[name], w[name])
    assert len({float(w.data[-1, 1]) for w in whole}) == 6  # six different runs
    sim = runs([False])[0]
    scrambled = Layout.of([_column("wire_tension"), _column("t_s")])
    with pytest.raises(ValueError, match="LAYOUT's, in its order"):
        sim.keep_log_columns(scrambled)


def _column(name: str):
    from control.columns import LOG_COLUMNS

    return next(c for c in LOG_COLUMNS if c.name == name)


def test_observers_on_another_control_model_predict_by_themselves_and_stay_as_alone():
    # the observers of the runs on the batch's control model (the first run's) predict
    # together (control.batch_ekf); a run whose control model differs (its observer's bias
    # time constants: T_b) predicts by itself; a run without an observer not at all
    from control.batch import _Slots

    spec = params.load_spec("full-scale")
    base = params.build(spec)
    observer = spec.observer.model_copy(update={"bias_time_constant_s": [300.0, 600.0, 900.0]})
    other = params.build(spec.model_copy(update={"observer": observer}))
    ekf = ControlSettings(feedback="ekf", feedforward=True)

    def runs():
        sims = [
            Simulation(base, tree_depth_m=100.0, seed=1, settings=ekf),
            Simulation(other, tree_depth_m=100.0, seed=2, settings=ekf, plant_ps=base),
            Simulation(base, tree_depth_m=100.0, seed=3, settings=ekf),
            Simulation(base, tree_depth_m=100.0, seed=4),
        ]
        for sim in sims:
            sim.set_target(3.0, -1.0, math.radians(5.0))
        return sims

    _each_as_alone(runs, 300)
    sims = runs()
    jobs = [next(sim.step_jobs(10)) for sim in sims]
    slots = _Slots(jobs[0], 4)
    assert all(slots.put(r, job) for r, job in enumerate(jobs))
    assert slots.same_model.tolist() == [True, False, True, True]
    assert slots.same_plant.tolist() == [True, True, True, True]
    assert [bool(sim.C.feedback_ekf) for sim in sims] == [True, True, True, False]


def test_the_kernel_reads_each_runs_inputs_where_its_job_made_them():
    """The batch reads a run's chunk inputs (environment rows, noise, fresh flags, spring) at
    their addresses, not from copies in its slots: inputs laid out otherwise (Fortran order,
    a strided view) are read from a contiguous copy and give the rows alone; inputs of a
    width the kernel does not read leave the run out of the batch (it runs alone)."""
    import dataclasses

    from control.batch import _Slots

    base = params.load("full-scale")
    ekf = ControlSettings(feedback="ekf", feedforward=True)

    def runs() -> list[Simulation]:
        sims = [Simulation(base, tree_depth_m=100.0, seed=i, settings=ekf) for i in range(3)]
        for i, sim in enumerate(sims):
            sim.set_target(1.0 + i, -0.5, math.radians(3.0 * i))
            sim.winch_to(sim.wire_length_m + 0.5, 0.1)  # a spring that changes inside chunks
        return sims

    def laid_out_otherwise(gen):
        job = next(gen)
        while True:
            job.env = np.asfortranarray(job.env)
            job.noise = np.repeat(job.noise, 2, axis=0)[::2]  # a strided view
            try:
                job = gen.send((yield job))
            except StopIteration as stop:
                return stop.value

    alone = [sim.step(250).data for sim in runs()]
    together = run_together([laid_out_otherwise(sim.step_jobs(250)) for sim in runs()])
    for a, o in zip(alone, together, strict=True):
        assert o.error is None
        assert np.array_equal(o.value.data, a)
    assert len({a.tobytes() for a in alone}) == 3

    jobs = [next(sim.step_jobs(10)) for sim in runs()]
    slots = _Slots(jobs[0], 3)
    wide = dataclasses.replace(jobs[1], env=np.zeros((10, jobs[1].env.shape[1] + 1)))
    assert not slots.put(1, wide)
    assert slots.length[1] == 0 and slots.inputs[1] is None  # nothing started
    assert slots.seen_P[1] is None and slots.seen_C[1] is None  # nothing of it taken
    assert slots.put(0, jobs[0])
    assert slots.inputs[0] is not None and slots.inputs[0][0] is jobs[0].env  # not copied
