#!/usr/bin/env bash
# The README's first command: set everything up, then plan the default gait
# (L = T = 0.45 s, arm amplitude 23.5 deg, normal arm swing) and print its summary.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
.venv/bin/biped-gait plan --json bags/default_gait.json
