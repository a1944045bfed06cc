"""The standard's rules on a check suite's figures: performance levels, the stated risk, the verdict's numbers.

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

import numpy as np

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
    """The performance level a peak drift ratio reaches: the first limit (times `slack`) it does not exceed."""
    return LEVELS[sum(drift_ratio > limit * slack for limit in limits)]


def risk_upper_bound(k: int, n: int, confidence: float) -> float:
    """One-sided Clopper-Pearson upper bound on a probability after k events in n trials: the `confidence`
    quantile of Beta(k + 1, n - k), the inverse of the regularised incomplete beta function (scipy.special:
    scipy.stats' beta.ppf to the last bit, without its 0.7 s import on every `rlc evaluate`)."""
    from scipy.special import betaincinv

    if n == 0:
        return 1.0
    return 1.0 if k >= n else float(betaincinv(k + 1, n - k, confidence))


def motion_levels(row: dict, system: str, tolerance: float) -> tuple[str, str]:
    """The performance levels a significant motion leaves the controlled building and the reference at: the
    higher of the level by peak transient drift and, where the row has residual drift ratios (a yielding
    plant), by permanent drift, as FEMA 356 defines a level (both within its limits). The controlled
    building's drifts count against a limit only beyond 1 + tolerance of it."""
    kinds = [("transient", "drift_ratio")] + [("permanent", "residual_ratio")] * ("residual_ratio" in row)
    levels = []
    for prefix, slack in (("", 1.0 + tolerance), ("reference_", 1.0)):
        reached = [LEVELS.index(level(row[prefix + key], DRIFT_LIMITS[system][kind], slack)) for kind, key in kinds]
        levels.append(LEVELS[max(reached)])
    return levels[0], levels[1]


DEVICE_FIGURES = (  # per mass device over a suite, the controlled building's then the reference's
    "peak_stroke_m",
    "reference_peak_stroke_m",
    "stroke_limit_m",  # with end-stops (`physics.end_stops`), these too
    "contacts",
    "reference_contacts",
    "peak_contact_force_N",
    "reference_peak_contact_force_N",
)


SHAPE_MODES = 3  # a ground-motion suite states its spectral shape at the building's first periods
SHAPE_DAMPING = 0.02  # of the oscillators it is measured with (Sa / PGA)
SHAPE_QUANTILES = {"p16": 16.0, "median": 50.0, "p84": 84.0}


POSSIBLE = {  # a per-motion figure and its possible range: ratios and drift ratios are finite and not negative
    "J1": (0.0, np.inf),
    "J2": (0.0, np.inf),
    "ratio": (0.0, np.inf),
    "drift_ratio": (0.0, np.inf),
    "reference_drift_ratio": (0.0, np.inf),
    "residual_ratio": (0.0, np.inf),
    "reference_residual_ratio": (0.0, np.inf),
    "over_bound": (0.0, np.inf),
}


def check_possible(rows: dict[str, dict]) -> None:
    """ValueError (one line naming the motion and the figure) for a per-motion figure no run can give: not a number
    (NaN, a boolean, text), infinite or negative. A verdict with one counts as none (`verdict.contradictions`)."""
    for name, row in rows.items():
        for key, (low, high) in POSSIBLE.items():
            if key in row and not possible(row[key], low, high):
                raise ValueError(f"{name}.{key} {row[key]!r} is no possible figure (a finite number >= {low:g})")
        shape = row.get("sa_over_pga", [])
        if not isinstance(shape, list) or not all(possible(value, 0.0, np.inf) for value in shape):
            raise ValueError(f"{name}.sa_over_pga {shape!r} is no possible figure (a list of finite numbers >= 0)")


def possible(value, low: float, high: float) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and low <= value < high


def suite_figures(
    rows: dict[str, dict],
    words: str,
    system: str,
    standard,
    *,
    devices: dict | None = None,
    periods: list | None = None,
) -> dict:
    """A suite criterion's figures from its per-motion `rows` (significant: J1, J2, ratio, drift ratios;
    insignificant: over_bound) against the reference `words` describes, under `standard`
    (`config.SafetyCheckConfig`: tolerance, risk_bound, confidence) for a building of lateral `system`; with mass
    devices their figures over the suite (`DEVICE_FIGURES`: peak strokes, m; with end-stops the limits, the
    contacts and the largest contact force, N); for ground motions measured at the building's `periods` (s), the
    suite's spread of spectral shapes there (each row's `sa_over_pga`: quantiles over every motion)."""
    check_possible(rows)
    tolerance = standard.tolerance
    significant = {name: row for name, row in rows.items() if "ratio" in row}
    quiet = {name: row for name, row in rows.items() if "ratio" not in row}
    above = [name for name, row in significant.items() if row["ratio"] > 1.0 + tolerance]
    strict = sum(row["ratio"] > 1.0 + ROUNDING for row in significant.values())
    levels = {name: motion_levels(row, system, tolerance) for name, row in significant.items()}
    higher = {name: list(pair) for name, pair in levels.items() if LEVELS.index(pair[0]) > LEVELS.index(pair[1])}
    loud = [name for name, row in quiet.items() if row["over_bound"] >= 1.0]
    n, k = len(significant), len(above)
    bound = risk_upper_bound(k, n, standard.confidence)
    risk_ok = k == 0 if standard.risk_bound == 0.0 else bound <= standard.risk_bound
    j1 = float(np.mean([row["J1"] for row in significant.values()])) if n else float("nan")
    j2 = float(np.mean([row["J2"] for row in significant.values()])) if n else float("nan")
    means_ok = not n or (j1 <= 1.0 + ROUNDING and j2 <= 1.0 + ROUNDING)
    passed = bool(n and risk_ok and means_ok and not higher and not loud)  # a suite that judged nothing passes not
    worst = max(significant, key=lambda name: significant[name]["ratio"], default=None)
    worst_j2 = max(significant, key=lambda name: significant[name]["J2"], default=None)
    figures = {
        "passed": passed,
        "dominates": passed and k == 0,
        "reference": words,
        "system": system,
        "motions": len(rows),
        "insignificant_motions": len(quiet),
        "significant_motions": n,
        "failure_count": k,  # significant motions above the reference beyond the tolerance
        "failures": above,
        "failure_probability_bound": round(bound, 4),
        "strict_failure_count": strict,  # significant motions above the reference by more than rounding
        "higher_level": higher,  # motion: [its level, the reference's]
        "insignificant_above_bound": loud,
        "mean_J1": round(j1, 4),
        "mean_J2": round(j2, 4),
        "worst_significant": worst,
        "worst_J2": worst_j2,
    }
    if devices is not None:
        figures |= {key: devices[key] for key in DEVICE_FIGURES if key in devices}
    if periods is not None:
        shapes = np.array([row["sa_over_pga"] for row in rows.values()], dtype=float).reshape(len(rows), len(periods))
        spread = {
            key: [round(float(v), 3) for v in np.percentile(shapes, q, axis=0)] for key, q in SHAPE_QUANTILES.items()
        }
        figures |= {"spectral_periods_s": periods, "spectral_shape": spread}
    return {"summary": suite_summary(figures, rows, standard)} | figures


def suite_summary(figures: dict, rows: dict[str, dict], standard) -> str:
    """One line: the outcome's figures, as `rlc check` prints them."""
    n, k = figures["significant_motions"], figures["failure_count"]
    if standard.risk_bound == 0.0:
        risk = f"{k} of {n} significant worse than {figures['reference']} beyond {standard.tolerance:.0%} (none may be)"
    else:
        risk = (
            f"{k} of {n} significant worse than {figures['reference']} beyond {standard.tolerance:.0%}, "
            f"failure probability <= {figures['failure_probability_bound']:.2%} at {standard.confidence:.0%} "
            f"(at most {standard.risk_bound:.0%})"
        )
    text = (
        f"{risk}{'; dominates' if figures['dominates'] else ''}; {figures['strict_failure_count']} worse at all; "
        f"{len(figures['higher_level'])} at a higher performance level ({SYSTEM_WORDS[figures['system']]}, "
        f"FEMA 356); {figures['insignificant_motions']} insignificant, "
        f"{len(figures['insignificant_above_bound'])} of them above the bound; "
        f"mean J1 {figures['mean_J1']:.3f}, mean J2 {figures['mean_J2']:.3f}"
    )
    if (worst := figures["worst_significant"]) is not None:
        text += f"; worst {rows[worst]['ratio']:.3f} ({worst}, {strength_text(rows[worst])})"
    if (worst := figures["worst_J2"]) is not None:
        text += f"; worst J2 {rows[worst]['J2']:.3f} ({worst})"
    if "peak_stroke_m" in figures:
        metres = {key: ", ".join(f"{value:.2f}" for value in figures.get(key, ())) for key in DEVICE_FIGURES[:2]}
        text += f"; peak stroke {metres['peak_stroke_m']} m"
        if "reference_peak_stroke_m" in figures:  # a passive verdict's reference, the bare building, has no mass
            text += f" ({metres['reference_peak_stroke_m']} m for the reference)"
    if "stroke_limit_m" in figures:
        limits = ", ".join(f"{value:g}" for value in figures["stroke_limit_m"])
        text += f" on end-stops at {limits} m: {sum(figures['contacts']):g} contacts, up to "
        text += f"{max(figures['peak_contact_force_N']) / 1e3:.0f} kN"
        if "reference_contacts" in figures:  # a passive verdict's reference, the bare building, has no stops
            reference = (sum(figures["reference_contacts"]), max(figures["reference_peak_contact_force_N"]) / 1e3)
            text += f" ({reference[0]:g}, {reference[1]:.0f} kN for the reference)"
    if "spectral_shape" in figures:
        shape, periods = figures["spectral_shape"], figures["spectral_periods_s"]
        at = ", ".join(
            f"{median:.2f} ({low:.2f}-{high:.2f}) at {period:.3g} s"
            for period, low, median, high in zip(periods, shape["p16"], shape["median"], shape["p84"], strict=True)
        )
        text += f"; the suite's Sa/PGA ({SHAPE_DAMPING:.0%} damped, median (16-84 %)) {at}"
    return text


def strength_text(row: dict) -> str:
    return f"PGA {row['pga_g']:g} g" if "pga_g" in row else row.get("load", "")


def rest_figures(peak_over_bound: float, standard) -> dict:
    """The at-rest criterion from its peak drift over the insignificance bound (the worst noise realisation)."""
    return {
        "passed": peak_over_bound < 1.0,
        "summary": f"peak drift {peak_over_bound:.3f} of the bound over {standard.rest_runs} noise realisations of "
        f"{standard.rest_duration:g} s",
        "peak_drift_over_bound": peak_over_bound,
    }


MARGINAL = 1e-6  # a closed loop within this of the building failed safe's own marginal modes is as stable as it


def stability_figures(
    design: float,
    per_scenario: dict[str, float | str],
    supervised: bool,
    failed_safe: float,
    *,
    stable_on: list[str] | tuple[str, ...] = (),
) -> dict:
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
    where = f"; unstable on {', '.join(unstable)}" if unstable else "; stable on every linear standard scenario"
    if judged:
        where += f"; judged on {', '.join(judged)}: {'unstable on ' + ', '.join(failing) if failing else 'stable'}"
    unjudged = [name for name in stable_on if name not in numbers]
    if unjudged:
        where += f"; {', '.join(unjudged)}: not among this experiment's linear scenarios, not judged"
    unsupervised = ", without the supervisor" if supervised else ""
    marginal = f" (the building failed safe: {failed_safe:.8f}, marginal)" if bound > 1.0 else ""
    return {
        "passed": design < bound and not failing,
        "summary": f"spectral radius {design:.8f} on the design model (linearised at rest{unsupervised}){marginal}"
        f"{where}",
        "judged_scenarios": judged,
        "spectral_radius_design_model": design,
        "spectral_radius_failed_safe": failed_safe,
        "spectral_radius_scenarios": per_scenario,
        "supervisor_left_out": supervised,
    }
