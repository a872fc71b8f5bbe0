#!/usr/bin/env bash
# Set up (if needed) and start the product on its embedded defaults: the operator console
# (3D view at http://127.0.0.1:8080/, API at http://127.0.0.1:8000/docs). Extra arguments go
# to `rov-console serve` (e.g. --mission sea-trial-appendix-c).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
exec .venv/bin/rov-console serve "$@"
