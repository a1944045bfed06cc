"""A safety verdict as a file: written beside the policy it judges, read back only when it still judges the
folder's files and its own figures agree with what it says, and compared figure by figure with a re-run.

A verdict (`MODEL_check.yaml`) holds the sha256 of what it judged (the policy's files, the experiment, the
standard): one whose digests no longer match the folder is read as no verdict. Its outcome, counts, risk
bound and means are re-derived from its own per-motion figures under the standard (`evaluation.standard`):
one they contradict (an outcome edited to passed, a mean edited down) is refused, in one line, wherever it
is read. What no file can prove is that its per-motion figures are what the controller does: that is the
folder's claim until `rlc check FOLDER --verify` re-runs the check and compares (`differences`).
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from rlcontroller.evaluation.figures import (
    Criterion,
    DeviceFigures,
    MotionFigures,
    RestFigures,
    StabilityFigures,
    SuiteFigures,
)
from rlcontroller.evaluation.standard import rest_figures, stability_figures, suite_figures
from rlcontroller.files import atomic_write

SUITES = {"check suite": "standard", "wind suite": "also", "ground-motion suite": "also"}
# --verify: figures agree within the noise another CPU's kernel brings plus the verdict's rounding (4
# decimals): under OPENBLAS_CORETYPE=Prescott the 76-story driver's per-motion J1 moved by up to 0.7 % (its
# trigger switches on a threshold), every other shipped verdict's by under 0.1 %: the standard's own
# tolerance, 1 % (docs/safety_check.md)
VERIFY_RELATIVE, VERIFY_ABSOLUTE = 1e-2, 1.5e-4
# the scenarios' spectral radii (judged on `stable_on`'s, reported on the rest): a delay makes the linearised
# loop's eigenvalues defective, and another kernel moves them by up to 1 % (the default's under
# OPENBLAS_CORETYPE=Prescott: 0.4 % and 0.8 %); whether a judged one is below 1 is compared exactly, as every
# pass is
VERIFY_REPORTED = 0.02


@dataclass
class Verdict:
    """Pass or fail per criterion, with the figures behind each."""

    controller: str
    passed: bool
    criteria: dict[str, Criterion] = field(default_factory=dict)
    judged: dict[str, str] = field(default_factory=dict)  # sha256 of what it judged (`judged_digests`)

    @classmethod
    def read(cls, fields: dict) -> Verdict:
        """A verdict from its file's fields (`dominates` there is derived, not read)."""
        criteria = {name: read_criterion(name, item) for name, item in fields.get("criteria", {}).items()}
        return cls(fields["controller"], fields["passed"], criteria, fields.get("judged", {}))

    @property
    def dominates(self) -> bool:
        """Passed, with no significant motion of any suite worse than the reference beyond the tolerance."""
        return dominating(self.passed, {name: item.dominates for name, item in self.suites().items()})

    def suites(self) -> dict[str, SuiteFigures]:
        return {name: item for name, item in self.criteria.items() if isinstance(item, SuiteFigures)}

    def to_yaml(self) -> str:
        """The verdict file: a motion's figures on one line."""
        fields = {"controller": self.controller, "passed": self.passed, "dominates": self.dominates}
        criteria = {name: item.fields() for name, item in self.criteria.items()}
        fields |= {"criteria": criteria} | ({"judged": self.judged} if self.judged else {})
        return yaml.safe_dump(fields, sort_keys=False, default_flow_style=None)

    def lines(self) -> list[str]:
        outcome = ("PASSED, dominates" if self.dominates else "PASSED") if self.passed else "FAILED"
        return [f"safety check of {self.controller}: {outcome}"] + [
            f"  {name}: {'pass' if item.passed else 'FAIL'} - {item.summary}"
            for name, item in self.criteria.items()
        ]


def read_criterion(name: str, item: dict) -> Criterion:
    """A criterion of a verdict file by its name: a suite's, the at-rest one or closed-loop stability."""
    if name in SUITES:
        return SuiteFigures.read(item)
    return {"at rest": RestFigures, "closed-loop stability": StabilityFigures}[name].read(item)


def dominating(passed: bool, suites: dict[str, bool | None]) -> bool:
    """A verdict dominates when it passed and every suite it judged dominates."""
    return passed and bool(suites) and all(suites.values())


def verdict_data(text: str):
    """A verdict file's data, by libyaml's safe loader where PyYAML was built with it (a 320-motion verdict of
    70 kB in 18 ms instead of 128 ms; the same data), else by PyYAML's own: plain data either way, no
    objects."""
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)(text)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def verdict_path(folder: Path, model: str, standard: str = "") -> Path:
    """MODEL_check.yaml: the verdict under the project's standard; MODEL_check-NAME.yaml under another."""
    return folder / f"{model}_check{'-' + standard if standard else ''}.yaml"


def policy_digests(folder: Path, model: str) -> dict[str, str]:
    """sha256 of a folder's policy files and the experiment it runs in (the run's config.yaml)."""
    names = (f"{model}_policy.yaml", f"{model}_policy.npz", "config.yaml")
    return {name: hashlib.sha256((folder / name).read_bytes()).hexdigest() for name in names}


def judged_digests(folder: Path, model: str, standard) -> dict[str, str]:
    """sha256 of what a verdict judges: the policy's files, the experiment it runs in (the run's
    config.yaml) and the standard (its resolved settings, so a comment does not count; `also` when it has
    one)."""
    digests = policy_digests(folder, model)
    settings = standard.model_dump(mode="json", exclude={"also"} if standard.also is None else None)
    digests["standard"] = hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()
    return digests


def also_criterion(also) -> str:
    """The name of the criterion a standard's `also` suite is judged as."""
    return "wind suite" if also.generator.kind == "wind" else "ground-motion suite"


def write_verdict(verdict: Verdict, folder: Path, model: str, standard: str = "") -> Path:
    return atomic_write(verdict_path(folder, model, standard), verdict.to_yaml())


def contradictions(fields: dict, standard, system: str) -> list[str]:
    """Where a verdict's recorded figures disagree with what its own per-motion figures give under
    `standard` for a building of lateral `system` (empty: it is consistent)."""
    criteria = fields.get("criteria")
    if not isinstance(criteria, dict):
        return ["it has no criteria"]
    standards = {"standard": standard, "also": standard.also}
    needed = ["check suite", "at rest"] + (
        [also_criterion(standard.also)] if standard.also is not None else []
    )
    found = [f"it has no {name!r} criterion" for name in needed if name not in criteria]
    for name, item in criteria.items():
        try:
            if name in SUITES:
                rows = {motion: MotionFigures.read(motion, row) for motion, row in item["per_motion"].items()}
                derived = suite_figures(
                    rows,
                    item["reference"],
                    system,
                    standards[SUITES[name]],
                    devices=DeviceFigures.read(item),
                    periods=item.get("spectral_periods_s"),
                )
            elif name == "at rest":
                derived = rest_figures(item["peak_drift_over_bound"], standard)
            elif name == "closed-loop stability":
                derived = stability_figures(
                    item["spectral_radius_design_model"],
                    item["spectral_radius_scenarios"],
                    item["supervisor_left_out"],
                    item["spectral_radius_failed_safe"],
                    stable_on=standard.stable_on,
                )
            else:
                found.append(f"{name!r} is no criterion of the standard")
                continue
        except ValueError as error:  # an impossible figure, named
            found.append(f"{name}: {error}")
            continue
        except (KeyError, TypeError, AttributeError):
            found.append(f"{name}: its figures are incomplete or malformed")
            continue
        found += [
            f"{name}.{key} {item.get(key)!r}, its figures give {value!r}"
            for key, value in derived.fields().items()
            if key != "per_motion" and not same(item.get(key), value)
        ]
    passed = all(isinstance(item, dict) and item.get("passed") is True for item in criteria.values())
    if fields.get("passed") is not passed:
        found.append(f"passed {fields.get('passed')!r}, its criteria give {passed!r}")
    suites = {
        name: isinstance(item, dict) and item.get("dominates")
        for name, item in criteria.items()
        if name in SUITES
    }
    dominates = dominating(passed, suites)
    if fields.get("dominates") is not dominates:
        found.append(f"dominates {fields.get('dominates')!r}, its criteria give {dominates!r}")
    return found


def same(recorded, derived) -> bool:
    if isinstance(derived, float) and math.isnan(derived):
        return isinstance(recorded, float) and math.isnan(recorded)
    if isinstance(derived, bool):
        return recorded is derived
    return recorded == derived


@dataclass(frozen=True)
class VerdictState:
    """What a folder's verdict says of its policy as it is now: `passed` True or False, or None with
    `reason` when there is none that judged these files and agrees with itself; `dominates` when passed."""

    passed: bool | None
    reason: str = ""
    dominates: bool = False


def read_verdict(folder: Path, model: str, standard, system: str) -> VerdictState:
    """The verdict on a folder's `model` policy under `standard`, if it judged the files the folder holds
    now and its figures agree with it: a verdict without digests, whose digests differ (weights, policy,
    experiment or standard changed since), that is unreadable, or that its own figures contradict
    (`contradictions`) counts as never checked, with the reason."""
    path = verdict_path(folder, model)
    if not path.is_file():
        return VerdictState(None, "never safety-checked")
    try:
        verdict = verdict_data(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError, OSError):
        return VerdictState(None, f"its verdict {path.name} is unreadable")
    passed = verdict.get("passed") if isinstance(verdict, dict) else None
    judged = verdict.get("judged") if isinstance(verdict, dict) else None
    if not isinstance(passed, bool):
        return VerdictState(None, f"its verdict {path.name} says neither passed nor failed")
    if not isinstance(judged, dict):
        return VerdictState(None, f"its verdict {path.name} does not say which files it judged")
    try:
        now = judged_digests(folder, model, standard)
    except OSError:
        return VerdictState(None, "a file its verdict judged is missing")
    changed = [name for name, digest in now.items() if judged.get(name) != digest]
    if changed:
        return VerdictState(None, f"{', '.join(changed)} changed since its verdict {path.name}")
    found = contradictions(verdict, standard, system)
    if found:
        more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
        return VerdictState(None, f"its verdict {path.name} contradicts its own figures: {found[0]}{more}")
    return VerdictState(passed, dominates=bool(verdict.get("dominates")))


def differences(recorded: dict, rerun: dict, path: str = "") -> list[str]:
    """Each figure of a recorded verdict that a re-run does not reproduce, one line each: numbers within
    VERIFY_RELATIVE of each other plus VERIFY_ABSOLUTE (the verdict's rounding) agree (the scenarios' reported
    spectral radii within VERIFY_REPORTED); the rest exactly.
    Summaries (words about the figures compared on their own) and the controller's label (a classical one's
    names its folder) are skipped."""
    found = []
    for key in list(recorded) + [key for key in rerun if key not in recorded]:
        where = f"{path}.{key}" if path else str(key)
        if key == "summary" or (key == "controller" and not path):
            continue
        if key not in rerun or key not in recorded:
            found.append(
                f"{where}: {'only in the recorded verdict' if key in recorded else 'missing from it'}"
            )
            continue
        mine, theirs = recorded[key], rerun[key]
        if isinstance(mine, dict) and isinstance(theirs, dict):
            found += differences(mine, theirs, where)
        elif not agree(
            mine, theirs, VERIFY_REPORTED if "spectral_radius_scenarios" in where else VERIFY_RELATIVE
        ):
            found.append(f"{where}: recorded {mine!r}, re-run {theirs!r}")
    return found


def agree(recorded, rerun, relative: float = VERIFY_RELATIVE) -> bool:
    if isinstance(recorded, list) and isinstance(rerun, list):
        return len(recorded) == len(rerun) and all(
            agree(a, b, relative) for a, b in zip(recorded, rerun, strict=True)
        )
    numbers = (int, float)
    if isinstance(recorded, bool) or isinstance(rerun, bool) or not isinstance(recorded, numbers):
        return recorded == rerun
    if not isinstance(rerun, numbers):
        return False
    if math.isnan(recorded) or math.isnan(rerun):
        return math.isnan(recorded) and math.isnan(rerun)
    if isinstance(recorded, int) and isinstance(rerun, int):
        return recorded == rerun
    return abs(recorded - rerun) <= relative * max(abs(recorded), abs(rerun)) + VERIFY_ABSOLUTE
