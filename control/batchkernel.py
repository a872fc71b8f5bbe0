"""The compiled kernel of ``control.batch``: the closed loop of many runs advanced together.

Each run keeps its own state and configuration as one slice of arrays stacked over the runs
(run index first): the states ``x[r]``, ``held_y[r]``, ``xhat[r]`` ...; its chunk's inputs
(environment rows, sensor noise and fresh flags, the control model's wire spring) and log
rows stay in the run's own arrays, read and written at their addresses (``row_at``); and
its configuration as ``PlantArrays``, ``ControlArrays`` and ``QualityState`` whose every
field has a leading run axis (``plant_view`` and friends give run r's own, as views). Run r's
step is ``control.loop._closed_steps``' step, the same calls on the same numbers, so a run in
a batch gives the same figures as the run alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array

from control import batch_ekf, loop
from control.columns import N_LOG
from control.loop import ControlArrays, ControlWork, QualityState
from sim import batch_plant, plant, sensors
from sim.gnc import JIT_NOALLOC


def _view_at(dtype: Any, itemsize: int, address: Any, length: Any) -> Any:
    """Typing and code of an intrinsic that views the ``length`` items of ``dtype`` at memory
    ``address`` as a 1-D array (no copy, no owner)."""
    if not isinstance(address, types.Integer) or not isinstance(length, types.Integer):
        return None
    array_type = types.Array(dtype, 1, "C")

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        address_v, length_v = args
        n = context.cast(builder, length_v, signature.args[1], types.intp)
        ary = make_array(array_type)(context, builder)
        data = builder.inttoptr(address_v, context.get_data_type(dtype).as_pointer())
        size = context.get_constant(types.intp, itemsize)
        populate_array(
            ary,
            data=data,
            shape=cgutils.pack_array(builder, [n]),
            strides=cgutils.pack_array(builder, [size]),
            itemsize=size,
            meminfo=None,
        )
        return ary._getvalue()

    return array_type(address, length), codegen


def _row_at(typingctx: Any, address: Any, length: Any) -> Any:
    """The ``length`` float64 numbers at memory ``address`` as a 1-D array (a view: no copy,
    no owner). Lets the kernel write each run's log rows straight into the rows its
    ``Simulation`` asked for (arrays of different runs, not one stacked array) instead of
    into a slot copied out afterwards, and read each run's chunk inputs (environment rows,
    noise, wire spring) where its job made them. The caller keeps that memory alive while
    the kernel runs (``control.batch._Slots.rows``, ``inputs``)."""
    return _view_at(types.float64, 8, address, length)


def _flags_at(typingctx: Any, address: Any, length: Any) -> Any:
    """``row_at`` for booleans (one byte each): a run's fresh-sample flags of a step."""
    return _view_at(types.boolean, 1, address, length)


row_at: Any = intrinsic(_row_at)
flags_at: Any = intrinsic(_flags_at)


def _prefetch_line(typingctx: Any, address: Any) -> Any:
    """Ask the processor to bring the cache line at memory ``address`` into its caches
    (``llvm.prefetch``: a hint, which never faults and changes no number)."""
    if not isinstance(address, types.Integer):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        i32 = ir.IntType(32)
        ptr = builder.inttoptr(args[0], ir.IntType(8).as_pointer())
        fnty = ir.FunctionType(ir.VoidType(), [ptr.type, i32, i32, i32])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.prefetch.p0")
        # read, keep in every level, data
        builder.call(fn, [ptr, ir.Constant(i32, 0), ir.Constant(i32, 3), ir.Constant(i32, 1)])
        return context.get_dummy_value()

    return types.none(address), codegen


prefetch_line: Any = intrinsic(_prefetch_line)


@njit(inline="always", **JIT_NOALLOC)
def prefetch_span(address: int, n_bytes: int) -> None:
    """Prefetch the cache lines of the ``n_bytes`` bytes at ``address``."""
    for offset in range(0, n_bytes, 64):
        prefetch_line(address + offset)
    prefetch_line(address + n_bytes - 1)


@njit(inline="always", **JIT_NOALLOC)
def prefetch_step(
    r: int,
    j: int,
    length: np.ndarray,
    env_at: np.ndarray,
    noise_at: np.ndarray,
    fresh_at: np.ndarray,
    spring_at: np.ndarray,
    log_at: np.ndarray,
    row_bytes: int,
) -> None:
    """Prefetch what run r's step j reads and writes after its control: its environment row
    j (the plant pass, the row's site columns), its log row j, and its next step's noise,
    fresh flags and spring rows (``sense_ahead``, the next step's start). Each run's chunk
    inputs are its own arrays, made by Python before the chunk and long out of the caches
    by the time the kernel reaches a row, and the runs' many streams are more than the
    processor's prefetchers follow: without this the sensors' sampling alone waited some
    80 ns a run-step on memory (docs/speed.md, twenty-sixth pass)."""
    prefetch_span(env_at[r] + j * (plant.N_ENV * 8), plant.N_ENV * 8)
    prefetch_span(log_at[r] + j * row_bytes, row_bytes)
    if j + 1 < length[r]:
        j1 = j + 1
        prefetch_span(noise_at[r] + j1 * (sensors.N_Y * 8), sensors.N_Y * 8)
        prefetch_span(fresh_at[r] + j1 * sensors.N_SENSORS, sensors.N_SENSORS)
        prefetch_span(spring_at[r] + j1 * 24, 24)


@njit(inline="always", **JIT_NOALLOC)
def plant_view(S: Any, r: int) -> plant.PlantArrays:
    """Run r's ``PlantArrays`` out of the stacked ones (every field with a run axis first)."""
    return plant.PlantArrays(
        S.tree_M_rb[r],
        S.tree_M_a[r],
        S.tree_M_inv[r],
        S.tree_D_l[r],
        S.tree_D_nl[r],
        S.tree_W0[r],
        S.tree_r_att[r],
        S.rov_M_rb[r],
        S.rov_M_a[r],
        S.rov_M_inv[r],
        S.rov_D_l[r],
        S.rov_D_nl[r],
        S.rov_W[r],
        S.rov_B[r],
        S.rov_r_cg[r],
        S.rov_r_cb[r],
        S.thr_T[r],
        S.thr_k_pos[r],
        S.thr_k_neg[r],
        S.thr_n_max[r],
        S.mount_r[r],
        S.mount_R[r],
        S.coupling_K[r],
        S.coupling_C[r],
        S.has_rov[r],
        S.dock_xy[r],
        S.dock_post_height[r],
        S.dock_post_radius[r],
        S.dock_mouth_radius[r],
        S.dock_bore_radius[r],
        S.dock_cone_height[r],
        S.tree_half_height[r],
        S.tree_footprint[r],
        S.contact_k[r],
        S.contact_c[r],
        S.post_k[r],
        S.post_c[r],
        S.friction_mu[r],
        S.tree_fk_mass[r],
        S.rov_fk_mass[r],
    )


@njit(inline="always", **JIT_NOALLOC)
def control_view(S: Any, r: int) -> ControlArrays:
    """Run r's ``ControlArrays`` out of the stacked ones."""
    return ControlArrays(
        S.feedback_ekf[r],
        S.use_ff[r],
        S.ref_kind[r],
        S.ref_params[r],
        S.Kp[r],
        S.Ki[r],
        S.Kd[r],
        S.M[r],
        S.M_inv[r],
        S.D_l[r],
        S.D_nl[r],
        S.k_h[r],
        S.p_eq[r],
        S.A[r],
        S.A_inv[r],
        S.i_limit[r],
        S.heave_newton[r],
        S.r_mount[r],
        S.psi_rel[r],
        S.alloc_kind[r],
        S.pinv_T[r],
        S.pinv_rows[r],
        S.prio_A[r],
        S.prio_D[r],
        S.prio_R[r],
        S.prio_rows[r],
        S.f_lo[r],
        S.f_hi[r],
        S.alloc_tol[r],
        S.k_pos[r],
        S.k_neg[r],
        S.n_max[r],
        S.T6[r],
        S.rov_to_tree[r],
        S.GQG[r],
        S.T_b[r],
        S.r_pos[r],
        S.r_psi[r],
        S.r_dvl[r],
        S.r_gyro[r],
        S.q_lo[r],
        S.q_hi[r],
        S.q_wild[r],
        S.q_rate[r],
        S.q_frozen[r],
        S.q_var[r],
        S.free_Kp[r],
        S.free_Ki[r],
        S.free_Kd[r],
    )


@njit(inline="always", **JIT_NOALLOC)
def set_spring(CS: Any, r: int, spring_j: np.ndarray) -> None:
    """Run r's control model's wire spring [k_h, p_eq north, east] into the stacked
    configuration (``ControlArrays.k_h``, ``p_eq``), as the simulator's refresh puts it into
    ``C`` between chunks."""
    CS.k_h[r] = spring_j[0]
    CS.p_eq[r, 0] = spring_j[1]
    CS.p_eq[r, 1] = spring_j[2]


@njit(inline="always", **JIT_NOALLOC)
def quality_view(S: Any, r: int) -> QualityState:
    """Run r's ``QualityState`` out of the stacked ones (views: the checks update it)."""
    return QualityState(
        S.last[r],
        S.last_t[r],
        S.repeat[r],
        S.hist[r],
        S.counters[r],
    )


@njit(inline="always", **JIT_NOALLOC)
def _block_step(
    x: np.ndarray, n_cols: int, m: int, P0: plant.PlantArrays, dt: float, bwork: Any
) -> int:
    """Step the block's ``n_cols`` loaded columns (padded, ``batch_plant.pad_block``) and
    put each column's new state back into its run's row of ``x`` (``bwork.runs``). Returns
    the padded width."""
    w = batch_plant.pad_block(bwork, n_cols, m)
    batch_plant.rk4_block_into(P0, dt, bwork, w)
    for c in range(n_cols):
        batch_plant.store_column(bwork, c, x[bwork.runs[c]])
    return w


@njit(inline="always", **JIT_NOALLOC)
def plants_into(
    active: np.ndarray,
    same_plant: np.ndarray,
    pos: np.ndarray,
    x: np.ndarray,
    n_rps: np.ndarray,
    env_at: np.ndarray,
    PS: Any,
    P0: plant.PlantArrays,
    dt: float,
    work: plant.PlantWork,
    bwork: batch_plant.BatchWork,
) -> int:
    """``batch_steps``' plant pass: one RK4 step of every active run's plant (``x[r]`` in
    place, at propeller speeds ``n_rps[r]`` and its environment row ``pos[r]``, read where
    its chunk's rows are, at address ``env_at[r]``: ``env_row``). The active runs
    on the batch's own plant (``same_plant``) go together in the structure-of-arrays step of
    ``sim.batch_plant``: each run's state, speeds and row go straight into the next column of
    a block (``load_column``, in run order, ``BLOCK`` runs a block), the block steps
    (padded to a multiple of ``LANES`` columns that repeat the first with no landing
    surface, so they cost the plain step and nothing more) and each column's new state goes
    straight back into its run's row. Runs that have ended or wait between chunks take no
    column (an ended run left landed on the frame would otherwise take the scalar contact in
    every stage to the batch's end). Any other run by itself. Returns the last block's
    padded width (0: no block)."""
    n_runs = pos.shape[0]
    m = n_rps.shape[1]
    c = 0
    w = 0
    for r in range(n_runs):
        if active[r] and same_plant[r]:
            batch_plant.load_column(bwork, c, x[r], n_rps[r], env_row(env_at, r, pos[r]))
            bwork.runs[c] = r
            c += 1
            if c == batch_plant.BLOCK:
                w = _block_step(x, c, m, P0, dt, bwork)
                c = 0
    if c > 0:
        w = _block_step(x, c, m, P0, dt, bwork)
    for r in range(n_runs):
        if active[r] and not same_plant[r]:
            # inlined: a call would pass run r's ``PlantArrays`` views one by one
            P = plant_view(PS, r)
            env_j = env_row(env_at, r, pos[r])
            plant.rk4_step_inline(x[r], x[r], n_rps[r, 0:m], env_j, P, dt, work)
    return w


@njit(inline="always", **JIT_NOALLOC)
def observe_run(
    r: int,
    env_j: np.ndarray,
    C: ControlArrays,
    on_model: bool,
    xhat: np.ndarray,
    Pc: np.ndarray,
    log_row: np.ndarray,
    c: int,
    dt: float,
    ebwork: batch_ekf.EkfBlock,
    W: ControlWork,
) -> bool:
    """Run r's observer prediction over the step just taken (``loop.observe_into``'s first
    part), from its step's log row: on the batch's control model (``on_model``) the run is
    loaded into column ``c`` of the block, with no samples (``sense_ahead`` may add them;
    ``end_column`` closes the column); on another it predicts by itself at once; without an
    observer nothing. Returns whether the run took column ``c``."""
    if not C.feedback_ekf:
        return False
    tau_tree = loop.observer_input_into(env_j, C, log_row, W)
    if not on_model:
        loop.predict_with_input_into(tau_tree, xhat[r], Pc[r], C, dt, W)
        return False
    batch_ekf.load_run(ebwork, c, xhat[r], Pc[r], tau_tree, C.k_h, C.p_eq)
    ebwork.runs[c] = r
    return True


@njit(inline="always", **JIT_NOALLOC)
def sense_ahead(
    t: float,
    x: np.ndarray,
    y: np.ndarray,
    noise_j: np.ndarray,
    fresh_j: np.ndarray,
    C: ControlArrays,
    Q: QualityState,
    row: np.ndarray,
    c: int,
    ebwork: batch_ekf.EkfBlock,
    W: ControlWork,
) -> None:
    """The start of a run's next step (at time ``t``), made at the end of this one so its
    observer corrects in the block right after it predicts: the row zeroed, the sensors
    sampled into the held values ``y`` from the plant's state ``x`` (``noise_j``,
    ``fresh_j``: the next step's), the signal checks, and the accepted samples into column
    ``c`` (``batch_ekf.load_samples``). The kernel's next step then starts at the control
    law (``loop.control_law_into``); per run these are ``loop._closed_steps``' operations in
    its order."""
    for i in range(N_LOG):
        row[i] = 0.0
    sensors.sample_into(y, x, y, noise_j, fresh_j, sensors.Y_SENSOR)
    accepted = W.vec[loop.W_ACCEPT, 0:5]
    loop.accept_samples_into(accepted, t, y, fresh_j, C, Q, row)
    acc = W.vec[loop.W_ACC4, 0:4]
    acc[batch_ekf.A_COMPASS] = accepted[sensors.COMPASS]
    acc[batch_ekf.A_POSITION] = accepted[sensors.POSITION]
    acc[batch_ekf.A_GYRO] = accepted[sensors.GYRO]
    acc[batch_ekf.A_DVL] = accepted[sensors.DVL]
    z = W.vec[loop.W_Z6, 0:6]
    z[batch_ekf.Z_PSI] = loop.tree_heading(y, C)
    z[batch_ekf.Z_NORTH] = y[0]
    z[batch_ekf.Z_EAST] = y[1]
    z[batch_ekf.Z_RATE] = y[10]
    z[batch_ekf.Z_U] = z[batch_ekf.Z_V] = 0.0
    if acc[batch_ekf.A_DVL] > 0.5:  # the DVL's velocity moved to the tree's origin
        uv = W.vec[loop.W_UV, 0:2]
        loop.tree_velocity_into(uv, y, C)
        z[batch_ekf.Z_U] = uv[0]
        z[batch_ekf.Z_V] = uv[1]
    r_var = W.vec[loop.W_RVAR4, 0:4]
    r_var[batch_ekf.A_COMPASS] = C.r_psi
    r_var[batch_ekf.A_POSITION] = C.r_pos
    r_var[batch_ekf.A_GYRO] = C.r_gyro
    r_var[batch_ekf.A_DVL] = C.r_dvl
    batch_ekf.load_samples(ebwork, c, acc, z, C.r_mount, r_var)


@njit(inline="always", **JIT_NOALLOC)
def end_column(
    xhat: np.ndarray,
    Pc: np.ndarray,
    c: int,
    C0: ControlArrays,
    dt: float,
    ebwork: batch_ekf.EkfBlock,
    scratch: np.ndarray,
) -> int:
    """Close the block's column ``c`` (loaded by ``observe_run``): a full block is predicted
    and corrected at once (``predict_block``). Returns the block's columns loaded now."""
    c += 1
    if c == batch_ekf.BLOCK:
        predict_block(xhat, Pc, c, C0, dt, ebwork, scratch)
        c = 0
    return c


@njit(inline="always", **JIT_NOALLOC)
def env_row(env_at: np.ndarray, r: int, j: int) -> np.ndarray:
    """Run r's environment row j (``N_ENV`` numbers) in its chunk's C-contiguous
    (steps, N_ENV) rows at address ``env_at[r]``."""
    return row_at(env_at[r] + j * (plant.N_ENV * 8), plant.N_ENV)


@njit(inline="always", **JIT_NOALLOC)
def predict_block(
    xhat: np.ndarray,
    Pc: np.ndarray,
    n_cols: int,
    C0: ControlArrays,
    dt: float,
    ebwork: batch_ekf.EkfBlock,
    scratch: np.ndarray,
) -> None:
    """The observers' predictions of the block's ``n_cols`` loaded runs (``batch_ekf``, on
    the batch's control model ``C0``) and their corrections with the samples of their next
    steps (``sense_ahead``), each run's new state and covariance back into its rows of
    ``xhat`` and ``Pc`` and the corrections' innovations into its row ``scratch[r]``
    (``ebwork.runs``)."""
    w = batch_ekf.pad_block(ebwork, n_cols)
    batch_ekf.predict_block_into(ebwork, w, dt, C0.M, C0.M_inv, C0.D_l, C0.D_nl, C0.T_b, C0.GQG)
    batch_ekf.correct_block_into(ebwork, w)
    for c in range(n_cols):
        r = ebwork.runs[c]
        batch_ekf.store_run(ebwork, c, xhat[r], Pc[r])
        loop.log_nis(
            scratch[r],
            batch_ekf.accepted_at(ebwork, c, batch_ekf.A_COMPASS),
            batch_ekf.nis_at(ebwork, c, 0),
            batch_ekf.accepted_at(ebwork, c, batch_ekf.A_POSITION),
            batch_ekf.nis_at(ebwork, c, 1),
            batch_ekf.nis_at(ebwork, c, 2),
        )


@njit(inline="always", **JIT_NOALLOC)
def steps_to_first_end(pos: np.ndarray, length: np.ndarray) -> int:
    """The steps until the first run with a chunk under way (``pos[r] < length[r]``) ends it
    (0 when none is under way): how far ``batch_steps`` goes in one call."""
    h = 0
    for r in range(pos.shape[0]):
        if pos[r] < length[r] and (h == 0 or length[r] - pos[r] < h):
            h = length[r] - pos[r]
    return h


@njit(**JIT_NOALLOC)
def batch_steps(
    pos: np.ndarray,
    length: np.ndarray,
    ok: np.ndarray,
    active: np.ndarray,
    k0: np.ndarray,
    x: np.ndarray,
    held_y: np.ndarray,
    xhat: np.ndarray,
    Pc: np.ndarray,
    cs: np.ndarray,
    target: np.ndarray,
    n_rps: np.ndarray,
    env_at: np.ndarray,
    noise_at: np.ndarray,
    fresh_at: np.ndarray,
    spring_at: np.ndarray,
    PS: Any,
    CS: Any,
    QS: Any,
    dt: float,
    log_at: np.ndarray,
    work: plant.PlantWork,
    W: ControlWork,
    same_plant: np.ndarray,
    P0: plant.PlantArrays,
    bwork: batch_plant.BatchWork,
    scratch: np.ndarray,
    keep: np.ndarray,
    same_model: np.ndarray,
    C0: ControlArrays,
    ebwork: batch_ekf.EkfBlock,
    sensed: np.ndarray,
) -> int:
    """Advance every run with a chunk under way (``pos[r] < length[r]``) step by step, all of
    them one step before any takes the next, until the first of them reaches the end of its
    chunk. Run r's step j (``pos[r]``) is its chunk's step, at time ``(k0[r] + j) dt``, and
    writes its log row j: the step's whole row (``N_LOG`` numbers) is made in ``scratch[r]``
    (zeroed first), then the columns ``keep`` (K indices into the whole row, in order) are
    copied to the K numbers at address ``log_at[r] + j K 8`` (a C-contiguous (steps, K) array
    of the run's own). Its inputs at step j are rows j of its chunk's own C-contiguous arrays
    at addresses ``env_at[r]`` (steps, N_ENV), ``noise_at[r]`` (steps, N_Y), ``fresh_at[r]``
    (steps, N_SENSORS) booleans and ``spring_at[r]`` (steps, 3). ``keep`` is every column
    for a whole log; a lean log (a campaign's runs: ``Simulation.keep_log_columns``) keeps
    the few its scores and legs read, and writes a sixth of the bytes a step. A run whose
    plant state stops being finite at step j ends its chunk there: ``ok[r] = j``,
    ``pos[r] = length[r]``; its rows from j on are left unwritten. Returns the steps taken.

    Each step goes over the runs three times: sensors, control and thrusters (propeller
    speeds into ``n_rps[r]``); the plants' RK4 steps (the runs whose plant is the batch's
    ``P0``, ``same_plant[r]``, together in the structure-of-arrays step of
    ``sim.batch_plant``, in blocks loaded straight from the runs' rows into ``bwork``); the
    observers' predictions and the rows' plant columns (the runs with an observer on the
    batch's control model ``C0``, ``same_model[r]``, predicted together in
    ``control.batch_ekf``'s blocks through ``ebwork``). Such a run whose chunk goes on also
    starts its next step there (``sense_ahead``: its row zeroed, its sensors sampled, their
    signal checks), so its observer corrects with the accepted samples in the block right
    after it predicts (``batch_ekf.correct_block_into``), and ``sensed[r]`` tells the next
    step to begin at the control law (``loop.control_law_into``); a run at its chunk's last
    step, or off the model, starts its next step in the first pass as before. Per run these
    are ``loop._closed_steps``' calls in its order (sensors, checks and corrections, control,
    allocation, thrusters, the RK4 step, ``observe_into``), with the same numbers. Before
    the control of its step, run r's control model's wire spring is set to its chunk's
    spring row j (``control.jobs.ChunkJob.spring``: a chunk past whole seconds refreshes it
    there; the checks and corrections do not read it)."""
    n_runs = pos.shape[0]
    m = CS.f_lo.shape[1]
    n_keep = keep.shape[0]
    row_bytes = n_keep * 8
    n_y, n_sensors = sensors.N_Y, sensors.N_SENSORS
    tau6 = W.vec[loop.W_TAU6, 0:6]
    f = W.vec[loop.W_F, 0:m]
    h = steps_to_first_end(pos, length)
    for _ in range(h):
        for r in range(n_runs):
            active[r] = pos[r] < length[r]
            if not active[r]:
                continue
            j = pos[r]
            prefetch_step(r, j, length, env_at, noise_at, fresh_at, spring_at, log_at, row_bytes)
            set_spring(CS, r, row_at(spring_at[r] + j * 24, 3))
            C = control_view(CS, r)
            row = scratch[r]
            xr, hr = x[r], held_y[r]
            if sensed[r]:  # sampled, checked and corrected at the end of its last step
                sensed[r] = False
                loop.control_law_into(tau6, xr, hr, xhat[r], cs[r], target[r], C, dt, row, W)
            else:
                Q = quality_view(QS, r)
                t = (k0[r] + j) * dt
                for i in range(N_LOG):
                    row[i] = 0.0
                noise_j = row_at(noise_at[r] + j * (n_y * 8), n_y)
                fresh_j = flags_at(fresh_at[r] + j * n_sensors, n_sensors)
                sensors.sample_into(hr, xr, hr, noise_j, fresh_j, sensors.Y_SENSOR)
                loop.control_step_into(
                    tau6, t, xr, hr, fresh_j, xhat[r], Pc[r], cs[r], target[r], C, Q, dt, row, W
                )
            loop.allocate_into(f, tau6, C, W)
            loop.thrusters_into(n_rps[r, 0:m], f, C, row, W)
        plants_into(active, same_plant, pos, x, n_rps, env_at, PS, P0, dt, work, bwork)
        c = 0
        for r in range(n_runs):
            if not active[r]:
                continue
            j = pos[r]
            t = (k0[r] + j) * dt
            C = control_view(CS, r)
            env_j = env_row(env_at, r, j)
            row = scratch[r]
            in_block = observe_run(r, env_j, C, same_model[r], xhat, Pc, row, c, dt, ebwork, W)
            loop.write_plant_row(row, t + dt, x[r], held_y[r], env_j, plant_view(PS, r), work)
            kept = row_at(log_at[r] + j * row_bytes, n_keep)
            for i in range(n_keep):
                kept[i] = row[keep[i]]
            pos[r] = j + 1
            if not plant.all_finite(x[r]):
                ok[r] = j
                pos[r] = length[r]
            elif in_block and j + 1 < length[r]:
                j1 = j + 1
                sense_ahead(
                    (k0[r] + j1) * dt,
                    x[r],
                    held_y[r],
                    row_at(noise_at[r] + j1 * (n_y * 8), n_y),
                    flags_at(fresh_at[r] + j1 * n_sensors, n_sensors),
                    C,
                    quality_view(QS, r),
                    row,
                    c,
                    ebwork,
                    W,
                )
                sensed[r] = True
            if in_block:
                c = end_column(xhat, Pc, c, C0, dt, ebwork, scratch)
        if c > 0:
            predict_block(xhat, Pc, c, C0, dt, ebwork, scratch)
    return h
