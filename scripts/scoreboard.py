"""Write docs/scoreboard.md: each shipped controller against the best classical law behind the same
supervisor.

Usage: python scripts/scoreboard.py [--records ../shared/records] [--out docs/scoreboard.md] [NAME ...]

Per shipped model (models/*/): its experiment's classical laws (`evaluation.evaluation.classical_controllers`:
the LQGs for actuators and drivers, LQG + wind model under wind, passive-off, passive-on and clipped-optimal
for dampers) and MPC (N = 20, the same cost and limits: `control.mpc.mpc_controller`), each run behind the
model's own supervisor on its plant, are judged by the standard's check-suite criterion (`rlc check`'s code).
Issue 78's rule: the figures that count are on the check suite's *strong* motions, its significant ones with
PGA >= 0.1 g (where limits bind and plants yield; their N stated), and on the seven records (mean J1, J2 over
stories and records). The best classical law is the passing one with the lowest J1 + J2 on the strong motions
(while none passes, the one with the fewest motions worse). Beside it the shipped controller's verdict figures
(its `best_check.yaml`, as `rlc check` wrote them). A learned controller *wins* where its J1 + J2 is at least
5 % below the best classical law's on the records and on the strong motions, with no more motions worse on the
whole check suite. Under wind the check suite is the wind suite (the records still shake the building), all of
it counted. About 20 min on 2 CPU cores.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import yaml

from rlcontroller.api.shipping import unshipped_experiments
from rlcontroller.config import load_experiment, load_safety_check
from rlcontroller.config.scenarios import safety_standard
from rlcontroller.control.mpc import DEFAULT_HORIZON
from rlcontroller.control.mpc_controllers import mpc_controller
from rlcontroller.control.policy_file import read_policy
from rlcontroller.evaluation.evaluation import classical_controllers, compare
from rlcontroller.evaluation.figures import SuiteFigures
from rlcontroller.evaluation.safety import drift_bounds, suite_criterion
from rlcontroller.files import atomic_write
from rlcontroller.physics.motions.loads import load_suite
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[1]
WIN = 0.05  # a learned controller wins at 5 % lower J1 + J2 on both suites, with no more motions worse
STRONG_G = 0.1  # the check suite's motions that count: PGA at least this (g)
# how each learned shipped controller was trained (its command; long runs under nohup with a log)
TRAINING = {
    "five_story_every_story": "rlc train studies/mpc/five_story_every_story_dagger.yaml",
    "five_story_mr_standard": "rlc train studies/devices/five_story_mr_standard.yaml",
    "five_story_paper_layout": "rlc train studies/mpc/five_story_paper_layout_dagger.yaml",
    "five_story_wind": "rlc train studies/mpc/five_story_wind_dagger.yaml",
    "five_story_yielding": "rlc train studies/mpc/five_story_yielding_ship_dagger.yaml",
}
# what was measured where a target is missed, and why (the docs that hold the curves)
MEASURED = {
    "nine_story_frame": (
        "its best law, LQG + ground model behind the measured dissipative rule, judged on the FE frame "
        "(round 6's suite): 7 of 294 worse (bound 4.4 %), but two motions at a higher performance level by "
        "permanent drift (1.23 % against 0.91 %, 1.10 % against 0.69 %): control that cuts a yielding "
        'frame\'s peaks can leave it leaning more (docs/safety_check.md, "Round 6: what ships")'
    ),
    "five_story_amd": (
        "with its end-stops every classical law fails against the driver off (LQG, LQG + ground, LQG + "
        "ground model: 21, 22, 35 of 261 worse, check J1 0.710-0.713); random search from LQG + ground "
        "model on the standard's objective gets to 16 of 261 (bound 9.2 %) at check J1 0.801 and no lower "
        "in 90 M steps (with a network for the residual, 26); SAC from nothing on the driver with its stops "
        "stays at or above the driver off "
        "(validation J1 1.56-1.98 without a trigger, 0.829-0.845 behind one, the driver off 0.834). The risk "
        "is out of this driver's reach: a constant 100 N (1 % of its force) makes 34 weak motions worse, and "
        "a law that acts only until the ground first reads 0.2 g leaves 19-22 of the 60 strong ones worse, "
        "their peaks following the stops' impacts: unblocked by a decision on the tolerance, not a "
        'controller (docs/devices.md, "Round 7: the roof driver with its stops")'
    ),
    "five_story_mr_standard": (
        "every constant command worsens 63-122 of 249 motions against passive-off (the dampers stiffen "
        "stories 1, 3 and 5 and drift moves to 2 and 4), and a network searched on the standard's "
        'objective keeps the dampers off (docs/devices.md, "Round 7: MR dampers")'
    ),
}


def check_figures(criterion: SuiteFigures) -> dict:
    """A suite criterion's figures; J1, J2 and N over its strong motions (all of a wind suite's loads)."""
    rows = [row for row in criterion.per_motion.values() if row.significant]
    strong = [row for row in rows if (STRONG_G if row.pga_g is None else row.pga_g) >= STRONG_G]
    return {
        "J1": criterion.mean_J1,
        "J2": criterion.mean_J2,
        "strong_J1": sum(row.J1 for row in strong) / len(strong),
        "strong_J2": sum(row.J2 for row in strong) / len(strong),
        "strong": len(strong),
        "k": f"{criterion.failure_count}/{criterion.significant_motions}",
        "worse": criterion.failure_count,
        "passed": criterion.passed,
        "dominates": criterion.dominates,
    }


def sum_j(figures: dict) -> float:
    return figures["strong_J1"] + figures["strong_J2"]


def scores(folder: Path, records: Path) -> dict:
    """The shipped controller's and the best classical law's figures, on the check suite and the records."""
    experiment = load_experiment(folder / "config.yaml")
    plant = Plant(experiment)
    policy = read_policy(folder, "best", plant)
    standard = load_safety_check(safety_standard(experiment))
    verdict = yaml.safe_load((folder / "best_check.yaml").read_text(encoding="utf-8"))
    shipped = check_figures(SuiteFigures.read(verdict["criteria"]["check suite"])) | {
        "passed": verdict["passed"]
    }
    shipped["dominates"] = verdict["dominates"]  # every suite (under wind the ground motions' too)
    judged = []
    for controller in [*classical_controllers(plant), mpc_controller(plant.design, DEFAULT_HORIZON)]:
        criterion = suite_criterion(plant, controller, standard, drift_bounds(plant, standard))
        judged.append((controller.name, check_figures(criterion)))
    passing = [item for item in judged if item[1]["passed"]]
    name, classical = min(
        passing or judged, key=lambda item: (item[1]["worse"] * (not passing), sum_j(item[1]))
    )
    motions, label = load_suite(records, None, plant)
    mpc = () if name in table_names(plant) else (mpc_controller(plant.design, DEFAULT_HORIZON),)
    table = compare(plant, motions, label, policy=policy, extra=mpc).summary()
    on_records = {
        key: table.loc[row, ["J1", "J2"]].tolist()
        for key, row in (("shipped", policy.name), ("classical", name))
    }
    return {
        "shipped": shipped,
        "classical": classical,
        "classical_name": name,
        "records": on_records,
        "kind": "classical" if policy.law else f"learned ({policy.algorithm})",
        "judged": judged,
    }


def table_names(plant: Plant) -> list[str]:
    """The controllers `evaluation.compare` runs anyway."""
    return [controller.name for controller in classical_controllers(plant)]


def wins(row: dict) -> bool:
    shipped, classical, records = row["shipped"], row["classical"], row["records"]
    on_check = sum_j(shipped) <= (1.0 - WIN) * sum_j(classical)
    on_records = sum(records["shipped"]) <= (1.0 - WIN) * sum(records["classical"])
    return row["kind"] != "classical" and on_check and on_records and shipped["worse"] <= classical["worse"]


def lead(shipped: float, classical: float) -> str:
    """How far below the classical law's J1 + J2 the shipped one's is (negative: above)."""
    return f"{1.0 - shipped / classical:+.1%}"


def page(rows: dict[str, dict], nothing: list[str]) -> str:
    lines = [
        "# Scoreboard: the shipped controllers against the best classical law",
        "",
        "Written by `python scripts/scoreboard.py` (its docstring says how). Check suite: the safety check's "
        "320 generated motions against the building failed safe; *strong*: its significant motions with PGA "
        ">= 0.1 g (N of them), where limits bind and plants yield (under wind: every wind load); mean J1, J2 "
        "over them; k = motions worse by more than 1 % of N significant on the whole suite; *dominates*: k = "
        "0 and passed, for the shipped controller on every suite it is judged on. Records: the seven PEER "
        "records against the uncontrolled building. The classical set (LQG variants or passive settings and "
        "clipped-optimal, and MPC with N = 20, the same cost and limits) runs behind the shipped "
        "controller's own supervisor; the best is the passing one with the lowest J1 + J2 on the strong "
        "motions. A learned controller wins at J1 + J2 at least 5 % below the best classical law's on the "
        "strong motions and on the records, with no more motions worse (issue 78's rule). *Lead*: how far "
        "below the classical law's J1 + J2 the shipped controller's is.",
        "",
        "| model | shipped | N strong | strong J1 | J2 | k | dominates | records J1 | J2 | best classical "
        "law | strong J1 | J2 | k | records J1 | J2 | lead strong | lead records | learned wins |",
        "|---" * 18 + "|",
    ]
    for name, row in rows.items():
        s, c, r = row["shipped"], row["classical"], row["records"]
        lines.append(
            f"| {name} | {row['kind']} | {s['strong']} | {s['strong_J1']:.3f} | {s['strong_J2']:.3f} | "
            f"{s['k']} | {'yes' if s['dominates'] else 'no'} "
            f"| {r['shipped'][0]:.3f} | {r['shipped'][1]:.3f} | {row['classical_name']}"
            f"{'' if c['passed'] else ' (fails)'} | {c['strong_J1']:.3f} | {c['strong_J2']:.3f} | {c['k']} "
            f"| {r['classical'][0]:.3f} | {r['classical'][1]:.3f} | {lead(sum_j(s), sum_j(c))} "
            f"| {lead(sum(r['shipped']), sum(r['classical']))} | {'**yes**' if wins(row) else 'no'} |"
        )
    lines += ["", "The whole check suite (significant motions, as the verdicts state them):", ""]
    lines += [
        "| model | shipped J1 | J2 | best classical law | J1 | J2 | every classical law: strong J1 + J2, k |"
    ]
    lines += ["|---" * 7 + "|"]
    for name, row in rows.items():
        s, c = row["shipped"], row["classical"]
        others = "; ".join(
            f"{law} {sum_j(figures):.3f}, {figures['k']}{'' if figures['passed'] else ' (fails)'}"
            for law, figures in row["judged"]
        )
        lines.append(
            f"| {name} | {s['J1']:.3f} | {s['J2']:.3f} | {row['classical_name']} | {c['J1']:.3f} "
            f"| {c['J2']:.3f} | {others} |"
        )
    learned = [name for name, row in rows.items() if row["kind"] != "classical"]
    won = sum(wins(row) for row in rows.values())
    total = len(rows) + len(nothing)
    lines += [
        "",
        f"Learned controllers ship on {len(learned)} of the {total} experiments ({len(rows)} here; "
        f"nothing ships for {', '.join(nothing) or 'none'}: models/README.md says why); {won} win by 5 %.",
    ]
    if not won:
        lines += ["", 'Why none wins by 5 % where it counts: docs/mpc.md, "Why none wins by 5 %".']
    lines += ["", "## Issue 78's targets", ""] + targets(rows, nothing, won)
    lines += ["", "## How the learned ones were trained", ""]
    lines += [f"- `{name}`: `{TRAINING.get(name, 'see its card.md')}`" for name in learned]
    return "\n".join(lines) + "\n"


def targets(rows: dict[str, dict], nothing: list[str], won: int) -> list[str]:
    """Where each of issue 78's targets stands, from the rows (the records' and check suite's figures)."""

    def shipped(name: str, bound: float) -> str:
        if name in nothing or name not in rows:
            return f"missed: nothing ships for {name}; {MEASURED[name]}"
        row = rows[name]
        met = row["shipped"]["J1"] <= bound and wins(row)
        won = "yes" if wins(row) else "no"
        figures = f"check J1 {row['shipped']['J1']:.3f}, wins: {won}"
        return f"met: {figures}" if met else f"missed: {figures}; {MEASURED[name]}"

    return [
        f"1. The FE frame ships: {shipped('nine_story_frame', 1.0)}.",
        f"2. The roof driver, J1 <= 0.85 and wins: {shipped('five_story_amd', 0.85)}.",
        f"3. MR dampers, J1 <= 0.90 and wins: {shipped('five_story_mr_standard', 0.90)}.",
        f"4. Learned wins on >= 3 experiments: {'met' if won >= 3 else 'missed'} ({won}); where limits bind "
        'MPC is the lead to win and its imitations tie it (docs/mpc.md, "Why none wins by 5 %"); random '
        "search aimed at the peaks (objective: peaks) beats MPC on the default's strong check motions by "
        "7-11 % and loses 3-5 % to it on the seven records; on the yielding building it trails LQG + ground "
        'by 1-2 % on the strong motions (docs/mpc.md, "Aimed at the peaks").',
        "5. RL from nothing reaches LQG's validation J1 and J2 in 30 min: reached, not held: the fast SAC "
        "recipe with an odd linear actor and 4 gradient steps per batch step, J1 0.634, J2 0.863 at 3.2 min "
        "(seed 1: 0.647, 0.869 at 1.6 min) against LQG's 0.656, 0.953, then J1 0.69-0.82; with 2 its best is "
        "0.682, 0.804 (before "
        "the odd actor: 0.915 at best); PPO with an odd linear actor crosses it in 10.5-12 min in three "
        'runs and drifts back; no kept policy passes the check: docs/training.md, "From nothing".',
        "6. Off-design mean J1 <= 0.270 over the 14 scenarios: missed: the shipped default 0.295 (its card; "
        "LQG + ground model, nominal design, 0.299); beside round 6's default (0.285), LQG + ground model "
        "re-designed on each scenario's own plant reaches 0.270 over its 11, and the best of the three in "
        "each scenario averages 0.279: a stiffer building, a "
        "40 ms delay and yielding stories cost 0.05-0.11 of J1 that knowing the plant does not give back "
        '(docs/robustness.md, "How far the default\'s family can go off design").',
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=REPOSITORY.parent / "shared" / "records")
    parser.add_argument("--out", type=Path, default=REPOSITORY / "docs" / "scoreboard.md")
    parser.add_argument(
        "names", nargs="*", help="only these models, the others' rows kept (default: every one)"
    )
    parser.add_argument("--from-json", action="store_true", help="the page again from the last run's figures")
    arguments = parser.parse_args()
    if arguments.from_json:
        rows = json.loads(arguments.out.with_suffix(".json").read_text(encoding="utf-8"))
        atomic_write(arguments.out, page(rows, list(unshipped_experiments()[0])))
        return
    kept = arguments.out.with_suffix(".json")
    # the others'
    rows = json.loads(kept.read_text(encoding="utf-8")) if arguments.names and kept.is_file() else {}
    for folder in sorted(p for p in (REPOSITORY / "models").iterdir() if (p / "best_check.yaml").is_file()):
        if arguments.names and folder.name not in arguments.names:
            continue
        rows[folder.name] = scores(folder, arguments.records)
        print(folder.name, rows[folder.name], flush=True)
    atomic_write(kept, json.dumps(rows, indent=1))  # the page again: --from-json
    atomic_write(arguments.out, page(rows, list(unshipped_experiments()[0])))
    print(f"wrote {arguments.out}")


if __name__ == "__main__":
    main()
