#!/usr/bin/env bash
# Reproduce docs/devices.md's, docs/wind.md's and docs/yielding.md's learned-against-classical tables from a
# fresh clone: three seeds of each learned controller (rlc sweep: mean, std, interquartile mean and
# bootstrap intervals over seeds), every run evaluated on the seven records, and each device's classical
# trade-off on the same records:
#   1. MR dampers on stories 1, 3, 5 (five_story_mr.yaml: model-free random search, 10 M steps; the same
#      with an affine policy started at full voltage, five_story_mr_affine.yaml, and on a reward without
#      the force term, five_story_mr_affine_peak.yaml), with the passive voltage levels and clipped-optimal
#      weights swept (rlc compare lqg --sweep), and every classical answer's safety check;
#   2. the roof active mass driver (five_story_amd.yaml: residual on LQG + ground model, 10 M steps), with
#      LQG's force-weight trade-off, and the learner x observation ablation on it: PPO on the same residual
#      (five_story_amd_ppo.yaml), random search without the prior on the same estimate
#      (five_story_amd_estimate.yaml) and on the model-free integrated readings (five_story_amd_model_free.yaml),
#      PPO on the model-free readings (five_story_amd_ppo_model_free.yaml); the stroke weight x 10 and x 100,
#      a reward aimed at J1 (five_story_amd_peak.yaml), LQG + ground model over its force and stroke weights
#      and driver detuning on the records and 200 generated motions (studies/devices/mass_driver_lqg_grid.py), and
#      the residual trained on detuned drivers (five_story_amd_detuned.yaml, by PPO five_story_amd_detuned_ppo.yaml,
#      and on the robust prior: the stroke weight x 10), each seed run on configs/scenarios/driver_detuning.yaml;
#   3. the yielding building (five_story_yielding.yaml: residual on LQG + ground model designed on the
#      elastic building, trained on yielding plants under strong generated shaking), with LQG's trade-off on
#      the yielding plant, and every seed also on 50 generated strong motions (PGA 0.3-1.2 g, a seed of
#      their own);
#   4. the 76-story wind benchmark's active TMD (seventy_six_story_atmd.yaml: residual on LQG + wind model,
#      12 M steps), evaluated on the wind suite configs/loads/wind_76.yaml.
# Wall time on 2 CPU cores, two runs at a time: about 35 min (1) + 70 min (2) + 10 min (3) + 35 min (4).
#   bash scripts/reproduce_devices.sh [OUT_DIR] [extra rlc sweep options]
# Records from $RLC_RECORDS, else ../shared/records. Started again, it redoes only what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
records="${RLC_RECORDS:-../shared/records}"
out="${1:-results/devices}"
shift || true
sweep() { rlc sweep "$1" --seeds 0-2 --workers 2 --out "$2" "${@:3}"; }
once() {  # run "$@" unless its output folder (the value after --out) already has a summary
  local target="${*: -1}"
  [ -f "$target/summary.csv" ] || [ -f "$target/damper_sweep.csv" ] || [ -f "$target/lqg_sweep.csv" ] ||
    [ -f "$target/robustness.csv" ] || "$@" > /dev/null
}

sweep configs/experiments/five_story_mr.yaml "$out/mr" --records "$records" "$@"
once rlc compare lqg --config configs/experiments/five_story_mr.yaml --records "$records" --sweep --out "$out/mr/classical"
sweep studies/devices/five_story_mr_affine.yaml "$out/mr_affine" --records "$records" "$@"
sweep studies/devices/five_story_mr_affine_peak.yaml "$out/mr_affine_peak" --records "$records" "$@"

sweep configs/experiments/five_story_amd.yaml "$out/amd" --records "$records" "$@"
once rlc compare lqg --config configs/experiments/five_story_amd.yaml --records "$records" --sweep --out "$out/amd/classical"
for ablation in ppo estimate model_free ppo_model_free peak detuned detuned_ppo; do
  sweep "studies/devices/five_story_amd_$ablation.yaml" "$out/amd_$ablation" --records "$records" "$@"
done
sweep configs/experiments/five_story_amd.yaml "$out/amd_stroke" --set reward.terms.3.weight=10,100 --records "$records" "$@"
sweep studies/devices/five_story_amd_detuned.yaml "$out/amd_detuned_stroke" --set reward.terms.3.weight=10 \
  --records "$records" "$@"
for run in "$out"/amd_detuned/seed[0-9]* "$out"/amd_detuned_ppo/seed[0-9]*; do
  once rlc robustness "$run" --records "$records" --scenarios configs/scenarios/driver_detuning.yaml --out "$run/detuning"
done
[ -d "$out/generated" ] || python scripts/generated_records.py "$out/generated" > /dev/null
if [ ! -f "$out/amd/lqg_grid.md" ]; then
  python studies/devices/mass_driver_lqg_grid.py --records "$records" "$out/generated" --plot "$out/amd/tradeoff.png" \
    --runs "$out"/amd/seed[0-9]* "$out"/amd_peak/seed[0-9]* "$out"/amd_detuned/seed[0-9]* > "$out/amd/lqg_grid.md.tmp"
  mv "$out/amd/lqg_grid.md.tmp" "$out/amd/lqg_grid.md"
fi

sweep configs/experiments/five_story_yielding.yaml "$out/yielding" --records "$records" "$@"
once rlc compare lqg --config configs/experiments/five_story_yielding.yaml --records "$records" --sweep --out "$out/yielding/classical"
if [ ! -d "$out/yielding/strong_motions" ]; then
  python scripts/generated_records.py "$out/yielding/strong_motions" --count 50 --config configs/excitations/strong.yaml > /dev/null
fi
for run in "$out"/yielding/seed[0-9]*; do
  once rlc evaluate "$run" --records "$out/yielding/strong_motions" --out "$run/strong_motions"
done
rlc aggregate "$out"/yielding/seed[0-9]*/strong_motions --out "$out/yielding/strong_motions_aggregate" > /dev/null
for device in mr amd yielding; do
  check="$out/$device/classical_check.txt"
  [ -f "$check" ] || { python studies/devices/check_classical.py "configs/experiments/five_story_$device.yaml" > "$check.tmp" &&
    mv "$check.tmp" "$check"; }
done

sweep configs/experiments/seventy_six_story_atmd.yaml "$out/wind" --records configs/loads/wind_76.yaml "$@"

echo "runs and aggregates: $out/mr, $out/amd, $out/yielding (strong motions: $out/yielding/strong_motions_aggregate),"
echo "$out/wind; each device's classical trade-off: $out/*/classical, its safety check: $out/*/classical_check.txt"
