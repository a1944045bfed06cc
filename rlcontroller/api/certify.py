"""`rlc certify`: a proven region of stability for a folder's controller, on its design model and on the
standard's linear scenario plants, checked by simulation from its boundary and written as certificate.yaml
(method: `evaluation.certificate`; docs/certificate.md)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from rlcontroller.api.common import QUIET, Report, folder_experiment
from rlcontroller.config import ConfigError, display_path

FORMAT = "rlcontroller-certificate"
FORMAT_VERSION = 1
BOUNDARY_STARTS = 64  # simulations from the certified boundary, per plant
BOUNDARY_SECONDS = 30.0
RISE_TOLERANCE = 1e-5  # of c: the observation's float32 rounding, far inside the region
ARIAS = np.pi / (2.0 * 9.80665)  # Arias intensity (m/s) per integral of g^2 dt (m^2/s^3)


class OutsideMethod(Exception):
    """The controller's plant is not one the method covers (the certificate says so instead of a region)."""


@dataclass(frozen=True)
class PlantCertificate:
    """The region on one plant, the response bound in it, and what the boundary simulations showed."""

    plant: str
    region: object  # evaluation.certificate.Region
    largest_level_after_start: float  # V / c over every boundary run after its first step (< 1: invariant)
    level_at_end: float  # V / c at the end of the runs (0: returned to rest)
    rises: int  # steps where V rose (the certificate says none can)
    seconds: float

    def fields(self) -> dict:
        region = self.region
        fields = {"plant": self.plant, "spectral_radius": round(region.spectral_radius, 6)}
        if region.reason:
            return fields | {"certified": False, "reason": region.reason}
        return fields | {
            "certified": True,
            "drift_mm": float(f"{region.drift_m * 1e3:.4g}"),
            "drift_velocity_mm_s": float(f"{region.velocity_m_s * 1e3:.4g}"),
            "equilibrium_drift_mm": float(f"{region.equilibrium_drift_m * 1e3:.3g}"),
            "level": float(f"{region.level:.6g}"),
            "lmi_largest_eigenvalue": float(f"{region.largest_eigenvalue:.3g}"),
            "response": {
                "drift_per_ground_acceleration_s2": float(f"{region.gain_s2:.4g}"),
                "ground_energy_m2_s3": float(f"{region.energy_m2_s3:.4g}"),
                "arias_intensity_m_s": float(f"{ARIAS * region.energy_m2_s3:.4g}"),
            },
            "boundary_check": {
                "starts": BOUNDARY_STARTS,
                "seconds": BOUNDARY_SECONDS,
                "largest_level_after_start": float(f"{self.largest_level_after_start:.4g}"),
                "level_at_end": float(f"{self.level_at_end:.3g}"),
                "rises": self.rises,
            },
            "solve_seconds": round(self.seconds, 2),
        }

    def line(self) -> str:
        return _line_from_fields(self.fields())


def _certify_plant(name: str, plant, controller, report: Report) -> PlantCertificate:
    from rlcontroller.control.feedback_graph import feedback_graph
    from rlcontroller.evaluation.certificate import boundary_starts, levels, region
    from rlcontroller.simulation.linearised import boundary_runs, open_loop

    started = time.perf_counter()
    loop = open_loop(plant)
    graph = feedback_graph(controller, n_plant=loop.n_plant, n_observation=plant.layout.size)
    building = plant.building
    omega = 2.0 * np.pi / float(building.periods()[0])
    found = region(loop, graph, drift=building.drift_matrix(), omega=omega)
    seconds = time.perf_counter() - started
    if found.reason:
        report.line(f"  {name}: none certified: {found.reason}")
        return PlantCertificate(name, found, float("nan"), float("nan"), 0, seconds)
    steps = int(round(BOUNDARY_SECONDS / plant.control_dt))
    runs = boundary_runs(plant, controller, boundary_starts(found, BOUNDARY_STARTS, seed=0), steps)
    level = levels(found, runs)
    rises = int(np.sum(np.diff(level, axis=0) > RISE_TOLERANCE))
    certified = PlantCertificate(name, found, float(level[1:].max()), float(level[-1].max()), rises, seconds)
    if certified.largest_level_after_start > 1.0 + 1e-6 or rises:
        raise RuntimeError(
            f"{name}: a run from the certified boundary left it or rose (level "
            f"{certified.largest_level_after_start:.4g}, {rises} rises): the certificate is wrong, a bug"
        )
    report.line(f"  {certified.line()}")
    return certified


def certified_plants(folder: Path, model: str, *, robust: bool, report: Report = QUIET):
    """The folder's controller certified on its design model and (`robust`) on each linear plant of the
    standard's scenarios; the reason where its plant is outside the method."""
    from rlcontroller.config import load_scenarios
    from rlcontroller.config.scenarios import standard_scenarios
    from rlcontroller.control.policy_file import read_policy
    from rlcontroller.physics.plant import Plant
    from rlcontroller.simulation.linearised import open_loop, scenario_plant

    experiment = folder_experiment(folder)
    plant = Plant(experiment)
    controller = read_policy(folder, model, plant)
    if controller.mpc is not None:
        raise ConfigError(
            f"{folder}: an MPC law solves a quadratic program every step: no network to certify"
        )
    design = plant.design
    if design.semi_active is not None:
        raise OutsideMethod(
            "semi-active dampers (hysteretic, not linear in the command) are outside the method "
            "(a linear plant)"
        )
    plants, nominal = [("design model", design)], open_loop(design)
    if robust:  # each linear scenario plant whose loop differs from the design model's (noise does not enter)
        for scenario in load_scenarios(standard_scenarios(experiment), experiment):
            judged = scenario_plant(plant, scenario) if scenario.plant is not None else None
            if judged is not None and not _same_loop(open_loop(judged), nominal):
                plants.append((scenario.name, judged))
    return [_certify_plant(name, judged, controller, report) for name, judged in plants]


def _same_loop(loop, other) -> bool:
    return all(
        np.array_equal(getattr(loop, name), getattr(other, name)) for name in ("state", "action", "ground")
    )


def certify(folder: Path, *, model: str = "best", robust: bool = True, report: Report = QUIET) -> Path:
    """Certify the folder's controller and write MODEL_certificate.yaml beside it; returns the path."""
    from rlcontroller.evaluation.verdict import policy_digests
    from rlcontroller.files import atomic_write

    report.line(f"certifying {display_path(folder)}'s {model} policy (supervisor left out)...")
    started = time.perf_counter()
    try:
        plants, reason = certified_plants(folder, model, robust=robust, report=report), ""
    except OutsideMethod as error:
        plants, reason = [], str(error)
        report.line(f"  none certified: {reason}")
    data = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "certified": policy_digests(folder, model),
        "method": "quadratic constraints on every unit (local sectors from interval bounds on the region), "
        "fixed Lyapunov matrix, LMI in the multipliers by eigenvalue minimisation, re-checked by eigvalsh "
        "(docs/certificate.md)",
        "supervisor": "left out (the network, its observation and filter, the action clips and force limits)",
        **({"reason": reason} if reason else {}),
        "plants": [certificate.fields() for certificate in plants],
        "solve_seconds": round(time.perf_counter() - started, 1),
    }
    path = folder / f"{model}_certificate.yaml"
    atomic_write(path, yaml.safe_dump(data, sort_keys=False))
    return path


def certificate_summary(folder: Path, model: str = "best") -> str:
    """One line for `rlc models` and the card: the design model's X, or why there is none."""
    from rlcontroller.evaluation.verdict import policy_digests

    path = folder / f"{model}_certificate.yaml"
    if not path.is_file():
        return "no certificate ('rlc certify')"
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    if not isinstance(data, dict) or data.get("certified") != policy_digests(folder, model):
        return "certificate out of date ('rlc certify')"
    if data.get("reason"):
        return f"none certified ({data['reason']})"
    nominal = data["plants"][0]
    if not nominal.get("certified"):
        return f"none certified ({nominal.get('reason')})"
    return f"certified region: story drifts up to {nominal['drift_mm']:.3g} mm"


def certificate_line(folder: Path, model: str = "best", report: Report = QUIET) -> str:
    """What `rlc check` reports of the certificate (a criterion reported, not yet judged): the design model's
    region from the folder's current MODEL_certificate.yaml, else certified now on the design model alone."""
    from rlcontroller.evaluation.verdict import policy_digests

    path = folder / f"{model}_certificate.yaml"
    data = yaml.safe_load(path.read_text(encoding="utf-8")) if path.is_file() else None
    if isinstance(data, dict) and data.get("certified") == policy_digests(folder, model):
        if data.get("reason"):
            return f"certificate (reported, not judged): none certified: {data['reason']}"
        nominal = data["plants"][0]
        return f"certificate (reported, not judged, {display_path(path)}): {_line_from_fields(nominal)}"
    try:
        (nominal,) = certified_plants(folder, model, robust=False, report=QUIET)
    except (OutsideMethod, ConfigError) as error:
        return f"certificate (reported, not judged): none certified: {error}"
    return f"certificate (reported, not judged; 'rlc certify' writes it): {nominal.line()}"


def _line_from_fields(fields: dict) -> str:
    if not fields.get("certified"):
        return f"{fields['plant']}: none certified: {fields.get('reason')}"
    response = fields["response"]
    return (
        f"{fields['plant']}: every start with story drifts up to {fields['drift_mm']:.3g} mm and drift "
        f"velocities up to {fields['drift_velocity_mm_s']:.3g} mm/s returns to rest; there, drift <= "
        f"{response['drift_per_ground_acceleration_s2']:.3g} s^2 x ground acceleration (2-norms) up to an "
        f"Arias intensity of {response['arias_intensity_m_s']:.2g} m/s"
    )


def certificate_card_lines(folder: Path, model: str = "best") -> list[str]:
    """The card's lines: the design model's region and, per scenario plant, its X or why none."""
    path = folder / f"{model}_certificate.yaml"
    head = "- **Certificate** (`rlc certify`, docs/certificate.md; the supervisor left out): "
    summary = certificate_summary(folder, model)
    if not summary.startswith("certified region"):
        return [head + summary]
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    nominal, *scenarios = data["plants"]
    lines = [head + _line_from_fields(nominal)]
    for fields in scenarios:
        figure = f"{fields['drift_mm']:.3g} mm" if fields.get("certified") else f"none ({fields['reason']})"
        lines.append(f"  - {fields['plant']}: {figure}")
    return lines
