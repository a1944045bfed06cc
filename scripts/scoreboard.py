"""Write docs/scoreboard.md: each shipped controller against the best classical law behind the same supervisor.

Usage: python scripts/scoreboard.py [--records ../shared/records] [--out docs/scoreboard.md]

Per shipped model (models/*/): its experiment's classical laws (`evaluation.evaluation.classical_controllers`:
the LQGs for actuators and drivers, LQG + wind model under wind, passive-off, passive-on and clipped-optimal for
dampers), each run behind the model's own supervisor on its plant, are judged by the standard's check-suite
criterion (`rlc check`'s code); the best is the passing one with the lowest mean J1 + J2 (while none passes, the
one with the fewest motions worse). Beside it the shipped controller's verdict figures (its `best_check.yaml`, as
`rlc check` wrote them) and both on the seven records (mean J1, J2 over stories and records). A learned
controller *wins* where its J1 + J2 is at least 5 % below the best classical law's on the records and on the
check suite, with no more motions worse. Under wind the check suite is the wind suite (the records still shake the
building). About 10 min on 2 CPU cores.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import yaml

from rlcontroller.api.common import safety_standard
from rlcontroller.api.shipping import unshipped_experiments
from rlcontroller.config import load_experiment, load_safety_check
from rlcontroller.control.policy_file import read_policy
from rlcontroller.evaluation.evaluation import classical_controllers, compare
from rlcontroller.evaluation.safety import drift_bounds, suite_criterion
from rlcontroller.files import atomic_write
from rlcontroller.physics.loads import load_suite
from rlcontroller.physics.plant import Plant

REPOSITORY = Path(__file__).resolve().parents[1]
WIN = 0.05  # a learned controller wins at 5 % lower J1 + J2 on both suites, with no more motions worse
TRAINING = {  # how each learned shipped controller was trained (its command; long runs under nohup with a log)
    "five_story_every_story": "rlc train studies/mpc/five_story_every_story_dagger.yaml",
    "five_story_mr_standard": "rlc train studies/devices/five_story_mr_standard.yaml",
    "five_story_paper_layout": "rlc train studies/mpc/five_story_paper_layout_dagger.yaml",
    "five_story_wind": "rlc train studies/mpc/five_story_wind_dagger.yaml",
    "five_story_yielding": "rlc train studies/mpc/five_story_yielding_ship_dagger.yaml",
}


def check_figures(criterion: dict) -> dict:
    return {
        "J1": criterion["mean_J1"],
        "J2": criterion["mean_J2"],
        "k": f"{criterion['failure_count']}/{criterion['significant_motions']}",
        "worse": criterion["failure_count"],
        "passed": criterion["passed"],
        "dominates": criterion["dominates"],
    }


def sum_j(figures: dict) -> float:
    return figures["J1"] + figures["J2"]


def scores(folder: Path, records: Path) -> dict:
    """The shipped controller's and the best classical law's figures, on the check suite and the records."""
    experiment = load_experiment(folder / "config.yaml")
    plant = Plant(experiment)
    policy = read_policy(folder, "best", plant)
    standard = load_safety_check(safety_standard(experiment))
    verdict = yaml.safe_load((folder / "best_check.yaml").read_text(encoding="utf-8"))
    shipped = check_figures(verdict["criteria"]["check suite"]) | {"passed": verdict["passed"]}
    shipped["dominates"] = verdict["dominates"]  # every suite (under wind the ground motions' too)
    judged = []
    for controller in classical_controllers(plant):
        criterion = suite_criterion(plant, controller, standard, drift_bounds(plant, standard))
        judged.append((controller.name, check_figures(criterion)))
    passing = [item for item in judged if item[1]["passed"]]
    name, classical = min(passing or judged, key=lambda item: (item[1]["worse"] * (not passing), sum_j(item[1])))
    motions, label = load_suite(records, None, plant)
    table = compare(plant, motions, label, policy).summary()
    on_records = {
        key: table.loc[row, ["J1", "J2"]].tolist() for key, row in (("shipped", policy.name), ("classical", name))
    }
    return {"shipped": shipped, "classical": classical, "classical_name": name, "records": on_records,
            "kind": "classical" if policy.law else f"learned ({policy.algorithm})"}  # fmt: skip


def wins(row: dict) -> bool:
    shipped, classical, records = row["shipped"], row["classical"], row["records"]
    on_check = shipped["J1"] + shipped["J2"] <= (1.0 - WIN) * (classical["J1"] + classical["J2"])
    on_records = sum(records["shipped"]) <= (1.0 - WIN) * sum(records["classical"])
    return row["kind"] != "classical" and on_check and on_records and shipped["worse"] <= classical["worse"]


def page(rows: dict[str, dict], nothing: list[str]) -> str:
    lines = [
        "# Scoreboard: the shipped controllers against the best classical law",
        "",
        "Written by `python scripts/scoreboard.py` (its docstring says how). Check suite: the safety check's 320 "
        "generated motions against the building failed safe (mean J1, J2 over the significant motions; k = motions "
        "worse by more than 1 % of N significant; *dominates*: k = 0 and passed, for the shipped controller on every "
        "suite it is judged on; under wind the check suite is the wind suite); records: the seven PEER records "
        "against the uncontrolled building. The best classical law runs behind the shipped controller's own "
        "supervisor. A learned controller wins at J1 + J2 at least 5 % below the classical law's on both, with no "
        "more motions worse.",
        "",
        "| model | shipped | check J1 | J2 | k | dominates | records J1 | J2 | best classical law | check J1 | J2 | k "
        "| dominates | records J1 | J2 | learned wins |",
        "|---" * 16 + "|",
    ]
    for name, row in rows.items():
        s, c, r = row["shipped"], row["classical"], row["records"]
        lines.append(
            f"| {name} | {row['kind']} | {s['J1']:.3f} | {s['J2']:.3f} | {s['k']} "
            f"| {'yes' if s['dominates'] else 'no'} "
            f"| {r['shipped'][0]:.3f} | {r['shipped'][1]:.3f} | {row['classical_name']}"
            f"{'' if c['passed'] else ' (fails)'} | {c['J1']:.3f} | {c['J2']:.3f} | {c['k']} "
            f"| {'yes' if c['dominates'] else 'no'} | {r['classical'][0]:.3f} | {r['classical'][1]:.3f} "
            f"| {'**yes**' if wins(row) else 'no'} |"
        )
    learned = [name for name, row in rows.items() if row["kind"] != "classical"]
    won = sum(wins(row) for row in rows.values())
    total = len(rows) + len(nothing)
    lines += ["", f"Learned controllers ship on {len(learned)} of the {total} experiments ({len(rows)} here; nothing "
              f"ships for {', '.join(nothing) or 'none'}: models/README.md says why); {won} win by 5 %."]  # fmt: skip
    if not won:
        lines += ["", "Why none wins by 5 % where it counts: docs/mpc.md, \"Why none wins by 5 %\"."]
    lines += ["", "## How the learned ones were trained", ""]
    lines += [f"- `{name}`: `{TRAINING.get(name, 'see its card.md')}`" for name in learned]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=Path, default=REPOSITORY.parent / "shared" / "records")
    parser.add_argument("--out", type=Path, default=REPOSITORY / "docs" / "scoreboard.md")
    arguments = parser.parse_args()
    rows = {}
    for folder in sorted(p for p in (REPOSITORY / "models").iterdir() if (p / "best_check.yaml").is_file()):
        rows[folder.name] = scores(folder, arguments.records)
        print(folder.name, rows[folder.name], flush=True)
    atomic_write(arguments.out, page(rows, list(unshipped_experiments()[0])))
    print(f"wrote {arguments.out}")


if __name__ == "__main__":
    main()
