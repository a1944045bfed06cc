"""Study: what each part of the supervisor costs, and the smallest supervisor that passes the check.

Usage: python studies/safety_check/supervisor_study.py [--records ../shared/records] [--out
results/supervisor_study]

LQG + ground model on the five-story building with an actuator on every story
(configs/experiments/five_story_every_story.yaml), designed on two costs — drift, base shear and force
(rewards/drift_shear_force.yaml, the experiment's when the study was made) and the same with the floors'
absolute accelerations (rewards/drift_shear_force_peak_acceleration.yaml, the experiment's since) — behind
each supervisor of `SUPERVISORS`. For each: the safety check's verdict (`evaluation.safety`, the standard),
mean J1 and J2 on a generated selection suite (the standard's generator, PGA 0.02-1.5 g, its own seed) and by
PGA band (generated, 0.02-0.1 g, 0.1-0.3 g, 0.3-1.5 g), and on the seven records (reported, never used to
choose).

The choice, on generated motions only: among the supervisors that pass the check and keep the
0.02-0.1 g band's J1 within 15 % of unsupervised LQG + ground model's (drift, shear and force), the
one with the lowest J1 on the selection suite among those whose J2 there is no higher than
unsupervised LQG + ground model's (same cost). Writes supervisor_study.csv and .md to --out.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd
from pydantic import TypeAdapter

from rlcontroller.assets import SAFETY_STANDARD
from rlcontroller.config import (
    GeneratorConfig,
    RewardConfig,
    SafetyCheckConfig,
    SupervisorConfig,
    load_experiment,
    load_safety_check,
)
from rlcontroller.config.base import read_model
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.evaluation.evaluation import evaluate
from rlcontroller.evaluation.safety import safety_check
from rlcontroller.files import atomic_write
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY
from rlcontroller.physics.motions.generators import generate_suite
from rlcontroller.physics.motions.records import choose_motions
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[2]
EXPERIMENT = REPOSITORY / "configs/experiments/five_story_every_story.yaml"
COSTS = {
    "drift, shear, force": REPOSITORY / "configs/rewards/drift_shear_force.yaml",
    "+ accelerations": REPOSITORY
    / "configs/rewards/drift_shear_force_peak_acceleration.yaml",  # the experiment's
}
SUPERVISORS = {  # name: SupervisorConfig fields (None: no supervisor)
    "none": None,
    "trigger 0.25-1": {"trigger": [0.25, 1.0]},
    "dissipative (hard)": {"dissipative": True},
    "standard: trigger 0.25-1 + dissipative (hard)": {"trigger": [0.25, 1.0], "dissipative": True},
    "trigger 0.25-0.3": {"trigger": [0.25, 0.3]},
    "trigger 0.15-0.3": {"trigger": [0.15, 0.3]},
    "trigger 0.1-0.3": {"trigger": [0.1, 0.3]},
    "trigger 0.05-0.25": {"trigger": [0.05, 0.25]},
    "trigger 0.1-0.3 + dissipative (hard)": {"trigger": [0.1, 0.3], "dissipative": True},
    **{
        f"trigger 0.1-0.3 + dissipative, fade {fade:g} m/s": {
            "trigger": [0.1, 0.3],
            "dissipative": True,
            "fade_velocity": fade,
        }
        for fade in (0.02, 0.05, 0.1, 0.2, 0.5)
    },
    "trigger 0.25-1 + dissipative, fade 0.1 m/s": {
        "trigger": [0.25, 1.0],
        "dissipative": True,
        "fade_velocity": 0.1,
    },
}
BANDS_G = {"0.02-0.1 g": (0.02, 0.1), "0.1-0.3 g": (0.1, 0.3), "0.3-1.5 g": (0.3, 1.5)}
SELECTION_SEED, BAND_SEED = 2026, 2027  # neither the check's (31337) nor any training or validation seed


def in_band(generator: GeneratorConfig, low_g: float, high_g: float) -> GeneratorConfig:
    """The standard's generator with every component's PGA log-uniform in [low_g, high_g] (g)."""
    raw = generator.model_dump(mode="json")
    for component in raw["components"]:
        component["generator"]["pga"] = [low_g * STANDARD_GRAVITY, high_g * STANDARD_GRAVITY]
    return TypeAdapter(GeneratorConfig).validate_python(raw)


def generated_suites(standard: SafetyCheckConfig) -> dict[str, list]:
    """The selection suite (200 motions, 0.02-1.5 g) and each band's (100 motions) of the standard's
    generator."""
    suites = {"selection": generate_suite(in_band(standard.generator, 0.02, 1.5), 200, SELECTION_SEED)}
    for offset, (band, (low, high)) in enumerate(BANDS_G.items()):
        suites[band] = generate_suite(in_band(standard.generator, low, high), 100, BAND_SEED + offset)
    return suites


def study(records: Path) -> pd.DataFrame:
    standard = load_safety_check(SAFETY_STANDARD)
    suites = generated_suites(standard) | {"seven records": choose_motions(records)[0]}
    experiment = load_experiment(EXPERIMENT)
    rows = []
    for cost, path in COSTS.items():
        reward = read_model(path, RewardConfig, "'terms'")
        for name, fields in SUPERVISORS.items():
            supervisor = None if fields is None else SupervisorConfig(**fields)
            plant = Plant(experiment.model_copy(update={"supervisor": supervisor}))
            lqg = LQGController(
                design_lqg_ground_model(plant.design, reward=reward), plant.design, "LQG + GM"
            )
            verdict = safety_check(plant, lqg, standard, scenarios=[])
            suite = verdict.criteria["check suite"]
            row = {
                "cost": cost,
                "supervisor": name,
                "check": "pass" if verdict.passed else "FAIL",
                "check_failures": suite.failure_count,
                "check_mean_J1": suite.mean_J1,
                "at_rest": verdict.criteria["at rest"].peak_drift_over_bound,
            }
            for suite_name, motions in suites.items():
                summary = (
                    evaluate(plant, motions, [lqg], suite_name, include_optimal=False).summary().loc[lqg.name]
                )
                row |= {
                    f"{suite_name} J1": round(float(summary["J1"]), 4),
                    f"{suite_name} J2": round(float(summary["J2"]), 4),
                }
            rows.append(row)
            print(
                f"{cost:22s} {name:52s} {row['check']:4s} "
                f"selection {row['selection J1']:.3f} / {row['selection J2']:.3f}",
                flush=True,
            )
    return pd.DataFrame(rows)


def chosen(table: pd.DataFrame) -> pd.Series:
    """The supervisor and cost the rule in the module docstring picks, from generated motions only."""
    unsupervised = table[(table["supervisor"] == "none") & (table["cost"] == next(iter(COSTS)))].iloc[0]
    eligible = table[
        (table["check"] == "pass")
        & (table["0.02-0.1 g J1"] <= 1.15 * unsupervised["0.02-0.1 g J1"])
        & (table["selection J2"] <= unsupervised["selection J2"])
    ]
    return eligible.sort_values("selection J1").iloc[0]


def markdown(table: pd.DataFrame, pick: pd.Series) -> str:
    columns = ["cost", "supervisor", "check", "check_failures", "at_rest", "selection J1", "selection J2"]
    columns += [f"{band} {metric}" for band in BANDS_G for metric in ("J1", "J2")]
    columns += ["seven records J1", "seven records J2"]
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for _, row in table.iterrows():
        cells = [f"{row[c]:.3f}" if isinstance(row[c], float) else str(row[c]) for c in columns]
        if row.name == pick.name:
            cells[1] = f"**{cells[1]}** (chosen)"
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=REPOSITORY.parent / "shared" / "records")
    parser.add_argument("--out", type=Path, default=REPOSITORY / "results" / "supervisor_study")
    arguments = parser.parse_args()
    table = study(arguments.records)
    pick = chosen(table)
    arguments.out.mkdir(parents=True, exist_ok=True)
    atomic_write(arguments.out / "supervisor_study.csv", table.to_csv(index=False))
    atomic_write(arguments.out / "supervisor_study.md", markdown(table, pick))
    print(
        f"chosen: {pick['supervisor']} with {pick['cost']}: "
        f"J1 {pick['selection J1']:.3f}, J2 {pick['selection J2']:.3f} "
        f"on the selection suite; seven records {pick['seven records J1']:.3f} / "
        f"{pick['seven records J2']:.3f}"
    )


if __name__ == "__main__":
    main()
