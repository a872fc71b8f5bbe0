#!/usr/bin/env bash
# Set up (if needed) and start the product on its embedded defaults.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
exec .venv/bin/rov-console simulate "$@"
