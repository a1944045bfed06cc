"""Write the model card (card.md) of every shipped controller in models/.

Usage: python scripts/model_cards.py [--records ../shared/records] [--models models] [NAME ...]

Each card says what the controller is, what it observes, how it was trained, its numbers on the seven
records (J1-J4, `rlc evaluate`; a controller for wind: on its wind suite, with the comfort criteria), on
the safety check's generated suite and at rest (its verdict, `best_check.yaml`, written by `rlc check`),
and over the experiment's standard robustness scenarios (`rlc robustness`). Run `rlc check` on a model
before this script: the card quotes the verdict file.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import yaml

from rlcontroller.api.certify import certificate_card_lines
from rlcontroller.config import load_experiment, load_scenarios
from rlcontroller.config.scenarios import standard_scenarios
from rlcontroller.control.mpc import DEFAULT_HORIZON
from rlcontroller.control.mpc_controllers import MPCController
from rlcontroller.control.policy_file import read_policy
from rlcontroller.control.supervisor import trigger_readings
from rlcontroller.evaluation.evaluation import compare
from rlcontroller.evaluation.robustness import robustness, summary
from rlcontroller.evaluation.tables import markdown_table
from rlcontroller.evaluation.verdict import Verdict
from rlcontroller.files import atomic_write
from rlcontroller.physics.motions.loads import load_suite
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[1]
WIND_SUITES = {  # by model
    "five_story_wind": REPOSITORY / "configs" / "loads" / "wind.yaml",
}
WIND_COLUMNS = ("J1", "J2", "rms_acceleration_top", "peak_acceleration_top_mg", "stroke_m")
RECORDS_TITLE = "The seven records (../shared/records: PEER NGA-West2, as recorded)"

# What each shipped controller is and why it is shipped, the experiment it was made from, and training wall
# times (`rlc train CONFIG`, 2 CPU cores, other jobs running).
ABOUT = {
    "five_story_every_story": (
        "The five-story building with an actuator on every story (100 kN each) behind the faded supervisor "
        "(configs/supervisors/faded.yaml), controlled by the learned MPC: a network (2 x 64, tanh) on the "
        "observation's Kalman estimate, taught by DAgger to act as MPC over 20 control steps with the "
        "experiment's cost (the floors' accelerations in it) and the force limits as constraints "
        "(docs/mpc.md). Shipped as the default by the rule: it passes the safety check with the lowest mean "
        "J1 + J2 on the check suite, 0.302 + 0.610 = 0.912 on round 7's suite, against the best classical "
        "law behind the same supervisor, LQG + ground, 0.316 + 0.635 = 0.951 (docs/scoreboard.md). Round 7 "
        "re-chose its supervisor's trigger on suites of the check's family with other seeds (0.15-0.6 m/s^2, "
        "from 0.1-0.3: sensor noise alone drove that one to the at-rest bound; docs/safety_check.md, 'Round "
        "7'). MPC itself does not ship: a shipped controller exports to ONNX, and a quadratic program every "
        "step does not (models/README.md).",
        "studies/mpc/five_story_every_story_dagger.yaml",
        "42 min (stopped at 579 k steps, the best at 105 k)",
    ),
    "five_story_yielding": (
        "The five-story building with an actuator on every story (100 kN each) on stories that yield "
        "(Bouc-Wen, 3 cm yield drift, 10 % post-yield stiffness), behind the yielding building's supervisor "
        "(configs/supervisors/yielding.yaml: a trigger at 0.2-0.6 m/s^2, the dissipative rule on stroke "
        "velocities integrated from the floors' accelerations, and past 2 cm of estimated story drift a "
        "hand-over for good to stiffness-proportional viscous dampers on those measured velocities), "
        "controlled by the learned MPC: a network (2 x 64, tanh) on the observation's Kalman estimate, "
        "taught by DAgger to act as MPC over 20 control steps with the floors' accelerations in the cost, "
        "MPC designed on the elastic design model, the rollouts on the yielding plant under motions of the "
        "check's family (round 6's) drawn with other seeds. Shipped by the rule: on round 6's suite it "
        "passed and dominated with the lowest mean J1 + J2, 0.549 + 0.749 = 1.298, against LQG + ground "
        "model with the same cost 1.317 and with the experiment's cost (the controller shipped before it) "
        "1.324. On round 7's suite it passes and dominates again, 0.457 + 0.746 = 1.203, against the best "
        "classical law behind its supervisor, LQG + ground, at 0.462 + 0.750 = 1.212: learning does not win "
        "by the 5 % that counts (docs/scoreboard.md).",
        "studies/mpc/five_story_yielding_ship_dagger.yaml",
        "7 min (417 k steps, the best at 314 k)",
    ),
    "five_story_mr_standard": (
        "MR dampers (100 kN, Spencer et al.'s model) on stories 1, 3 and 5 of the five-story building, their "
        "voltages commanded by a learned affine law on the floors' accelerations and the dampers' measured "
        "forces: random search started at passive-off (the check's own reference) and climbing the "
        "standard's objective on motions of the check's family (other seeds), selected by the standard on "
        "128 validation motions. It passes and dominates round 7's check suite (0 of 249 significant motions "
        "worse than the dampers at passive-off by more than 1 %, 14 worse by less), at mean J1 0.986, J2 "
        "0.998: it barely acts. Round 6's law, searched on the broad motions (8 of 298 worse on round 6's "
        "suite, J1 0.917), fails round 7's (20 of 249, J1 0.935, J2 1.039). The field's classical answers "
        "fail both: passive-on 122 of 249 worse, clipped-optimal 81 (a held voltage moves the drift to "
        "stories 2 and 4, which have no damper; docs/safety_check.md).",
        "studies/devices/five_story_mr_standard.yaml",
        "9 min (30 M steps, the best at 9.3 M)",
    ),
    "five_story_paper_layout": (
        "The paper's layout: the five-story building with actuators on stories 1, 3 and 5 (100 kN each) "
        "behind the standard supervisor (a ground trigger at 0.25-1.0 m/s^2 and the dissipative rule), "
        "controlled by the learned MPC: a network (2 x 64, tanh) on the observation's Kalman estimate, "
        "taught by DAgger to act as MPC over 20 control steps with the floors' accelerations in the cost, on "
        "motions of the check's family drawn with other seeds. It ships under round 6's standard, which "
        "states a risk: on round 7's suite 3 of the 273 significant check motions are worse than the "
        "building without control by more than 1 % (95 % bound 2.8 %, at most 5 % allowed); no motion "
        "reaches a higher performance level. By the rule (lowest mean J1 + J2 on the check suite) it ties "
        "LQG + ground model behind the same supervisor, 0.609 + 0.905 = 1.514 against 0.609 + 0.912 = 1.521, "
        "3 worse each (round 6's suite: 1.444 against 1.446): where the limits rarely bind MPC is LQG. "
        "Target J1 <= 0.55 on the check suite: missed (0.609): with three actuators the unactuated stories "
        "keep most of their drift (docs/safety_check.md).",
        "studies/mpc/five_story_paper_layout_dagger.yaml",
        "4 min (417 k steps, the best at 417 k)",
    ),
    "five_story_wind": (
        "The five-story building with an actuator on every story (100 kN each), controlled against wind for "
        "occupant comfort by the learned MPC: a network (2 x 64, tanh) on the observation's Kalman estimate "
        "(LQG + wind model's filter, which also models the ground from its reading: the building it protects "
        "will also shake), taught by DAgger to act as MPC over 20 control steps on the wind model's map, "
        "which plans around the force limits strong winds reach where LQG + wind model clips; trained on "
        "generated wind, each load with no delay or one control step of it (drawn), and selected by the "
        "standard on generated wind (a loop stable with a 20 ms actuator lag and one step of delay first: "
        "the check judges both since issue 80; the round-6 controller, trained without the delay, was "
        "unstable one step late, spectral radius 1.0018). Behind the wind supervisor "
        "(configs/supervisors/wind.yaml): a trigger at 0.3-1.0 m/s^2 on the floors' accelerations, which "
        "wind and earthquakes both move, so that sensor noise never drives it. Shipped by the rule: wind "
        "suite J1 + J2 0.745 against LQG + wind model's 0.757 (the controller shipped before round 6), no "
        "wind load worse. What it gives up against that law: one of the 273 significant ground motions worse "
        "than no control by more than 1 % (within the standard's stated risk).",
        "studies/mpc/five_story_wind_dagger.yaml",
        "15 min on a machine shared with a CI run (1.06 M steps, the best at 288 k)",
    ),
}


def observation(folder: Path) -> str:
    experiment = load_experiment(folder / "config.yaml")
    sensors, wind = experiment.sensors, experiment.excitation.generator.kind == "wind"
    readings = ", ".join(f"{m.quantity} (noise {m.noise_std:g})" for m in sensors.measurements)
    parts = [f"{readings} and the ground acceleration, {sensors.history} step(s) of history"]
    if sensors.state_estimate:
        models = [
            *(["the wind's floor forces"] if wind else []),
            *(["ground filter"] if sensors.ground_model else []),
        ]
        parts.append(
            "a Kalman estimate of the building's state" + "".join(f" and {model}" for model in models)
        )
    if sensors.twin:
        parts.append("the fail-safe twin's estimate and each story's running peak drift under it")
    if sensors.integration_cutoff:
        parts.append(f"the readings' model-free integrals (cut-off {sensors.integration_cutoff:g} Hz)")
    if sensors.action_history:
        parts.append(f"the last {sensors.action_history} action(s)")
    return "; ".join(parts)


def supervision(plant: Plant) -> str:
    supervisor = plant.experiment.supervisor
    if supervisor is None:
        return "none (actions go to the actuators as they are)"
    parts = []
    if supervisor.trigger is not None:
        start, full = supervisor.trigger
        # what the trigger reads, as it reads it
        floors = list(trigger_readings(plant)[0]) != [plant.layout.ground]
        watched = "largest floor acceleration reading" if floors else "ground reading"
        parts.append(f"off until the {watched} reaches {start:g} m/s^2, full authority from {full:g} m/s^2")
    measured = supervisor.dissipative == "measured"
    velocity = "measured stroke velocity (integrated floor accelerations)" if measured else "stroke velocity"
    if supervisor.dissipative and supervisor.fade_velocity > 0.0:
        parts.append(
            f"a force that would feed energy into its story is faded out as its {velocity} grows to "
            f"{supervisor.fade_velocity:g} m/s"
        )
    elif supervisor.dissipative:
        parts.append("only forces that take energy out of the building pass")
    if supervisor.fallback is not None:
        fallback = supervisor.fallback
        damping = ", ".join(f"{value / 1e3:g}" for value in fallback.damping)
        parts.append(
            f"once any story's estimated drift passes {fallback.drift:g} m, every actuator acts for good as "
            f"a viscous damper on its measured stroke velocity ({damping} kN s/m, deadband "
            f"{fallback.deadband:g} m/s)"
        )
    return "; ".join(parts)


def card(folder: Path, records: Path) -> str:
    about, config, wall = ABOUT[folder.name]
    experiment = load_experiment(folder / "config.yaml")
    plant = Plant(experiment)
    policy = read_policy(folder, "best", plant)
    wind = WIND_SUITES.get(folder.name)
    motions, label = load_suite(wind or records, None, plant)
    label = label.replace(f"{REPOSITORY}/", "")
    # what it imitates
    extra = (MPCController(plant.design, DEFAULT_HORIZON),) if policy.algorithm == "DAgger" else ()
    table = compare(plant, motions, label, policy=policy, extra=extra).summary()
    scenarios = load_scenarios(standard_scenarios(experiment), experiment)
    if wind:  # yielding stories are not modelled under floor loads (`rlc robustness` skips them alike)
        scenarios = [
            scenario for scenario in scenarios if scenario.plant is None or scenario.plant.hysteresis is None
        ]
    per_scenario = summary(robustness(experiment, scenarios, motions, label, policy=policy)[0])["J1"].unstack(
        "controller"
    )
    verdict = Verdict.read(yaml.safe_load((folder / "best_check.yaml").read_text()))
    lines = [
        f"# {folder.name}",
        "",
        about,
        "",
        f"- **Observation**: {observation(folder)}.",
        f"- **Supervisor**: {supervision(plant)}.",
        (
            f"- **Design** (`rlc design {config}`): {policy.designed}."
            if policy.law
            else f"- **Training**: `{config}` ({policy.algorithm}, {policy.steps:,} steps; {wall} on 2 CPU "
            "cores); selected on generated validation motions, never on records."
        ),
        f"- **Safety check** (`rlc check`): **{verdict.lines()[0].split(': ', 1)[1]}** (the folder's claim "
        f"until re-run: `rlc check models/{folder.name} --verify`)",
        *(f"  -{line[1:]}" for line in verdict.lines()[1:]),
        *certificate_card_lines(folder),
    ]
    columns = WIND_COLUMNS if wind else ("J1", "J2", "J3", "J4")
    title = f"{label}" if wind else RECORDS_TITLE
    lines += ["", f"## {title}", "", markdown_table(table[[c for c in columns if c in table.columns]])]
    if wind:  # a building controlled against wind will also shake
        records_table = compare(
            plant, load_suite(records, None, plant)[0], "records", policy=policy
        ).summary()
        lines += ["", f"## {RECORDS_TITLE}", "", markdown_table(records_table[["J1", "J2", "J3", "J4"]])]
    count = len(scenarios)
    lines += [
        "",
        f"## Robustness: mean J1 over the {count} standard scenarios (the same "
        f"{'loads' if wind else 'records'})",
    ]
    lines += ["", "| controller | mean J1 |", "|---|---|"]
    lines += [f"| {name} | {value:.3f} |" for name, value in per_scenario.mean().items()]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=REPOSITORY.parent / "shared" / "records")
    parser.add_argument("--models", type=Path, default=REPOSITORY / "models")
    parser.add_argument("names", nargs="*", help="only these models (default: every one)")
    arguments = parser.parse_args()
    for folder in sorted(p for p in arguments.models.iterdir() if (p / "best_policy.yaml").is_file()):
        if arguments.names and folder.name not in arguments.names:
            continue
        atomic_write(folder / "card.md", card(folder, arguments.records))
        print(f"wrote {folder / 'card.md'}")


if __name__ == "__main__":
    main()
