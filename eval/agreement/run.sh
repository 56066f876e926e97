#!/usr/bin/env bash
# Agreement study: the analytic labeller against the simulated cup on 1,000 random reachable
# known-state grasps over the three evaluation sets (seeded). Writes agreement.json (every trial
# and the per-set figures) beside this script. About 1.5 minutes on 2 cores.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/../.."
bin=".venv/bin/suctionbench"
out="$("$bin" bench agreement --sets basic,typical,adversarial --trials 1000 --workers "${WORKERS:-2}" --seed 0 --json)"
printf '%s\n' "$out" | tail -n 1 | python3 -m json.tool > "$here/agreement.json.tmp"
mv "$here/agreement.json.tmp" "$here/agreement.json"
