"""A safety verdict's figures as types: one motion's (`MotionFigures`), a suite criterion's (`SuiteFigures`,
with its mass devices' `DeviceFigures`), the at-rest criterion's (`RestFigures`) and the closed-loop stability
criterion's (`StabilityFigures`). Each is read from a verdict file's fields (`read`) and written back as them
(`fields`), in the file's own names and order: a verdict file keeps its format, byte for byte.

Ratios are dimensionless (a controlled figure over the reference's, a drift over a story's height); strokes
are in m, forces in N, periods in s, ground accelerations in g.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np


def possible(value, low: float = 0.0, high: float = np.inf) -> bool:
    """A number (not a boolean) within [low, high): no NaN, no infinity."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and low <= value < high


def _present(figures) -> dict:
    """A dataclass's fields that are set, in their declared order (None: not in the file)."""
    return {
        item.name: value
        for item in dataclasses.fields(figures)
        if (value := getattr(figures, item.name)) is not None
    }


@dataclass(frozen=True)
class MotionFigures:
    """One motion of a check suite (a verdict's `per_motion` row): how strong it was and, where the
    reference's drift reached the insignificance bound (significant), the controlled building against the
    reference."""

    pga_g: float | None = None  # a ground motion's peak acceleration (g)
    load: str | None = None  # a floor load's description (wind)
    sa_over_pga: tuple[float, ...] | None = None  # its spectral shape at the building's first periods
    over_bound: float | None = None  # insignificant: the controlled peak drift over the bound
    J1: float | None = None  # significant: peak drift over the reference's, the stories' mean
    J2: float | None = None  # peak floor acceleration over the reference's, the floors' mean
    ratio: float | None = None  # what the risk counts (`physics.metrics.ratio_to_reference`)
    drift_ratio: float | None = None  # the largest peak story drift over its height
    reference_drift_ratio: float | None = None
    residual_ratio: float | None = None  # a yielding plant's largest permanent story drift over its height
    reference_residual_ratio: float | None = None
    # a passive verdict's failed motions: the energy's share
    ground_energy_near_first_mode: float | None = None

    @property
    def significant(self) -> bool:
        return self.ratio is not None

    @property
    def yields(self) -> bool:
        """Whether the row judges permanent drift too (a yielding plant)."""
        return self.residual_ratio is not None

    @classmethod
    def read(cls, name: str, row: dict) -> MotionFigures:
        """The figures of the motion `name` from its row: ValueError (one line naming the motion and the
        figure) for one no run can give (not a number, NaN, infinite or negative); KeyError where a
        significant row lacks a figure the standard reads."""
        numbers = {}
        for key in NUMBERS:
            if key in row:
                if not possible(row[key]):
                    raise ValueError(
                        f"{name}.{key} {row[key]!r} is no possible figure (a finite number >= 0)"
                    )
                numbers[key] = row[key]
        shape = row.get("sa_over_pga", [])
        if not isinstance(shape, list) or not all(possible(value) for value in shape):
            raise ValueError(
                f"{name}.sa_over_pga {shape!r} is no possible figure (a list of finite numbers >= 0)"
            )
        needed = SIGNIFICANT if "ratio" in row else ("over_bound",)
        needed += ("reference_residual_ratio",) if "residual_ratio" in row else ()
        for key in needed:
            numbers[key] = row[key]  # a KeyError names what is missing
        shape = tuple(row["sa_over_pga"]) if "sa_over_pga" in row else None
        return cls(pga_g=row.get("pga_g"), load=row.get("load"), sa_over_pga=shape, **numbers)

    def row(self) -> dict:
        """The verdict file's row."""
        row = _present(self)
        if self.sa_over_pga is not None:
            row["sa_over_pga"] = list(self.sa_over_pga)
        return row

    def strength(self) -> str:
        return f"PGA {self.pga_g:g} g" if self.pga_g is not None else self.load or ""


NUMBERS = ("over_bound", "J1", "J2", "ratio", "drift_ratio", "reference_drift_ratio", "residual_ratio")
NUMBERS += ("reference_residual_ratio", "ground_energy_near_first_mode")
SIGNIFICANT = ("J1", "J2", "ratio", "drift_ratio", "reference_drift_ratio")


@dataclass(frozen=True)
class DeviceFigures:
    """Per mass device over a suite, the controlled building's then the reference's (a passive verdict's
    reference, the bare building, has none): peak strokes (m); with end-stops (`physics.end_stops`) their
    limits (m), the contacts and the largest contact force (N)."""

    peak_stroke_m: list[float] | None = None
    reference_peak_stroke_m: list[float] | None = None
    stroke_limit_m: list[float] | None = None
    contacts: list[int] | None = None
    reference_contacts: list[int] | None = None
    peak_contact_force_N: list[float] | None = None
    reference_peak_contact_force_N: list[float] | None = None

    @classmethod
    def read(cls, item: dict) -> DeviceFigures | None:
        """The device figures a suite criterion's fields hold, None without any."""
        found = {key.name: item[key.name] for key in dataclasses.fields(cls) if key.name in item}
        return cls(**found) if found else None

    def summary(self) -> str:
        """The words a suite's summary ends with: peak strokes, end-stops and their contacts."""
        text = ""
        if self.peak_stroke_m is not None:
            text += f"; peak stroke {', '.join(f'{value:.2f}' for value in self.peak_stroke_m)} m"
            if self.reference_peak_stroke_m is not None:
                reference = ", ".join(f"{value:.2f}" for value in self.reference_peak_stroke_m)
                text += f" ({reference} m for the reference)"
        if self.stroke_limit_m is not None:
            limits = ", ".join(f"{value:g}" for value in self.stroke_limit_m)
            text += f" on end-stops at {limits} m: {sum(self.contacts):g} contacts, up to "
            text += f"{max(self.peak_contact_force_N) / 1e3:.0f} kN"
            if self.reference_contacts is not None:
                forces = max(self.reference_peak_contact_force_N) / 1e3
                text += f" ({sum(self.reference_contacts):g}, {forces:.0f} kN for the reference)"
        return text


@dataclass(frozen=True)
class SuiteFigures:
    """A suite criterion ("check suite", and the standard's `also`: "wind suite" or "ground-motion suite"):
    the outcome under the standard and the figures it follows from (`evaluation.standard.suite_figures`)."""

    summary: str  # one line, as `rlc check` prints it
    passed: bool
    dominates: bool  # passed with no significant motion worse than the reference beyond the tolerance
    reference: str  # what the controller is judged against, in words
    system: str  # the building's lateral system (`standard.DRIFT_LIMITS`)
    motions: int
    insignificant_motions: int
    significant_motions: int
    failure_count: int  # significant motions above the reference beyond the tolerance
    failures: list[str]
    failure_probability_bound: float  # one-sided Clopper-Pearson at the standard's confidence
    strict_failure_count: int  # significant motions above the reference by more than rounding
    higher_level: dict[str, list[str]]  # motion: [its performance level, the reference's]
    insignificant_above_bound: list[str]
    mean_J1: float
    mean_J2: float
    worst_significant: str | None
    worst_J2: str | None
    devices: DeviceFigures | None = None
    spectral_periods_s: list[float] | None = None  # the building's first periods (s)
    spectral_shape: dict[str, list[float]] | None = None  # Sa/PGA there: p16, median, p84 over the motions
    per_motion: dict[str, MotionFigures] | None = None

    @classmethod
    def read(cls, item: dict) -> SuiteFigures:
        """A suite criterion from a verdict file's fields."""
        names = [key.name for key in dataclasses.fields(cls) if key.name not in ("devices", "per_motion")]
        rows = {name: MotionFigures.read(name, row) for name, row in item.get("per_motion", {}).items()}
        return cls(
            **{name: item.get(name) for name in names}, devices=DeviceFigures.read(item), per_motion=rows
        )

    def fields(self) -> dict:
        """The verdict file's fields, in its order (the per-motion rows last)."""
        names = [key.name for key in dataclasses.fields(self)]
        figures = {name: getattr(self, name) for name in names[: names.index("devices")]}
        if self.devices is not None:
            figures |= _present(self.devices)
        if self.spectral_periods_s is not None:
            figures |= {"spectral_periods_s": self.spectral_periods_s, "spectral_shape": self.spectral_shape}
        if self.per_motion is not None:
            figures["per_motion"] = {name: row.row() for name, row in self.per_motion.items()}
        return figures


@dataclass(frozen=True)
class RestFigures:
    """The at-rest criterion: the building under sensor noise alone stays below the insignificance bound."""

    passed: bool
    summary: str
    peak_drift_over_bound: float  # the worst noise realisation's peak drift over the bound

    @classmethod
    def read(cls, item: dict) -> RestFigures:
        return cls(item["passed"], item["summary"], item["peak_drift_over_bound"])

    def fields(self) -> dict:
        return {key.name: getattr(self, key.name) for key in dataclasses.fields(self)}


@dataclass(frozen=True)
class StabilityFigures:
    """The closed-loop stability criterion: spectral radii of the loop linearised at rest, on the design model
    and on each standard scenario's plant (text where one was not checked)."""

    passed: bool
    summary: str
    judged_scenarios: list[str]  # the scenarios of the standard's `stable_on` that were checked
    spectral_radius_design_model: float
    spectral_radius_failed_safe: float  # the building with its devices failed safe
    spectral_radius_scenarios: dict[str, float | str]
    supervisor_left_out: bool

    @classmethod
    def read(cls, item: dict) -> StabilityFigures:
        return cls(**{key.name: item[key.name] for key in dataclasses.fields(cls)})

    def fields(self) -> dict:
        return {key.name: getattr(self, key.name) for key in dataclasses.fields(self)}


Criterion = SuiteFigures | RestFigures | StabilityFigures
