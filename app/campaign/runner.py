"""Run a campaign on Dask distributed: an embedded LocalCluster (one single-threaded worker
process per core) or an existing cluster at a scheduler address.

Each task is a block of runs, run one after another (``missions.campaign.run_block``); its rows
are written as it comes back. Tasks of a worker that dies are rescheduled by Dask on the
others; a block that is lost is submitted again run by run (one task each, so that a run that
kills its worker takes no other with it), and a run whose task keeps killing workers (Dask's
``KilledWorker``) is submitted again up to ``LOST_RETRIES`` times, then counted as a run with
an error. The client keeps one row per run whatever happens (a late duplicate is dropped), and
``--resume`` submits only the runs without a row.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import multiprocessing
import os
import time
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import dask

from missions import campaign as cm
from missions import schema

from . import store

POLL_S = 0.1
"""How often the client looks for finished runs [s]."""
LOST_RETRIES = 3
"""Times a run whose worker was lost is submitted again before it counts as an error."""
LOCAL_WORKER_CONFIG: dict[str, Any] = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "1s",
}
LOCAL_WORKER_ENVIRON: dict[str, Any] = {
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None
}
"""Dask settings of the embedded cluster's workers (an existing cluster keeps its own). Dask's
defaults suit workers holding large, changing data; a campaign worker steps small arrays in
a tight loop, and five of them cost it time (some 10-20 % together, measured with
``benchmarks/campaign_benchmark.py``): the statistical profiler (every 10 ms a thread takes
the interpreter lock to sample the running task's stack, for the dashboard's profile page),
``MALLOC_TRIM_THRESHOLD_=65536`` (glibc hands freed memory back to the system above 64 KiB
and faults it in again for the next chunk's arrays; unset, glibc adapts its thresholds) and
the event loop's tick (``distributed.admin.tick.interval``, 20 ms), the loop's check of its
own responsiveness for a warning when it was stuck for 3 s or more, which takes the
interpreter lock from the task 50 times a second: once a second is plenty for a 3 s warning.
The system monitor (each process's CPU, memory, network and disk counters for the dashboard,
every 0.5 s) and the nannies' memory monitor (each worker's memory against its limit, every
0.1 s) run on the same two cores as the workers; every 5 s and every second leave the
dashboard its graphs and a runaway worker's memory caught within a second (what it saves:
``docs/performance.md``). The nannies and the scheduler live in the calling process, so the
settings apply there as well as in the workers.
A threshold in the calling process's own environment still reaches the workers (they inherit
it): the user's own, or one that a nanny with Dask's settings exported there earlier."""


LOCAL_START_METHOD = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
"""How the embedded cluster's nannies start their workers: by forking this process where the
system can (Linux), otherwise as Dask does by default (spawn, a fresh interpreter).

A spawned worker starts an interpreter and imports Dask before the cluster is up, then on its
first task this package, numba and scipy, and loads the compiled kernels, all before it
steps. A forked one has what this process has imported already (measured with
``benchmarks/campaign_benchmark.py``; figures in ``docs/performance.md``).
The process that forks is a command line's (``rov-console campaign``, ``operability``), whose
only other thread is Dask's event loop, the one that forks; the console's server never starts
a cluster. A worker that a nanny starts again after a crash is spawned: the setting holds while
the cluster is made."""


def blocks_of(todo: list[int], size: int) -> list[list[int]]:
    """The runs ``todo`` cut into tasks of ``size`` runs, in order (the last may be shorter)."""
    return [todo[k : k + size] for k in range(0, len(todo), size)]


def shrinking_blocks(todo: list[int], workers: int) -> list[list[int]]:
    """The runs ``todo`` cut into tasks that shrink towards the end (guided self-scheduling):
    each takes the runs left divided by twice the workers, rounded up, at least 1 and at most
    ``MAX_RUNS_PER_TASK``. The first tasks are large, sharing a task's overhead over many
    runs; the last are single runs, so the workers finish within about one run of each other
    instead of one waiting while the other runs a last large block alone (equal blocks of 32
    leave 200 runs on two workers ending with one core idle on a last block of 8)."""
    blocks: list[list[int]] = []
    k = 0
    while k < len(todo):
        size = max(1, min(cm.MAX_RUNS_PER_TASK, -(-(len(todo) - k) // (2 * max(1, workers)))))
        blocks.append(todo[k : k + size])
        k += size
    return blocks


@dataclass
class CampaignProgress:
    """What the campaign has done so far (runs in this session and in earlier ones)."""

    total: int
    done: int = 0
    failed: int = 0
    errors: int = 0
    resubmitted: int = 0
    simulated_s: float = 0.0
    wall_s: float = 0.0


def _cluster_client(scheduler: str | None, workers: int | None) -> Any:
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler, timeout="20s"), None
    # a nanny reads its workers' environment as it starts, and hands each worker it starts
    # (again, after a crash) its own copy of the config: a key given here, not one set
    # around it (the nanny's copy shares the nested settings that a context restores)
    start = {"distributed.worker.multiprocessing-method": LOCAL_START_METHOD}
    with dask.config.set({**LOCAL_WORKER_CONFIG, **LOCAL_WORKER_ENVIRON, **start}):
        cluster = LocalCluster(
            n_workers=workers or os.cpu_count() or 1,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            silence_logs=logging.ERROR,
            config=LOCAL_WORKER_CONFIG,
        )
    return Client(cluster), cluster


@contextlib.contextmanager
def local_cluster(workers: int | None) -> Iterator[str]:
    """An embedded cluster (``_cluster_client``'s) kept up across several ``run_campaign``
    calls: yields its scheduler's address (the operability table runs two passes on it)."""
    client, cluster = _cluster_client(None, workers)
    try:
        yield cluster.scheduler_address
    finally:
        client.close()
        cluster.close()


def task_key(text: str, index: int) -> str:
    """The Dask key of a run: the campaign text's digest and the run index."""
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    return f"campaign-run-{digest}-{index}"


def block_key(text: str, indices: list[int]) -> str:
    """The Dask key of a block of runs (one run: its ``task_key``)."""
    if len(indices) == 1:
        return task_key(text, indices[0])
    digest = hashlib.sha1(text.encode()).hexdigest()[:12]
    return f"campaign-block-{digest}-{indices[0]}-{len(indices)}"


def run_campaign(
    campaign: cm.Campaign,
    base: schema.Mission,
    text: str,
    out: Path,
    scheduler: str | None = None,
    workers: int | None = None,
    resume: bool = False,
    show_progress: bool = True,
    on_row: Callable[[dict, Any], None] | None = None,
    batch: int = 50,
    flush_s: float = 5.0,
    per_task: int | None = None,
    limit: int | None = None,
    only: Collection[int] | None = None,
) -> CampaignProgress:
    """Run every run of the campaign that has no row in ``out`` yet; rows go to Parquet parts
    as they finish. ``on_row(row, client)`` is called after each row (tests use it).
    ``per_task``: runs per task (None: ``shrinking_blocks`` for the cluster's workers).
    ``limit``: run at most this many runs for a quick look (``cm.quick_look_runs``: one of each
    point first); ``resume`` later runs the rest. ``only``: run just these runs (the
    operability table's second pass: more seeds where a cell is near a limit)."""
    from distributed import as_completed

    store.create(out, text, base, resume)
    done = store.done_runs(out)
    chosen = sorted(set(only)) if only is not None else cm.quick_look_runs(campaign, limit)
    todo = [i for i in chosen if i not in done]
    total = campaign.runs if limit is None and only is None else len(set(chosen) | done)
    progress = CampaignProgress(total=total, done=len(done))
    if resume and done:
        prior = store.read_rows(out)
        progress.failed = sum(not r["success"] for r in prior)
        progress.errors = sum(r["simulated_s"] is None for r in prior)
    if not todo:
        return progress
    writer = store.PartWriter(out, batch=batch, flush_s=flush_s)
    client, cluster = _cluster_client(scheduler, workers)
    written: set[int] = set()
    lost: dict[int, int] = {}
    t0 = time.perf_counter()
    try:
        n_workers = len(client.scheduler_info().get("workers", {})) or workers or 1
        blocks = blocks_of(todo, per_task) if per_task else shrinking_blocks(todo, n_workers)
        with _progress_bar(show_progress, campaign.name, progress) as bar:
            futures = {
                client.submit(
                    cm.run_block, campaign, base, block, key=block_key(text, block), pure=False
                ): block
                for block in blocks
            }
            pending = as_completed(list(futures))
            while not pending.is_empty():
                # poll, so that Ctrl-C reaches this thread between polls
                finished = pending.next_batch(block=False)
                if not finished:
                    time.sleep(POLL_S)
                    continue
                for future in finished:
                    block = futures[future]
                    try:
                        rows = future.result()
                    except Exception as err:  # the task itself never raises: a worker was lost
                        future.release()
                        rows = []
                        for index in block:
                            lost[index] = lost.get(index, 0) + 1
                            if lost[index] <= LOST_RETRIES:
                                retry = client.submit(
                                    cm.run_block,
                                    campaign,
                                    base,
                                    [index],
                                    key=f"{task_key(text, index)}-retry{lost[index]}",
                                    pure=False,
                                )
                                futures[retry] = [index]
                                pending.add(retry)
                                progress.resubmitted += 1
                                continue
                            rows.append(
                                cm.failed_row(
                                    cm.run_inputs(campaign, base, index),
                                    f"lost {lost[index]} workers: {type(err).__name__}: {err}",
                                )
                            )
                    future.release()
                    for row in rows:
                        index = int(row["run"])
                        if index in written:
                            continue  # a run counts once
                        written.add(index)
                        writer.add(row)
                        progress.done += 1
                        progress.failed += not row["success"]
                        progress.errors += row["simulated_s"] is None
                        progress.simulated_s += row["simulated_s"] or 0.0
                        bar(progress)
                        if on_row is not None:
                            on_row(row, client)
    finally:
        writer.close()
        progress.wall_s = time.perf_counter() - t0
        client.close()
        if cluster is not None:
            cluster.close()
    return progress


class _Bar:
    def __init__(self, show: bool, name: str, progress: CampaignProgress) -> None:
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.progress = Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("runs, failed {task.fields[failed]}"),
            TimeElapsedColumn(),
            TextColumn("left"),
            TimeRemainingColumn(),
            disable=not show,
            transient=False,
        )
        self.task = self.progress.add_task(
            name, total=progress.total, completed=progress.done, failed=progress.failed
        )

    def __enter__(self) -> Callable[[CampaignProgress], None]:
        self.progress.start()
        return self.update

    def update(self, p: CampaignProgress) -> None:
        self.progress.update(self.task, completed=p.done, failed=p.failed)

    def __exit__(self, *exc: object) -> None:
        self.progress.stop()


def _progress_bar(show: bool, name: str, progress: CampaignProgress) -> _Bar:
    return _Bar(show, name, progress)


def rerun(out: Path, index: int) -> tuple[dict, dict, Any, Any]:
    """Prepare run ``index`` of a results folder again: (stored row, inputs row, mission,
    simulation). The caller drives it (with a recorder, for ``--log``)."""
    campaign, base, _ = store.open_results(out)
    rows = {int(r["run"]): r for r in store.read_rows(out)}
    if index not in rows:
        have = f"0 to {campaign.runs - 1}" if campaign.runs else "none"
        raise cm.CampaignError(
            f"run {index} has no row in {out} (runs of this campaign: {have}; "
            f"{len(rows)} have rows)"
        )
    inputs, mission, sim = cm.prepare_run(campaign, base, index)
    return rows[index], cm.input_row(inputs), mission, sim
