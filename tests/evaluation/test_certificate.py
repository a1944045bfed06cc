"""A certificate is checked, not trusted: its matrices are the simulator's, its sectors hold, a linear law's
region is the Lyapunov equation's, an unstable loop gets none, and every shipped certificate is current."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
import yaml
from scipy.linalg import solve_discrete_lyapunov

from rlcontroller.api.certify import certificate_summary, certify
from rlcontroller.api.common import folder_experiment, shipped_folders
from rlcontroller.assets import MODELS
from rlcontroller.control.controllers import LQGPrior
from rlcontroller.control.feedback_graph import UNITS, feedback_graph
from rlcontroller.control.networks import Actor, Layer
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.control.policy_file import read_policy
from rlcontroller.evaluation.certificate import (
    DECREASE,
    decrease_lmi,
    equilibrium,
    lyapunov_matrix,
    region,
    sectors,
    start_box,
)
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.linearised import boundary_runs, open_loop

DEFAULT = MODELS / "five_story_every_story"


def _loop(controller_of=None):
    plant = Plant(folder_experiment(DEFAULT))
    controller = read_policy(DEFAULT, "best", plant) if controller_of is None else controller_of(plant)
    design = plant.design
    loop = open_loop(design)
    graph = feedback_graph(controller, n_plant=loop.n_plant, n_observation=design.layout.size)
    return design, controller, loop, graph


def _linear_law(plant: Plant, sign: float = 1.0) -> PolicyController:
    """LQG + measured ground as a residual with a zero network: a linear law behind its clip."""
    size, m = plant.layout.size, plant.building.n_actuators
    zero = Layer(np.zeros((m, size), np.float32), np.zeros(m, np.float32), None)
    prior = LQGPrior.design(plant)
    prior = LQGPrior(sign * prior.feedback, sign * prior.feedforward, plant.layout)
    return PolicyController(Actor((zero,), squash=False), prior=prior)


def test_the_open_loop_and_the_graph_step_as_the_simulator_does():
    design, controller, loop, graph = _loop()
    rng = np.random.default_rng(3)
    starts = rng.standard_normal((5, graph.n_state)) * 0.01
    runs = boundary_runs(design, controller, starts, 1)
    predicted = np.array([loop.state @ s + loop.action @ graph.forward(s)[2] for s in starts])
    assert np.max(np.abs(runs[1] - predicted)) < 1e-6 * np.max(np.abs(runs[1]))


def test_every_units_sector_holds_inside_the_region_its_bounds_were_taken_on():
    _, _, loop, graph = _loop()
    rest = equilibrium(loop, graph)
    lyapunov = lyapunov_matrix(loop, graph, loop.state + loop.action @ graph.jacobian(rest))
    box = start_box(loop, np.eye(5, loop.n_plant), 10.0)
    level = 1e-4 * np.max(np.einsum("ij,jk,ik->i", box, lyapunov, box))  # starts of 1 cm: wide sectors
    alpha, beta, _ = sectors(graph, rest, np.linalg.inv(lyapunov), level)
    rng = np.random.default_rng(0)
    directions = rng.standard_normal((400, rest.size))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    values, vectors = np.linalg.eigh(lyapunov)
    inside = directions @ (vectors * np.sqrt(level / values)).T * rng.uniform(0, 1, (400, 1)) ** 0.1
    zeta0, pre0, _ = graph.forward(rest)
    for state in rest + inside:
        zeta, pre, _ = graph.forward(state)
        dv, dw = pre - pre0, zeta[graph.n_state :] - zeta0[graph.n_state :]
        assert np.all((dw - alpha * dv) * (beta * dv - dw) >= -1e-12)
    assert np.min(alpha) < 0.5  # the test reaches wide sectors


def test_a_linear_laws_region_is_the_lyapunov_equations_where_its_clip_does_not_act():
    """Where no clip acts the closed loop is linear: the LMI is the Lyapunov inequality of A_cl itself (its
    largest eigenvalue with no multipliers is that of P^-1/2 A_cl' P A_cl P^-1/2, less 1 - delta), and the
    certified level reaches at least the largest one on which no clip acts."""
    design, _, loop, graph = _loop(_linear_law)
    rest = equilibrium(loop, graph)
    assert np.max(np.abs(rest)) == 0.0
    closed = loop.state + loop.action @ graph.jacobian(rest)
    found = region(loop, graph, drift=design.building.drift_matrix(), omega=10.0)
    lyapunov, inverse = found.lyapunov, np.linalg.inv(found.lyapunov)
    radius = np.max(np.abs(np.linalg.eigvals(closed)))
    scaled = closed / (radius + 0.75 * (1.0 - radius))
    q = lyapunov - scaled.T @ lyapunov @ scaled
    assert np.allclose(solve_discrete_lyapunov(scaled.T, q), lyapunov, rtol=1e-8, atol=1e-10 * lyapunov.max())
    rows = graph.output @ np.vstack(
        [np.eye(graph.n_state), np.zeros((graph.size - graph.n_state, graph.n_state))]
    )
    prior_rows = graph.stages[-1].weight[:, : graph.n_state]  # what the final clip reads of the state
    unclipped = float(np.min(1.0 / np.einsum("ij,jk,ik->i", prior_rows, inverse, prior_rows)))
    assert found.level >= unclipped / 1.06 and not found.reason
    level = unclipped / 2.0
    alpha, beta, reach = sectors(graph, rest, inverse, level)
    assert np.all(alpha == 1.0) and np.all(beta == 1.0)
    m0, _, _, _ = decrease_lmi(loop, graph, lyapunov, level, alpha, beta, reach)
    values, vectors = np.linalg.eigh(lyapunov)
    root = vectors / np.sqrt(values)
    expected = np.linalg.eigvalsh(root.T @ closed.T @ lyapunov @ closed @ root)[-1] - (1.0 - DECREASE)
    assert np.linalg.eigvalsh(m0[: graph.n_state, : graph.n_state])[-1] == pytest.approx(expected, abs=1e-9)
    assert rows.shape[0] == design.building.n_actuators


def test_an_unstable_loop_gets_no_region_and_says_why():
    design, _, loop, graph = _loop(lambda plant: _linear_law(plant, sign=-3.0))
    found = region(loop, graph, drift=design.building.drift_matrix(), omega=10.0)
    assert found.level == 0.0 and found.reason.startswith(
        "the loop linearised at its equilibrium is unstable"
    )


@pytest.mark.slow
def test_certify_writes_a_checked_certificate_that_names_what_it_certified(tmp_path):
    """The shipped certificate reproduces (the design model's X, to the bisection's 5 % and a kernel's
    rounding), and one edit to what it certified makes it out of date."""
    folder = tmp_path / "model"
    shutil.copytree(DEFAULT, folder)
    (folder / "best_certificate.yaml").unlink()
    assert certificate_summary(folder) == "no certificate ('rlc certify')"
    path = certify(folder, robust=False)
    assert path == folder / "best_certificate.yaml"
    assert certificate_summary(folder).startswith("certified region: story drifts up to ")
    (mine,) = yaml.safe_load(path.read_text())["plants"]
    shipped = yaml.safe_load((DEFAULT / "best_certificate.yaml").read_text())["plants"][0]
    assert mine["plant"] == shipped["plant"] == "design model" and mine["lmi_largest_eigenvalue"] < 0
    assert mine["drift_mm"] == pytest.approx(shipped["drift_mm"], rel=0.1)
    assert mine["boundary_check"]["rises"] == 0 and mine["boundary_check"]["largest_level_after_start"] < 1
    (folder / "config.yaml").write_text((folder / "config.yaml").read_text() + "\n")
    assert certificate_summary(folder) == "certificate out of date ('rlc certify')"


def test_mr_dampers_get_a_certificate_that_says_why_none_was_found(tmp_path):
    folder = tmp_path / "mr"
    shutil.copytree(MODELS / "five_story_mr_standard", folder)
    certify(folder, robust=False)
    assert certificate_summary(folder).startswith("none certified (semi-active dampers (hysteretic")


def test_every_shipped_controller_has_a_current_certificate():
    for folder in shipped_folders():
        assert "('rlc certify')" not in certificate_summary(folder), folder.name


@pytest.mark.parametrize("kind", sorted(UNITS))
def test_a_units_chord_slope_from_any_point_is_least_at_an_end(kind):
    """`sectors` takes alpha from the chords to the interval's ends (and the slope at the point)."""
    phi, slope, _ = UNITS[kind]
    rng = np.random.default_rng(1)
    for center, lower, upper in rng.uniform(-3, 3, (300, 3)):
        lower, upper = min(lower, center), max(upper, center)
        v = np.linspace(lower, upper, 301)
        v = v[np.abs(v - center) > 1e-9]
        if v.size == 0:
            continue
        chords = (phi(v) - phi(center)) / (v - center)
        ends = [(phi(x) - phi(center)) / (x - center) for x in (lower, upper) if abs(x - center) > 1e-9]
        assert chords.min() >= min(ends + [slope(np.array(center))]) - 1e-9


def test_certifying_mpc_is_refused_in_one_line():
    from typer.testing import CliRunner

    from rlcontroller.cli import app
    from tests.conftest import MPC_POLICY

    result = CliRunner().invoke(app, ["certify", str(MPC_POLICY)])
    assert result.exit_code == 2
    assert "an MPC law solves a quadratic program every step: no network to certify" in result.output
    assert len(result.output.strip().splitlines()) == 2  # the progress line, then the error


def test_the_check_reports_a_current_certificate_and_refuses_none_silently():
    from rlcontroller.api.certify import certificate_line
    from tests.conftest import MPC_POLICY

    shipped = certificate_line(DEFAULT)
    assert shipped.startswith("certificate (reported, not judged, ")
    assert "design model: every start with story drifts up to " in shipped
    assert certificate_line(MPC_POLICY).endswith(
        "an MPC law solves a quadratic program every step: no network to certify"
    )
