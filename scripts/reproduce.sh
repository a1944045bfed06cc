#!/usr/bin/env bash
# Reproduce the README's Results from a fresh clone, three seeds of each learned controller, every run
# evaluated on the seven records (rlc sweep: two runs at a time; mean, std, interquartile mean and
# bootstrap intervals over seeds):
#   1. configs/five_story.yaml (the benchmark) and five_story_odd.yaml (odd actor), then LQG's
#      trade-off and the value of preview;
#   2. studies/robustness/five_story_robust.yaml (trained on randomised plants), each seed also through
#      `rlc robustness` (standard scenarios), aggregated per scenario and over all scenarios;
#   3. studies/model_free/five_story_model_free.yaml (readings only: no model, no Kalman filter, no LQG prior;
#      PPO), and the same linear policy learned by random search with common random numbers, on the
#      nominal and on randomised plants (five_story_model_free_random_search[_robust].yaml), each
#      seed of those two also through `rlc robustness`;
#   4. the shipped controllers (every story actuated, the standard supervisor; models/README.md):
#      configs/experiments/five_story_every_story.yaml and five_story_every_story_robust.yaml (robustness too).
# Steps 1-3: 61 min end to end on a 2-core VM (README, Round 2); step 4 adds 3 x (104-164 s + 199-269 s)
# of training, two at a time, plus robustness (measured per run, not end to end). PPO on randomised
# plants (five_story_model_free_robust.yaml) and five_story_robust_free.yaml are run with their own
# `rlc sweep` commands, README Round 2.
#   bash scripts/reproduce.sh [OUT_DIR] [extra rlc sweep options, e.g. --engine dask --address tcp://HOST:8786]
# Records from $RLC_RECORDS, else ../shared/records. Started again, it redoes only what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
records="${RLC_RECORDS:-../shared/records}"
out="${1:-results/five_story}"
shift || true
sweep() { rlc sweep "$1" --seeds 0-2 --workers 2 --records "$records" --out "$2" "${@:3}"; }

robustness_of() {  # rlc robustness for every seed of a folder, then the aggregate over seeds
  for run in "$1"/seed[0-9]*; do
    if [ ! -f "$run/robustness/robustness.csv" ]; then
      rlc robustness "$run" --records "$records" --out "$run/robustness" > /dev/null
    fi
  done
  rlc aggregate "$1"/seed[0-9]*/robustness --out "$1/robustness_aggregate" > /dev/null
}

sweep configs/five_story.yaml "$out" "$@"
sweep studies/benchmark/five_story_odd.yaml "$out/odd" "$@"
if [ ! -f "$out/compare_lqg/summary.csv" ]; then
  rlc compare lqg "$out/seed0" --records "$records" --sweep --preview --out "$out/compare_lqg" > /dev/null
fi

sweep studies/robustness/five_story_robust.yaml "$out/robust" "$@"
robustness_of "$out/robust"

sweep studies/model_free/five_story_model_free.yaml "$out/model_free" "$@"

sweep studies/model_free/five_story_model_free_random_search.yaml "$out/model_free_random_search" "$@"
robustness_of "$out/model_free_random_search"
sweep studies/model_free/five_story_model_free_random_search_robust.yaml "$out/model_free_random_search_robust" "$@"
robustness_of "$out/model_free_random_search_robust"

sweep configs/experiments/five_story_every_story.yaml "$out/every_story" "$@"
sweep configs/experiments/five_story_every_story_robust.yaml "$out/every_story_robust" "$@"
robustness_of "$out/every_story_robust"

echo "runs and aggregates: $out (benchmark), $out/odd, $out/robust, $out/model_free,"
echo "$out/model_free_random_search, $out/model_free_random_search_robust, $out/every_story,"
echo "$out/every_story_robust (robustness: */robustness_aggregate);"
echo "LQG trade-off and preview: $out/compare_lqg"
