"""Write the model card (card.md) of every shipped controller in models/.

Usage: python scripts/model_cards.py [--records ../shared/records] [--models models]

Each card says what the controller is, what it observes, how it was trained, its numbers on the seven
records (J1-J4, `rlc evaluate`), on the safety check's generated suite and at rest (its verdict,
`best_check.yaml`, written by `rlc check`), and over the standard robustness scenarios (`rlc
robustness`). Run `rlc check` on a model before this script: the card quotes the verdict file.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import yaml

from rlcontroller.config import load_experiment, load_scenarios
from rlcontroller.control.policy import read_policy
from rlcontroller.evaluation.evaluation import compare
from rlcontroller.evaluation.robustness import robustness, summary
from rlcontroller.evaluation.safety import Verdict
from rlcontroller.files import atomic_write
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.records import load_records

REPOSITORY = Path(__file__).resolve().parents[1]
SCENARIOS = REPOSITORY / "configs" / "scenarios" / "standard.yaml"

# What each shipped controller is and why it is shipped; training wall times of seeds 0-2 (`rlc train CONFIG
# --seed S`, 2 CPU cores, two trainings at a time).
ABOUT = {
    "five_story_every_story": (
        "The five-story building with an actuator on every story (100 kN each) behind the faded supervisor "
        "(configs/supervisors/faded.yaml), controlled by LQG + ground model designed on a cost with the floors' "
        "absolute accelerations: classical, no training. Shipped as the default: it passes the safety check with "
        "the lowest mean J1 + J2 on the check suite; the random-search residual trained on it (the same "
        "experiment, seed 0, best by validation J1 + J2) only ties it (docs/safety_check.md).",
        "configs/experiments/five_story_every_story.yaml",
        "",
    ),
}


def observation(folder: Path) -> str:
    sensors = load_experiment(folder / "config.yaml").sensors
    readings = ", ".join(f"{m.quantity} (noise {m.noise_std:g})" for m in sensors.measurements)
    parts = [f"{readings} and the ground acceleration, {sensors.history} step(s) of history"]
    if sensors.state_estimate:
        parts.append(
            "a Kalman estimate of the building's state" + (" and ground filter" if sensors.ground_model else "")
        )
    if sensors.integration_cutoff:
        parts.append(f"the readings' model-free integrals (cut-off {sensors.integration_cutoff:g} Hz)")
    if sensors.action_history:
        parts.append(f"the last {sensors.action_history} action(s)")
    return "; ".join(parts)


def supervision(experiment) -> str:
    supervisor = experiment.supervisor
    if supervisor is None:
        return "none (actions go to the actuators as they are)"
    parts = []
    if supervisor.trigger is not None:
        start, full = supervisor.trigger
        parts.append(f"off until the ground reading reaches {start:g} m/s^2, full authority from {full:g} m/s^2")
    if supervisor.dissipative and supervisor.fade_velocity > 0.0:
        parts.append(
            "a force that would feed energy into its story is faded out as its stroke velocity grows to "
            f"{supervisor.fade_velocity:g} m/s"
        )
    elif supervisor.dissipative:
        parts.append("only forces that take energy out of the building pass")
    return "; ".join(parts)


def card(folder: Path, records: Path) -> str:
    about, config, wall = ABOUT[folder.name]
    experiment = load_experiment(folder / "config.yaml")
    plant = Plant(experiment)
    policy = read_policy(folder, "best", plant)
    motions, label = load_records(records)
    table = compare(plant, motions, label, policy).summary().round(3)
    scenarios = load_scenarios(SCENARIOS, experiment)
    per_scenario = summary(robustness(experiment, scenarios, motions, label, policy)[0])["J1"].unstack("controller")
    verdict = Verdict(**yaml.safe_load((folder / "best_check.yaml").read_text()))
    lines = [
        f"# {folder.name}",
        "",
        about,
        "",
        f"- **Observation**: {observation(folder)}.",
        f"- **Supervisor**: {supervision(experiment)}.",
        (
            f"- **Design** (`rlc design {config}`): {policy.designed}."
            if policy.law
            else f"- **Training**: `{config}` ({policy.algorithm}, {policy.steps:,} steps; {wall} on 2 CPU cores); "
            "selected on generated validation motions, never on records."
        ),
        f"- **Safety check** (`rlc check`): **{'PASSED' if verdict.passed else 'FAILED'}**",
        *(f"  -{line[1:]}" for line in verdict.lines()[1:]),
    ]
    lines += [
        "",
        "## The seven records (../shared/records: PEER NGA-West2, as recorded)",
        "",
        "| controller | J1 | J2 | J3 | J4 |",
        "|---|---|---|---|---|",
    ]
    lines += [
        f"| {name} | {row.J1:.3f} | {row.J2:.3f} | {row.J3:.3f} | {row.J4:.3f} |" for name, row in table.iterrows()
    ]
    lines += ["", "## Robustness: mean J1 over the 14 standard scenarios (the same records)", ""]
    lines += ["| controller | mean J1 |", "|---|---|"]
    lines += [f"| {name} | {value:.3f} |" for name, value in per_scenario.mean().items()]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=REPOSITORY.parent / "shared" / "records")
    parser.add_argument("--models", type=Path, default=REPOSITORY / "models")
    arguments = parser.parse_args()
    for folder in sorted(p for p in arguments.models.iterdir() if (p / "best_policy.yaml").is_file()):
        atomic_write(folder / "card.md", card(folder, arguments.records))
        print(f"wrote {folder / 'card.md'}")


if __name__ == "__main__":
    main()
