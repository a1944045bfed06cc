"""The nonlinear benchmark's criteria J1-J17 (`rlc evaluate --criteria benchmark`): Ohtori, Christenson,
Spencer and Dyke (2004), "Benchmark control problems for seismically excited nonlinear buildings", J. Eng.
Mech. 130(4).

Per record, the controlled response C against the uncontrolled building's UC on the same record (the benchmark
takes each criterion's largest value over its records: `worst_over_records`, over those where it is defined).
h_i story heights, m_i floor masses, W = g sum m_i the seismic weight, ||q|| = sqrt(1/t_f int q^2 dt) over
the whole response (t_f: the record and its settling tail), x and x' floor displacements and velocities
relative to the ground, a absolute ones.

    J1  max_t,i |d_i|/h_i            / the same of UC          peak interstory drift ratio
    J2  max_t,i |a_i|                / the same of UC          peak floor acceleration
    J3  max_t |sum_i m_i a_i|        / the same of UC          peak base shear
    J4-J6   J1-J3 with ||.|| in place of max_t                 normed drift, acceleration, base shear
    J7  max_t,j |phi_j|/phi_y,j      / the same of UC          ductility at the member ends (connections)
    J8  max_j E_j / (M_y,j phi_y,j)  / the same of UC          dissipated energy at the member ends
    J9  connections that yield       / those of UC             plastic connections
    J10 J7 with ||.|| in place of max_t                        normed ductility
    J11 max_t,l |f_l| / W                                      peak control force
    J12 max_t,l |y_l| / max_t,i |x_i of UC|                    peak device stroke
    J13 max_t sum_l P_l / (max_t,i |x'_i of UC| W)             peak control power, P_l = |f_l y'_l|
    J14 sum_l 1/t_f int P_l dt / (max_t,i |x'_i of UC| W)      total control power
    J15 control devices    J16 sensors the controller reads    J17 states the controller carries between steps

J7-J10 need an FE plant's member ends (`physics.fe.connections`; other plants: not reported). A connection
yields where its tangent stiffness falls below half its value after gravity; its yield moment M_y is its force
there and its yield curvature phi_y = M_y / that initial tangent (the curvature it would have reached
elastically). J7, J8 and J10 go over the connections that yield in C or UC (the others never reach their yield
values, which are then unknown); E_j is int M dphi less the change of the elastic energy M^2 / (2 k0) (J).
With no connection yielding in UC the four are not defined (NaN). y_l (J12) is integrated from the velocity
across the device at the control steps. The paper itself was not reachable from where this was written: the
forms above are the benchmark's as the field quotes them; docs/opensees.md says what was and was not checked.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from rlcontroller.evaluation.tables import markdown_table
from rlcontroller.files import atomic_write
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY
from rlcontroller.physics.response import Response
from rlcontroller.physics.structure import Building

CRITERIA = tuple(f"J{i}" for i in range(1, 18))
YIELDED = 0.5  # of the initial tangent: below it a connection has yielded


def norm(history: np.ndarray) -> np.ndarray:
    """sqrt(1/t_f int q^2 dt) per component (rectangle rule on samples 1..K of equal steps, t_f = K dt)."""
    return np.sqrt(np.mean(history[1:] ** 2, axis=0))


def response_criteria(controlled: Response, uncontrolled: Response, building: Building) -> dict[str, float]:
    """J1-J6 and J11-J14 of one record (module docstring)."""
    dt = float(controlled.time[1] - controlled.time[0])
    heights, masses = building.story_heights, building.floor_masses
    weight = STANDARD_GRAVITY * float(np.sum(masses))

    def responses(result: Response) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return result.drift / heights, result.absolute_acceleration, result.absolute_acceleration @ masses

    criteria = {}
    for number, (c, u) in enumerate(zip(responses(controlled), responses(uncontrolled), strict=True)):
        criteria[f"J{number + 1}"] = float(np.max(np.abs(c)) / np.max(np.abs(u)))
        criteria[f"J{number + 4}"] = float(np.max(norm(c)) / np.max(norm(u)))
    force = controlled.force
    power = np.abs(force * controlled.device_velocity)
    stroke = np.vstack(
        [np.zeros((1, force.shape[1])), np.cumsum(_trapezoids(controlled.device_velocity, dt), axis=0)]
    )
    speed = float(np.max(np.abs(uncontrolled.velocity)))
    criteria["J11"] = float(np.max(np.abs(force))) / weight
    criteria["J12"] = float(np.max(np.abs(stroke)) / np.max(np.abs(uncontrolled.displacement)))
    criteria["J13"] = float(np.max(np.sum(power, axis=1))) / (speed * weight)
    criteria["J14"] = float(np.sum(np.mean(power[1:], axis=0))) / (speed * weight)  # 1/t_f int: forces held
    return criteria


def _trapezoids(history: np.ndarray, dt: float) -> np.ndarray:
    return 0.5 * (history[1:] + history[:-1]) * dt


def connection_criteria(controlled: np.ndarray, uncontrolled: np.ndarray) -> dict[str, float]:
    """J7-J10 of one record from both runs' member ends (steps + 1, connections, 3: deformation, force,
    tangent; `physics.fe.connections`), module docstring."""
    initial, runs = uncontrolled[0, :, 2], (controlled, uncontrolled)
    usable = initial > 0.0
    yielded_c, yielded_u = (np.any(run[:, :, 2] < YIELDED * initial, axis=0) & usable for run in runs)
    criteria = {"J9": float(np.sum(yielded_c) / np.sum(yielded_u)) if yielded_u.any() else np.nan}
    if not yielded_u.any():
        return criteria | {"J7": np.nan, "J8": np.nan, "J10": np.nan}
    chosen = yielded_c | yielded_u
    yield_curvature, yield_moment = np.zeros(chosen.sum()), np.zeros(chosen.sum())
    for column, j in enumerate(np.flatnonzero(chosen)):
        run = uncontrolled if yielded_u[j] else controlled
        first = int(np.argmax(run[:, j, 2] < YIELDED * initial[j]))
        yield_moment[column] = abs(run[first, j, 1])
        yield_curvature[column] = yield_moment[column] / initial[j]

    def measures(run: np.ndarray) -> tuple[float, float, float]:
        deformation, force = run[:, chosen, 0], run[:, chosen, 1]
        work = np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(deformation, axis=0), axis=0)
        stored = (force[-1] ** 2 - force[0] ** 2) / (2.0 * initial[chosen])
        return (
            float(np.max(np.max(np.abs(deformation), axis=0) / yield_curvature)),
            float(np.max((work - stored) / (yield_moment * yield_curvature))),
            float(np.max(norm(deformation) / yield_curvature)),
        )

    (peak_c, energy_c, normed_c), (peak_u, energy_u, normed_u) = measures(controlled), measures(uncontrolled)
    return criteria | {"J7": peak_c / peak_u, "J8": energy_c / energy_u, "J10": normed_c / normed_u}


def benchmark_criteria(
    responses: dict[tuple[str, str], Response],
    records: list[str],
    controllers: dict[str, tuple[int, int, int]],
    building: Building,
) -> pd.DataFrame:
    """J1-J17 per controller and record, long form (controller, record, criterion, value). `controllers`: name
    -> (devices, sensors, carried states) for J15-J17; `responses[name, record]`, "uncontrolled" among
    them."""
    if building.story_heights is None:
        raise ValueError("the benchmark's criteria need the building's story_heights (J1, J4: drift ratios)")
    rows = []
    for name, (devices, sensors, states) in controllers.items():
        for record in records:
            controlled, uncontrolled = responses[name, record], responses["uncontrolled", record]
            criteria = response_criteria(controlled, uncontrolled, building)
            if controlled.connections is not None and uncontrolled.connections is not None:
                criteria |= connection_criteria(controlled.connections, uncontrolled.connections)
            if devices == 0:  # no control: no force, stroke or power
                criteria |= {"J11": 0.0, "J12": 0.0, "J13": 0.0, "J14": 0.0}
            criteria |= {"J15": devices, "J16": sensors, "J17": states}
            rows += [
                {"controller": name, "record": record, "criterion": key, "value": float(value)}
                for key, value in criteria.items()
            ]
    return pd.DataFrame(rows)


def write_benchmark(evaluation, building: Building, folder: Path) -> str:
    """benchmark_criteria.csv (per record) and benchmark_criteria.md (the worst over the records) of
    `evaluation` (`evaluation.evaluation.Evaluation`) on `building` (the plant's) in `folder`; returns the
    Markdown."""
    criteria = benchmark_criteria(evaluation.responses, evaluation.records, evaluation.costs, building)
    atomic_write(folder / "benchmark_criteria.csv", criteria.to_csv(index=False))
    table = worst_over_records(criteria)
    table[["J15", "J16", "J17"]] = table[["J15", "J16", "J17"]].astype(int).astype(str)  # counts, as counts
    table.index.name = "controller"
    elastic = (
        criteria[(criteria.controller == "uncontrolled") & (criteria.criterion == "J9")]["value"].isna().sum()
    )
    defined = f" (J7-J10 over {len(evaluation.records) - elastic}: the others leave the bare frame elastic)"
    text = "\n".join(
        [
            "# The benchmark's criteria J1-J17 (Ohtori et al. 2004), the largest over "
            f"{len(evaluation.records)} records"
            + (defined if elastic and "J9" in set(criteria.criterion) else ""),
            "",
            markdown_table(table),
            "",
            "J1-J10: controlled / uncontrolled (J7-J10 at the FE model's member ends; - where not defined). "
            "J11-J14: force, stroke and power over the building's weight and uncontrolled peaks. "
            "J15 devices, J16 sensors, J17 states carried (rlcontroller/evaluation/benchmark.py).",
        ]
    )
    atomic_write(folder / "benchmark_criteria.md", text + "\n")
    return text


def worst_over_records(criteria: pd.DataFrame) -> pd.DataFrame:
    """The benchmark's form: each criterion's largest value over the records where it is defined (J7-J10 are
    not where the uncontrolled building stays elastic), per controller (rows) and criterion (columns,
    J1-J17)."""
    table = criteria.groupby(["controller", "criterion"], sort=False)["value"].max().unstack("criterion")
    order = list(dict.fromkeys(criteria["controller"]))
    return table.loc[order, [c for c in CRITERIA if c in table.columns]]
