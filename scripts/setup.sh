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
  echo "setup: installing rov-console$extras into .venv" >&2
  .venv/bin/python -m pip install --quiet --disable-pip-version-check --upgrade pip >&2
  .venv/bin/python -m pip install --quiet --disable-pip-version-check -e ".$extras" >&2
  echo "$want" > "$stamp"
fi
# compile the numeric core into numba's cache now, so every run loads the same machine code;
# the cache is kept per version of the sources (sim/numba_cache.py): after a change to them
# this compiles again (a few minutes), otherwise it returns at once
.venv/bin/python -m app.precompile --if-needed >&2
