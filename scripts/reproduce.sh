#!/usr/bin/env bash
# Reproduce the README's Results from a fresh clone: train configs/five_story.yaml with three
# seeds, evaluate each against the uncontrolled building, LQG and the clairvoyant optimum on the
# seven records, aggregate mean +- std over seeds, trace LQG's trade-off and the value of preview.
#   bash scripts/reproduce.sh [OUT_DIR]        (records from $RLC_RECORDS, else ../shared/records)
# An interrupted run is resumed from its newest checkpoint when the script is started again;
# finished trainings and evaluations are kept (outputs are never overwritten).
set -euo pipefail
cd "$(dirname "$0")/.."
records="${RLC_RECORDS:-../shared/records}"
out="${1:-results/five_story}"
mkdir -p "$out"
for seed in 0 1 2; do
  run="$out/seed$seed"
  if [ ! -f "$run/final_model.zip" ]; then
    if [ -f "$run/config.yaml" ]; then
      rlc train --resume "$run" --no-progress
    else
      rlc train configs/five_story.yaml --seed "$seed" --run-dir "$run" --no-progress
    fi
  fi
  if [ ! -f "$run/evaluation/summary.csv" ]; then
    rlc evaluate "$run" --records "$records" --out "$run/evaluation" > /dev/null
  fi
done
python scripts/aggregate.py "$out"/seed* | tee "$out/results.md"
if [ ! -f "$out/compare_lqg/summary.csv" ]; then
  rlc compare lqg "$out/seed0" --records "$records" --sweep --preview --out "$out/compare_lqg" > /dev/null
fi
echo "tables and plots: $out/seed*/evaluation, $out/compare_lqg, summary: $out/results.md"
