"""Planning campaigns on Dask: the result store (Parquet parts), the distributed runner, the
report (success rates, the operability envelope) and the ``rov-console campaign`` commands.
The file format and one run live in ``missions.campaign``."""
