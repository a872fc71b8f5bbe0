"""Limits the command line states in its options and help, kept apart from the modules that
use them so that ``rov-console --help`` and an option out of range answer without loading
the simulation (``missions.campaign`` pulls in numba, scipy and the compiled control core,
some 1.4 s of imports)."""

MAX_RUNS_PER_TASK = 32
"""Most runs of a campaign in one Dask task (``missions.campaign.run_block``): enough to
share a task's overhead, few enough that a lost worker costs little."""
