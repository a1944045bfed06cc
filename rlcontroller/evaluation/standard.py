"""The standard's rules on a check suite's figures: performance levels, the stated risk, the verdict's
numbers.

Everything here is a function of a suite's per-motion figures (drift ratios, J1, J2) and the standard, so a
verdict file can be re-derived from its own rows (`evaluation.verdict.contradictions`): a criterion whose
recorded outcome, counts, bound or means its rows contradict is refused wherever it is read.

- **Performance levels** (FEMA 356, *Prestandard and Commentary for the Seismic Rehabilitation of Buildings*,
  2000, Table C1-3; ASCE 41 keeps them): a story drift ratio within Immediate Occupancy, Life Safety or
  Collapse Prevention, or beyond it, by the peak transient drift ratio and, where the plant yields, the
  permanent (residual) one. "Negligible" permanent drift at IO is read as 1/500 (0.2 %), the out-of-plumb
  tolerance of steel erection (AISC 303, Code of Standard Practice, 7.13.1.1). The controlled building may
  reach no higher level than the reference on any significant motion; its drift counts against a limit
  only beyond 1 + tolerance of it.
- **Risk** (the form of ASCE 7-16 16.2.4, which allows a stated share of unacceptable responses, and FEMA
  P-695, which states collapse as a probability): k significant motions worse than the reference beyond the
  tolerance, of N; the one-sided Clopper-Pearson upper bound on that probability at the standard's
  confidence must be at most its `risk_bound` (0.05 at 95 %: k <= 9 of 320). A `risk_bound` of 0 asks k = 0.
- **k = 0 dominates**: never worse than the reference on any motion (round 5's standard).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from rlcontroller.evaluation.figures import (
    DeviceFigures,
    MotionFigures,
    RestFigures,
    StabilityFigures,
    SuiteFigures,
)

ROUNDING = 1e-9  # a controller that never acts equals the reference to this relative rounding
PLUMB = 0.002  # "negligible" permanent drift: AISC 303's erection tolerance, 1/500
LEVELS = ("IO", "LS", "CP", "beyond CP")  # index = how many limits the drift ratio exceeds
# FEMA 356 Table C1-3: drift ratio limits (IO, LS, CP), transient and permanent, per lateral system
DRIFT_LIMITS = {
    "steel_moment_frame": {"transient": (0.007, 0.025, 0.05), "permanent": (PLUMB, 0.01, 0.05)},
    "concrete_moment_frame": {"transient": (0.01, 0.02, 0.04), "permanent": (PLUMB, 0.01, 0.04)},
    "concrete_wall": {"transient": (0.005, 0.01, 0.02), "permanent": (PLUMB, 0.005, 0.02)},
}
SYSTEM_WORDS = {
    "steel_moment_frame": "steel moment frame",
    "concrete_moment_frame": "concrete moment frame",
    "concrete_wall": "concrete walls",
}


def level(drift_ratio: float, limits: tuple[float, ...], slack: float = 1.0) -> str:
    """The performance level a peak drift ratio reaches: the first limit (times `slack`) it does not
    exceed."""
    return LEVELS[sum(drift_ratio > limit * slack for limit in limits)]


def risk_upper_bound(k: int, n: int, confidence: float) -> float:
    """One-sided Clopper-Pearson upper bound on a probability after k events in n trials: the
    `confidence` quantile of Beta(k + 1, n - k). With no event (a dominating verdict) that is
    1 - (1 - confidence)^(1/n) in closed form; otherwise the inverse of the regularised incomplete beta
    function (scipy.special, imported only then: its 0.1 s import would otherwise sit on every
    `rlc evaluate`, which re-derives the shipped verdict)."""
    if n == 0 or k >= n:
        return 1.0
    if k == 0:
        return -math.expm1(math.log1p(-confidence) / n)
    from scipy.special import betaincinv

    return float(betaincinv(k + 1, n - k, confidence))


def motion_levels(row: MotionFigures, system: str, tolerance: float) -> tuple[str, str]:
    """The performance levels a significant motion leaves the controlled building and the reference at: the
    higher of the level by peak transient drift and, where the row has residual drift ratios (a yielding
    plant), by permanent drift, as FEMA 356 defines a level (both within its limits). The controlled
    building's drifts count against a limit only beyond 1 + tolerance of it."""
    limits = DRIFT_LIMITS[system]
    controlled = [level(row.drift_ratio, limits["transient"], 1.0 + tolerance)]
    reference = [level(row.reference_drift_ratio, limits["transient"])]
    if row.yields:
        controlled.append(level(row.residual_ratio, limits["permanent"], 1.0 + tolerance))
        reference.append(level(row.reference_residual_ratio, limits["permanent"]))
    return max(controlled, key=LEVELS.index), max(reference, key=LEVELS.index)


SHAPE_MODES = 3  # a ground-motion suite states its spectral shape at the building's first periods
SHAPE_DAMPING = 0.02  # of the oscillators it is measured with (Sa / PGA)
SHAPE_QUANTILES = {"p16": 16.0, "median": 50.0, "p84": 84.0}


def suite_figures(
    rows: dict[str, MotionFigures],
    words: str,
    system: str,
    standard,
    *,
    devices: DeviceFigures | None = None,
    periods: list | None = None,
) -> SuiteFigures:
    """A suite criterion from its motions' figures `rows` against the reference `words` describes, under
    `standard` (`config.SafetyCheckConfig`: tolerance, risk_bound, confidence) for a building of lateral
    `system`; with mass devices their figures over the suite; for ground motions measured at the building's
    `periods` (s), the suite's spread of spectral shapes there (quantiles of every row's `sa_over_pga`)."""
    tolerance = standard.tolerance
    significant = {name: row for name, row in rows.items() if row.significant}
    quiet = {name: row for name, row in rows.items() if not row.significant}
    above = [name for name, row in significant.items() if row.ratio > 1.0 + tolerance]
    strict = sum(row.ratio > 1.0 + ROUNDING for row in significant.values())
    levels = {name: motion_levels(row, system, tolerance) for name, row in significant.items()}
    higher = {
        name: list(pair) for name, pair in levels.items() if LEVELS.index(pair[0]) > LEVELS.index(pair[1])
    }
    loud = [name for name, row in quiet.items() if row.over_bound >= 1.0]
    n, k = len(significant), len(above)
    bound = risk_upper_bound(k, n, standard.confidence)
    risk_ok = k == 0 if standard.risk_bound == 0.0 else bound <= standard.risk_bound
    j1 = float(np.mean([row.J1 for row in significant.values()])) if n else float("nan")
    j2 = float(np.mean([row.J2 for row in significant.values()])) if n else float("nan")
    means_ok = not n or (j1 <= 1.0 + ROUNDING and j2 <= 1.0 + ROUNDING)
    passed = bool(n and risk_ok and means_ok and not higher and not loud)  # one that judged nothing fails
    shape = None
    if periods is not None:
        shapes = np.array([row.sa_over_pga for row in rows.values()], dtype=float).reshape(len(rows), -1)
        shape = {
            key: [round(float(v), 3) for v in np.percentile(shapes, q, axis=0)]
            for key, q in SHAPE_QUANTILES.items()
        }
    figures = SuiteFigures(
        summary="",
        passed=passed,
        dominates=passed and k == 0,
        reference=words,
        system=system,
        motions=len(rows),
        insignificant_motions=len(quiet),
        significant_motions=n,
        failure_count=k,
        failures=above,
        failure_probability_bound=round(bound, 4),
        strict_failure_count=strict,
        higher_level=higher,
        insignificant_above_bound=loud,
        mean_J1=round(j1, 4),
        mean_J2=round(j2, 4),
        worst_significant=max(significant, key=lambda name: significant[name].ratio, default=None),
        worst_J2=max(significant, key=lambda name: significant[name].J2, default=None),
        devices=devices,
        spectral_periods_s=periods,
        spectral_shape=shape,
        per_motion=rows,
    )
    return replace(figures, summary=suite_summary(figures, standard))


def suite_summary(figures: SuiteFigures, standard) -> str:
    """One line: the outcome's figures, as `rlc check` prints them."""
    n, k, rows = figures.significant_motions, figures.failure_count, figures.per_motion
    risk = f"{k} of {n} significant worse than {figures.reference} beyond {standard.tolerance:.0%}"
    if standard.risk_bound == 0.0:
        risk += " (none may be)"
    else:
        risk += (
            f", failure probability <= {figures.failure_probability_bound:.2%} at {standard.confidence:.0%} "
            f"(at most {standard.risk_bound:.0%})"
        )
    text = (
        f"{risk}{'; dominates' if figures.dominates else ''}; {figures.strict_failure_count} worse at "
        f"all; {len(figures.higher_level)} at a higher performance level "
        f"({SYSTEM_WORDS[figures.system]}, FEMA 356); {figures.insignificant_motions} insignificant, "
        f"{len(figures.insignificant_above_bound)} of them above the bound; mean J1 "
        f"{figures.mean_J1:.3f}, mean J2 {figures.mean_J2:.3f}"
    )
    if (worst := figures.worst_significant) is not None:
        text += f"; worst {rows[worst].ratio:.3f} ({worst}, {rows[worst].strength()})"
    if (worst := figures.worst_J2) is not None:
        text += f"; worst J2 {rows[worst].J2:.3f} ({worst})"
    if figures.devices is not None:
        text += figures.devices.summary()
    if figures.spectral_shape is not None:
        shape, periods = figures.spectral_shape, figures.spectral_periods_s
        at = ", ".join(
            f"{median:.2f} ({low:.2f}-{high:.2f}) at {period:.3g} s"
            for period, low, median, high in zip(
                periods, shape["p16"], shape["median"], shape["p84"], strict=True
            )
        )
        text += f"; the suite's Sa/PGA ({SHAPE_DAMPING:.0%} damped, median (16-84 %)) {at}"
    return text


def rest_figures(peak_over_bound: float, standard) -> RestFigures:
    """The at-rest criterion from its peak drift over the insignificance bound (the worst noise
    realisation)."""
    runs = f"{standard.rest_runs} noise realisations of {standard.rest_duration:g} s"
    summary = f"peak drift {peak_over_bound:.3f} of the bound over {runs}"
    return RestFigures(passed=peak_over_bound < 1.0, summary=summary, peak_drift_over_bound=peak_over_bound)


# a closed loop within this of the building failed safe's own marginal modes is as stable as it
MARGINAL = 1e-6


def stability_figures(
    design: float,
    per_scenario: dict[str, float | str],
    supervised: bool,
    failed_safe: float,
    *,
    stable_on: list[str] | tuple[str, ...] = (),
) -> StabilityFigures:
    """The closed-loop stability criterion from the spectral radius on the design model and on each standard
    scenario's plant (a string where it was not checked): below 1, or where the building failed safe is itself
    marginal (a radius of 1 to rounding: an MR damper's hysteretic memory, which no command removes), no more
    than MARGINAL above that building's radius `failed_safe`. Judged on the design model and on the scenarios
    of `stable_on` that were checked (a real installation's actuator lag and one step of computation); the
    other scenarios' radii are reported."""
    bound = max(1.0, failed_safe + MARGINAL)
    numbers = {name: radius for name, radius in per_scenario.items() if not isinstance(radius, str)}
    if any(not np.isfinite(radius) or radius < 0.0 for radius in [design, *numbers.values()]):
        raise ValueError("a spectral radius that no matrix has (NaN or negative)")
    judged = [name for name in stable_on if name in numbers]
    unstable = [name for name, radius in numbers.items() if radius >= bound]
    failing = [name for name in judged if numbers[name] >= bound]
    where = "; stable on every linear standard scenario"
    if unstable:
        where = f"; unstable on {', '.join(unstable)}"
    if judged:
        outcome = f"unstable on {', '.join(failing)}" if failing else "stable"
        where += f"; judged on {', '.join(judged)}: {outcome}"
    unjudged = [name for name in stable_on if name not in numbers]
    if unjudged:
        where += f"; {', '.join(unjudged)}: not among this experiment's linear scenarios, not judged"
    unsupervised = ", without the supervisor" if supervised else ""
    marginal = f" (the building failed safe: {failed_safe:.8f}, marginal)" if bound > 1.0 else ""
    return StabilityFigures(
        passed=design < bound and not failing,
        summary=f"spectral radius {design:.8f} on the design model (linearised at rest{unsupervised})"
        f"{marginal}{where}",
        judged_scenarios=judged,
        spectral_radius_design_model=design,
        spectral_radius_failed_safe=failed_safe,
        spectral_radius_scenarios=per_scenario,
        supervisor_left_out=supervised,
    )
