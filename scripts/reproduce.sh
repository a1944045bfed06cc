#!/usr/bin/env bash
# Reproduce the README's Results from a fresh clone: train configs/five_story.yaml and its odd-actor
# variant (five_story_odd.yaml) with three seeds each and evaluate every run on the seven records
# (rlc sweep: two runs at a time, mean, std, interquartile mean and bootstrap intervals over seeds),
# then trace LQG's trade-off and the value of preview. About 15 min on a 2-core machine.
#   bash scripts/reproduce.sh [OUT_DIR] [extra rlc sweep options, e.g. --engine dask --address tcp://HOST:8786]
# Records from $RLC_RECORDS, else ../shared/records. Started again, it redoes only what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
records="${RLC_RECORDS:-../shared/records}"
out="${1:-results/five_story}"
shift || true
rlc sweep configs/five_story.yaml --seeds 0-2 --workers 2 --records "$records" --out "$out" "$@"
rlc sweep configs/five_story_odd.yaml --seeds 0-2 --workers 2 --records "$records" --out "$out/odd" "$@"
if [ ! -f "$out/compare_lqg/summary.csv" ]; then
  rlc compare lqg "$out/seed0" --records "$records" --sweep --preview --out "$out/compare_lqg" > /dev/null
fi
echo "runs: $out/seed*, $out/odd/seed*; aggregates: $out/aggregate.md, $out/odd/aggregate.md; LQG trade-off and preview: $out/compare_lqg"
