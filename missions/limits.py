"""Limits the command line states in its options and help, kept apart from the modules that
use them so that ``rov-console --help`` and an option out of range answer without loading
the simulation (``missions.campaign`` pulls in numba, scipy and the compiled control core,
some 1.4 s of imports)."""

MAX_RUNS_PER_TASK = 32
"""Most runs of a campaign stepped together in one batch (one Dask task,
``missions.campaign.run_block``). Measured on 64 docking runs on one core of an AMD Zen 5
(``benchmarks/batch_benchmark.py --sizes 8,16,32,64``, load 0.6): batches of 16 and 32 ran
3,358x and 3,492x against 2,337x alone, a batch of 64 2,978x (the control steps, still run by
run, then go out of cache). On a Zen 3 batches of 8, 16 and 32 were within the machine's noise
of one another (``docs/speed.md``, sixteenth pass), so 32 stayed."""
