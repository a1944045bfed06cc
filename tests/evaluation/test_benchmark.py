"""The nonlinear benchmark's criteria (`evaluation.benchmark`) against hand-computed values: drift ratios,
base shear from the floor masses, normed responses, force, stroke and power over the weight, and the member
ends' ductility, dissipated energy and plastic connections of elastic-perfectly-plastic hinges driven through
known cycles."""

import numpy as np
import pytest

from rlcontroller.evaluation.benchmark import benchmark_criteria, connection_criteria, response_criteria
from rlcontroller.physics.motions.excitation import STANDARD_GRAVITY
from rlcontroller.physics.response import Response
from rlcontroller.physics.structure import Building

DT = 0.1
MASSES = np.array([2.0e5, 1.0e5])
HEIGHTS = np.array([5.0, 4.0])


def _building() -> Building:
    n = MASSES.size
    return Building(
        mass=np.diag(MASSES),
        stiffness=np.eye(n),
        damping=np.zeros((n, n)),
        actuator_matrix=np.eye(n)[:, :1],
        force_limits=np.array([1e6]),
        story_heights=HEIGHTS,
    )


def _response(drift, acceleration, velocity, displacement, force=None, device_velocity=None) -> Response:
    k = len(drift)
    zeros = np.zeros((k, 2))
    force = np.zeros((k, 1)) if force is None else force
    device_velocity = np.zeros((k, 1)) if device_velocity is None else device_velocity
    return Response(
        time=np.arange(k) * DT,
        ground=np.zeros(k),
        displacement=np.asarray(displacement, float),
        velocity=np.asarray(velocity, float),
        drift=np.asarray(drift, float),
        absolute_acceleration=np.asarray(acceleration, float),
        story_shear=zeros,
        base_shear=np.zeros(k),
        force=force,
        device_velocity=device_velocity,
    )


def test_response_criteria_are_the_benchmarks_ratios():
    drift_u = [[0, 0], [0.05, 0.02], [-0.02, 0.04], [0.01, -0.01]]  # story 1 peaks 1 %, story 2 1 % of 4 m
    drift_c = [[0, 0], [0.02, 0.01], [-0.01, 0.03], [0.0, 0.0]]
    acc_u = [[0, 0], [1.0, -2.0], [2.0, 2.0], [0.0, 0.0]]  # base shear 2e5 - 2e5 = 0, then 6e5
    acc_c = [[0, 0], [1.0, 1.0], [-1.0, 0.5], [0.0, 0.0]]  # 3e5, -1.5e5
    vel_u, disp_u = [[0, 0], [0.5, 1.0], [0, 0], [0, 0]], [[0, 0], [0.1, 0.2], [0, 0.05], [0, 0]]
    force = np.array([[0.0], [3e4], [-6e4], [3e4]])
    device_velocity = np.array([[0.0], [0.2], [0.2], [0.2]])
    controlled = _response(drift_c, acc_c, vel_u, disp_u, force, device_velocity)
    uncontrolled = _response(drift_u, acc_u, vel_u, disp_u)
    criteria = response_criteria(controlled, uncontrolled, _building())
    assert criteria["J1"] == pytest.approx((0.03 / 4.0) / (0.05 / 5.0))
    assert criteria["J2"] == pytest.approx(1.0 / 2.0)
    assert criteria["J3"] == pytest.approx(3e5 / 6e5)
    rms = lambda x: np.sqrt(np.mean(np.asarray(x, float)[1:] ** 2, axis=0))  # noqa: E731
    assert criteria["J4"] == pytest.approx(np.max(rms(drift_c) / HEIGHTS) / np.max(rms(drift_u) / HEIGHTS))
    assert criteria["J5"] == pytest.approx(np.max(rms(acc_c)) / np.max(rms(acc_u)))
    shear = lambda a: np.asarray(a, float) @ MASSES  # noqa: E731
    assert criteria["J6"] == pytest.approx(rms(shear(acc_c)) / rms(shear(acc_u)))
    weight = STANDARD_GRAVITY * MASSES.sum()
    assert criteria["J11"] == pytest.approx(6e4 / weight)
    stroke = (0.1 + 0.2 + 0.2) * DT  # m: the velocity from rest to 0.2 m/s in the first step, then held
    assert criteria["J12"] == pytest.approx(stroke / 0.2)  # over the uncontrolled peak floor displacement
    assert criteria["J13"] == pytest.approx(6e4 * 0.2 / (1.0 * weight))
    assert criteria["J14"] == pytest.approx((3e4 + 6e4 + 3e4) * 0.2 / 3 / (1.0 * weight))


def _elastic_perfectly_plastic(deformation: np.ndarray, stiffness: float, strength: float) -> np.ndarray:
    """(steps, 3): deformation, force, tangent of a bilinear hinge with no hardening, from rest."""
    force, rows = 0.0, []
    for step, value in enumerate(deformation):
        trial = force + stiffness * (value - (deformation[step - 1] if step else 0.0))
        force = float(np.clip(trial, -strength, strength))
        rows.append((value, force, stiffness if abs(trial) < strength else 0.0))
    return np.array(rows)


def _cycles(amplitude: float, steps: int = 400) -> np.ndarray:
    return amplitude * np.sin(np.linspace(0.0, 4.0 * np.pi, steps + 1))


def test_member_end_criteria_of_bilinear_hinges_through_known_cycles():
    k, m_y = 2.0, 4.0  # phi_y = 2
    runs = {}
    for name, amplitudes in {"uncontrolled": (6.0, 3.0), "controlled": (4.0, 1.0)}.items():
        runs[name] = np.stack([_elastic_perfectly_plastic(_cycles(a), k, m_y) for a in amplitudes], axis=1)
    criteria = connection_criteria(runs["controlled"], runs["uncontrolled"])
    assert criteria["J7"] == pytest.approx((4.0 / 2.0) / (6.0 / 2.0), rel=1e-6)
    assert criteria["J9"] == pytest.approx(1 / 2)  # the second hinge yields only uncontrolled

    def dissipated(hinge: np.ndarray) -> float:  # an EPP hinge dissipates M_y per unit of plastic deformation
        return m_y * np.sum(np.abs(np.diff(hinge[:, 0] - hinge[:, 1] / k)))

    expected = dissipated(runs["controlled"][:, 0]) / dissipated(runs["uncontrolled"][:, 0])
    assert expected < 0.7
    assert criteria["J8"] == pytest.approx(expected, rel=0.01)  # the trapezoid rule on 400 steps
    normed = lambda run: np.sqrt(np.mean(run[1:, :, 0] ** 2, axis=0)) / 2.0  # noqa: E731
    assert criteria["J10"] == pytest.approx(
        np.max(normed(runs["controlled"])) / np.max(normed(runs["uncontrolled"]))
    )


def test_member_end_criteria_are_undefined_where_nothing_yields_uncontrolled():
    elastic = _elastic_perfectly_plastic(_cycles(1.0), 2.0, 4.0)[:, None, :]
    criteria = connection_criteria(elastic, elastic)
    assert all(np.isnan(criteria[key]) for key in ("J7", "J8", "J9", "J10"))


def test_costs_and_missing_heights():
    drift = [[0, 0], [0.01, 0.01]]
    uncontrolled = _response(drift, drift, drift, drift)
    responses = {("uncontrolled", "r"): uncontrolled, ("LQG", "r"): uncontrolled}
    table = benchmark_criteria(responses, ["r"], {"uncontrolled": (0, 0, 0), "LQG": (1, 3, 7)}, _building())
    lqg = table[table.controller == "LQG"].set_index("criterion")["value"]
    assert (lqg["J15"], lqg["J16"], lqg["J17"]) == (1, 3, 7)
    uncontrolled_row = table[table.controller == "uncontrolled"].set_index("criterion")["value"]
    assert uncontrolled_row[["J11", "J12", "J13", "J14"]].tolist() == [0.0] * 4
    no_heights = Building(**{**_building().__dict__, "story_heights": None})
    with pytest.raises(ValueError, match="story_heights"):
        benchmark_criteria(responses, ["r"], {"uncontrolled": (0, 0, 0)}, no_heights)
