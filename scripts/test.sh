#!/usr/bin/env bash
# Set up (if needed), run the static checks (ruff lint and format, mypy) and the default test
# suite. Extra arguments go to pytest.
# Installs what the tests need beyond Python packages: Debian's chromium (the console is tested
# in a real headless browser) and the JavaScript MCAP reader used to cross-check our logs.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --test
if ! command -v chromium >/dev/null 2>&1; then
  if [[ $(id -u) -eq 0 ]]; then
    echo "test: installing Debian's chromium" >&2
    apt-get update -qq >&2 && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >&2
  else
    echo "test: chromium missing and not root: browser tests will fail" >&2
  fi
fi
if [[ -f tests/js/package.json && ! -d tests/js/node_modules ]]; then
  echo "test: installing the JavaScript test packages" >&2
  (cd tests/js && npm ci --no-audit --no-fund --loglevel=error >&2)
fi
# the numeric core's kernels into numba's cache (after a change of the core; nothing
# otherwise), beside the static checks, so the tests load them instead of compiling
# them inside a console's paced loop
echo "test: compiling the numeric core in the background (python -m app.precompile)" >&2
.venv/bin/python -m app.precompile >&2 &
precompile=$!
# static checks: lint, format and types (CI enforces all three)
code=(sim control missions app web tests benchmarks scripts)
echo "test: ruff check, ruff format --check, mypy" >&2
.venv/bin/ruff check "${code[@]}"
.venv/bin/ruff format --check "${code[@]}"
.venv/bin/mypy
wait "$precompile"
# two workers (this is a 2-core machine); a test module stays on one worker (its module
# fixtures: the browser modules share one server and one Chromium per module), and the browser
# modules all on one worker, one after the other (tests/conftest.py says why and how).
# TEST_WORKERS=0 runs serially.
exec .venv/bin/python -m pytest -n "${TEST_WORKERS:-2}" --dist loadfile --no-loadscope-reorder "$@"
