#!/usr/bin/env bash
# Create or refresh the virtual environment at .venv (repository root) with the product and,
# with --test, what the tests need. Safe to run again: it skips work that is already done.
set -euo pipefail
cd "$(dirname "$0")/.."
extras=""
[[ "${1:-}" == "--test" ]] && extras="[test]"
python=${PYTHON:-python3}
if [[ ! -x .venv/bin/python ]]; then
  echo "setup: creating .venv" >&2
  "$python" -m venv .venv
fi
stamp=".venv/.installed$(echo "$extras" | tr -d '[]')"
want="$(sha256sum pyproject.toml | cut -c1-16)"
if [[ ! -f "$stamp" || "$(cat "$stamp")" != "$want" ]]; then
  echo "setup: installing rov-console$extras and its packages into .venv" >&2
  # uv (from PyPI, into the venv) resolves and installs in parallel, much faster than pip on
  # a new machine (docs/performance.md); pip itself if uv cannot be had
  if .venv/bin/python -m pip install --quiet --disable-pip-version-check uv >&2; then
    .venv/bin/uv pip install --quiet --python .venv/bin/python -e ".$extras" >&2
  else
    .venv/bin/python -m pip install --quiet --disable-pip-version-check -e ".$extras" >&2
  fi
  echo "$want" > "$stamp"
fi
# One OpenBLAS kernel for every process of this environment. OpenBLAS chooses its kernels by
# the CPU it finds, and its Haswell, SkylakeX and SapphireRapids kernels round differently in
# the last bits (the set-up's matrix inverses and pseudo-inverses, the controller's
# matrix-vector products each step); a full-scale docking run carries that into its figures
# at 1e-5 relative. Pinned to the Haswell kernels (any x86-64 CPU with AVX2 and FMA runs
# them), a mission with the same seed gives the same figures on every such machine
# (tests/test_reproducible.py). A .pth file's import line runs as Python starts, before numpy
# loads OpenBLAS; an OPENBLAS_CORETYPE set by the user wins.
site_packages=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
cat > "$site_packages/rov_console_openblas.pth" <<'PTH'
import os; os.environ.setdefault("OPENBLAS_CORETYPE", "Haswell") if os.uname().machine == "x86_64" and {"avx2", "fma"} <= set(open("/proc/cpuinfo").read().split()) else None
PTH
