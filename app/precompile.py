"""Compile the numeric core once, into numba's on-disk cache, at set-up time.

Every later process loads the compiled code instead of compiling it again (a first run would
otherwise spend half a minute compiling). It also makes runs bit-for-bit repeatable: code
compiled fresh in a process and the same code loaded from the cache can differ in the last
bits (about 1e-9 relative after a long run), so set-up puts the cache in place before any run.

The cache is kept per version of the numeric core's sources (``sim.numba_cache``).
``--if-needed`` (what ``scripts/setup.sh`` runs each time) compiles only when this version's
folder has not been filled yet, and then removes the folders of earlier versions.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from sim.plant import PlantArrays

DONE_MARK = "precompiled"
"""The file written into the cache folder once every kernel is in it."""


def cache_dir() -> Path:
    """numba's cache folder for this process (chosen when ``sim`` is imported)."""
    import sim  # noqa: F401

    return Path(os.environ["NUMBA_CACHE_DIR"])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m app.precompile", description=__doc__)
    parser.add_argument(
        "--if-needed",
        action="store_true",
        help="do nothing when this version of the sources is compiled already",
    )
    parser.add_argument(
        "--part",
        choices=PARTS,
        help="compile one part only, into the cache (what the parallel precompile runs)",
    )
    args = parser.parse_args(argv)
    if args.part:
        compile_all(args.part)
        return
    folder = cache_dir()
    mark = folder / DONE_MARK
    if args.if_needed and mark.is_file():
        return
    print(f"precompile: compiling the numeric core into {folder} (a few minutes)", flush=True)
    t0 = time.perf_counter()
    if (os.cpu_count() or 1) >= 2:
        compile_parts_at_once()
    compile_all()  # loads what the parts compiled; compiles anything they left
    print(f"precompile: numeric core compiled in {time.perf_counter() - t0:.0f} s")
    folder.mkdir(parents=True, exist_ok=True)
    mark.write_text("every kernel of app.precompile is in this folder\n")
    from sim import numba_cache

    if folder == numba_cache.CHOSEN:  # our folder, not one the user chose: drop older ones
        numba_cache.prune(folder)


PARTS = ("closed-loop", "open-loop-and-qp", "batch")
"""Three parts of the compile that share no large kernel, so that separate processes compile
them at once: the closed loop's chunk kernel (``loop.run_chunk``); the open loop's
(``loop.run_open_chunk``) with the QP allocation's step (``loop.control_step`` and
``loop.finish_step``, which calls ``plant.rk4_step_into``), the plant's own kernels as
Python calls them (``plant.rk4_step_into``, ``rhs``, ...) and the small kernels Python calls
directly (``compile_entry_points``); and the batch kernel of campaigns
(``control.batchkernel.batch_steps``) with the batch plant. On this repository's Zen 3 (2
cores, the three side by side, numba's compile events recorded per function, 2026-11-27;
docs/speed.md, seventeenth pass) the parts took 699 s, 978 s and 1 254 s when the
plant's own kernels were in the closed loop's part (390 s of it, and ``rk4_step_into``
compiled in two parts); each kernel that inlines the plant's step takes minutes
(``loop._closed_steps`` 830 s of the closed loop's part, ``loop._open_steps`` 460 s)."""


def compile_parts_at_once() -> None:
    """Compile the parts in subprocesses, side by side. numba writes each cache file under
    a temporary name and renames it, so two processes saving the small kernels both use is
    safe; a part that fails leaves its kernels to the in-process pass after it."""
    procs = [
        subprocess.Popen([sys.executable, "-m", "app.precompile", "--part", part]) for part in PARTS
    ]
    for part, proc in zip(PARTS, procs, strict=True):
        if proc.wait() != 0:
            print(f"precompile: part {part} failed; compiling it here", flush=True)


def compile_all(part: str | None = None) -> None:
    """Run what fills the cache: every kernel the product calls, with the argument types it
    calls them with (``part``: one of ``PARTS`` only)."""
    from control.config import ALLOCATIONS, MODES, ControlSettings
    from control.simulation import Simulation
    from sim import params

    closed = part in (None, "closed-loop")
    other = part in (None, "open-loop-and-qp")
    ps = params.load("model-scale")
    from sim import batch_plant, plant

    arrays = Simulation(params.load("full-scale"), tree_depth_m=100.0).arrays
    m = arrays.thr_T.shape[1]
    x, n, env = np.zeros(plant.N_STATE), np.zeros(m), np.zeros(plant.N_ENV)
    env[plant.E_LREST] = 100.0  # a 100 m wire; the values do not matter, the calls only compile
    if part in (None, "batch"):
        from control.batch import run_together

        runs = [Simulation(ps, tree_depth_m=100.0) for _ in range(2)]
        run_together([sim.step_jobs(2) for sim in runs])
        # the batch plant's step called from Python (its tests and tools): ``rk4_batch_into``
        # around the batch kernel's own ``rk4_block_into``, compiled just above
        batch_plant.rk4_batch(
            np.zeros((plant.N_STATE, 2)), np.zeros((m, 2)), np.zeros((plant.N_ENV, 2)), arrays, 0.01
        )
    if other:
        # the plant's own kernels as tools, benchmarks and tests call them from Python (one
        # step, the right-hand side, a run of steps): compiled here rather than by the first
        # test run (rk4_step_into is the step the QP path's finish_step and the other kernels
        # call, so this part compiles it once for both; rhs inlines the right-hand side once
        # more)
        plant.rk4_step_into(x.copy(), x, n, env, arrays, 0.01, plant.make_work(m))
        plant.rk4_step(x, n, env, arrays, 0.01)
        plant.rhs_into(np.zeros(plant.N_STATE), x, np.zeros(6), env, arrays, plant.make_work(m))
        plant.rhs(x, n, env, arrays)
        plant.advance(x, n, env[None, :], arrays, 0.01)
    if other:
        compile_entry_points(arrays)
    if closed:
        for feedback in ("perfect", "ekf"):
            for allocation in ("pinv", "priority"):
                for reference in ("first", "third"):
                    settings = ControlSettings(
                        feedback=feedback,
                        allocation=allocation,
                        reference=reference,
                        feedforward=True,
                    )
                    Simulation(ps, tree_depth_m=100.0, settings=settings).step(2)
        # a request of several chunks: each writes into the request's rows (run_chunk_into)
        Simulation(ps, tree_depth_m=100.0, chunk_steps=1).step(2)
    if other:
        Simulation(ps, tree_depth_m=100.0, control=False).step(2)
        Simulation(ps, tree_depth_m=100.0, control=False, chunk_steps=1).step(2)
    # what the console does to a running simulation: every mode, every allocation in each,
    # the grip, the pilot's demand, and the readings its snapshot takes. Some of these call
    # kernels from Python with their own argument types; compiled here, they are loaded from
    # the cache later instead of compiling for seconds inside the console's loop (where a
    # command then waited 10 s and got a 503)
    allocations = [a for a in ALLOCATIONS if (other if a == "qp" else closed)]
    for name in ("model-scale", "full-scale"):
        sim = Simulation(params.load(name), tree_depth_m=100.0)
        if closed:
            sim.step(2)
        for mode in MODES:
            sim.set_mode(mode)
            for allocation in allocations:
                sim.set_allocation(allocation)
                sim.step(2)
                sim.set_pilot_demand(0.2, -0.1, 0.1, 0.05)
                sim.step(2)
                sim.present_row()
                sim.wire_tension_newton()
        sim.set_mode("tree")
        for allocation in allocations:
            sim.set_allocation(allocation)
            sim.set_grip(False)
            sim.step(2)
            sim.set_grip(True)
            sim.step(2)


def compile_entry_points(arrays: PlantArrays) -> None:
    """The small kernels that Python calls directly (not only from inside the chunk kernels,
    which inline them): the landing plan's hold (``plant.hold_needed_xyn``), the scoring's
    angle wrap, the site's wire offset, the allocation's thruster maps, and the plant's,
    observer's, controller's and reference's pieces as the unit tests and tools call them.
    Each is compiled for the argument types it is called with (``dispatcher.compile``, nothing
    run), so a fresh clone's first docking, or first test run, does not compile them (the
    tests spent 55-98 s on it: docs/speed.md, nineteenth pass). A call with other types still
    compiles on first use, as before."""
    from numba import typeof, types
    from numba.core.errors import NumbaPerformanceWarning

    from control import allocation, ekf, pid, quality, refkernel
    from sim import gnc, plant, sensors, thrusters, wire

    f8, i8, b1 = types.float64, types.int64, types.boolean
    a1, a2, a3 = types.float64[::1], types.float64[:, ::1], types.float64[:, :, ::1]
    any1 = types.float64[:]
    ro1 = types.Array(f8, 1, "C", readonly=True)
    i1, i2 = types.int64[::1], types.int64[:, ::1]
    ro_i1 = types.Array(i8, 1, "C", readonly=True)
    bools = types.boolean[::1]
    pa = typeof(arrays)
    signatures: list[tuple[Any, tuple[Any, ...]]] = [
        (gnc.ssa, (f8,)),
        (gnc.ssa, (a1,)),
        (gnc.ssa_each, (a1,)),
        (gnc.Tzyx, (f8, f8)),
        (gnc.m2c, (a2, a1)),
        (gnc.mv, (a2, a1)),
        (gnc.cross, (a1, a1)),
        (gnc.coriolis_force, (a2, a1)),
        (gnc.euler_from_rotation, (a2,)),
        (wire.horizontal_offset_c, (f8, f8, f8, f8, f8)),
        (wire.horizontal_offset_c, (f8, f8, f8, i8, f8)),
        (plant.hold_needed_xyn, (a2, f8, a1, pa)),
        (plant.attachment_velocity_n, (a1, a2, a1)),
        (plant.tree_wrench, (a1, a1, pa, a2)),
        (plant.rov_wrench, (a1, a1, a1, pa, a2)),
        (plant.coupling_wrench, (a1, pa, a2, a2)),
        (plant.contact_wrench, (a1, a1, pa, a2)),
        (plant.contact_energy, (a1, a1, pa)),
        (plant.contact_reach, (pa,)),
        (plant.post_penetration, (a1, pa)),
        (plant._post_top, (a1, a1, pa, i8)),
        (plant._post_top, (any1, any1, pa, i8)),
        (plant._corner_body, (pa, i8)),
        (sensors.sample_into, (a1, a1, a1, a1, bools, i1)),
        (sensors.sample_into, (a1, a1, a1, a1, bools, ro_i1)),
        (ekf.predict, (a1, a2, a1, f8, a2, a2, a1, a1, f8, a1, a1, a2)),
        (ekf.correct, (a1, a2, a1, i1, a1, i8)),
        (ekf.model_rhs, (a1, a1, a2, a2, a1, a1, f8, a1, a1)),
        (ekf.jacobian_phi_into, (a2, a1, f8, f8, f8, a2, a2, a1, a1, f8, a1, a1)),
        (pid.ned_to_body, (a1, f8)),
        (pid.tree_pid, (a1,) * 9 + (b1, a2, a1, a1, f8, a1, a2, a2, a1, f8)),
        (
            quality.check_sample,
            (i8, a1, f8, a1, a1, i1, a2, i2, a1, a1, a1, a1, i1, a1, i1, i1),
        ),
        (refkernel._first_kernel, (a1, a1, a1, f8)),
        (refkernel.first_order_step, (a1, a1, f8, a2)),
        (refkernel.third_order_step, (a1, a1, f8, a2)),
        (refkernel.reference_step, (i8, a1, a1, f8, a2)),
        (refkernel.reference_step_into, (a1, i8, a1, a1, f8, a2)),
        (refkernel.polls_still_away, (i8, a1, a1, f8, a2, a1, a1, i8, i8, a1)),
        (allocation._priority_forces, (a2, a3, a3, a1, a1, a1, f8)),
    ]
    # the thrusters' maps: the parameter sets' arrays are read-only, a caller's own are not
    for speed_or_thrust in (thrusters.speed_from_thrust, thrusters.thrust_from_speed):
        for first, rest in ((a1, a1), (a1, ro1), (ro1, ro1)):
            signatures.append((speed_or_thrust, (first, rest, rest, rest)))
    for into in (thrusters.speed_from_thrust_into, thrusters.thrust_from_speed_into):
        for second, rest in ((a1, a1), (a1, ro1), (ro1, ro1)):
            signatures.append((into, (a1, second, rest, rest, rest)))
    signatures.append((thrusters.speed_from_thrust_into, (a1, ro1, a1, a1, a1)))
    with warnings.catch_warnings():  # gnc.m2c's '@' on a block of M: a reference form, not
        warnings.simplefilter("ignore", NumbaPerformanceWarning)  # the step's
        for kernel, sig in signatures:
            kernel.compile(sig)


if __name__ == "__main__":
    main()
