"""The feedback graph a certificate reasons about is the controller that acts: the same actions, the same
derivative."""

from __future__ import annotations

import numpy as np
import pytest

from rlcontroller.api.common import folder_experiment
from rlcontroller.assets import MODELS
from rlcontroller.control.controllers import LQGPrior
from rlcontroller.control.feedback_graph import UNITS, feedback_graph
from rlcontroller.control.networks import Actor, Layer, Normalizer
from rlcontroller.control.policy_controller import PolicyController
from rlcontroller.control.policy_file import read_policy
from rlcontroller.physics.plant import Plant
from tests.conftest import NETWORK_POLICY


def _odd_squashed_controller(plant: Plant, rng) -> PolicyController:
    """Every kind of unit at once: a clipping normaliser, ReLU and ELU layers, an odd network, SAC's squashing
    and a residual on LQG."""
    size, m = plant.layout.size, plant.building.n_actuators
    layers = (
        Layer(
            rng.standard_normal((8, size)).astype(np.float32),
            rng.standard_normal(8).astype(np.float32),
            "ReLU",
        ),
        Layer(
            rng.standard_normal((6, 8)).astype(np.float32), rng.standard_normal(6).astype(np.float32), "ELU"
        ),
        Layer(
            rng.standard_normal((m, 6)).astype(np.float32), rng.standard_normal(m).astype(np.float32), None
        ),
    )
    normalizer = Normalizer(rng.standard_normal(size) * 0.1, rng.uniform(0.5, 2.0, size), 1e-8, 1.5)
    return PolicyController(Actor(layers, squash=True, odd=True), normalizer, prior=LQGPrior.design(plant))


@pytest.mark.parametrize("which", ["default", "retired", "every unit"])
def test_the_graph_acts_as_the_controller_and_has_its_derivative(which):
    rng = np.random.default_rng(7)
    folder = {"default": MODELS / "five_story_every_story", "retired": NETWORK_POLICY}.get(which)
    plant = Plant(folder_experiment(folder if folder else MODELS / "five_story_every_story"))
    controller = read_policy(folder, "best", plant) if folder else _odd_squashed_controller(plant, rng)
    graph = feedback_graph(controller, n_plant=plant.n_state, n_observation=plant.layout.size)
    states = rng.standard_normal((6, graph.n_state)) * 20.0  # large enough to clip and saturate
    acted = controller.act(states[:, plant.n_state :].astype(np.float32))
    graphed = np.array([graph.forward(state)[2] for state in states])
    assert np.max(np.abs(graphed - acted)) < 1e-5  # the controller runs in float32
    assert np.max(np.abs(acted)) == pytest.approx(1.0)  # some action saturates: the clips are in the graph
    state, step = states[0] * 0.001, 1e-6
    central = np.column_stack(
        [
            (graph.forward(state + step * e)[2] - graph.forward(state - step * e)[2]) / (2 * step)
            for e in np.eye(graph.n_state)
        ]
    )
    assert np.allclose(graph.jacobian(state), central, atol=1e-6)


@pytest.mark.parametrize("kind", sorted(UNITS))
def test_every_unit_is_monotone_with_slopes_in_zero_one_and_unimodal_slope(kind):
    """What the sectors rest on (`certificate.sectors`): phi monotone, 0 <= phi' <= 1, phi' rising then
    falling, and the largest phi' on an interval is the one the table gives."""
    phi, slope, most = UNITS[kind]
    v = np.linspace(-6.0, 6.0, 24001)
    assert np.all(np.diff(phi(v)) >= 0.0)
    s = slope(v)
    assert np.all((s >= 0.0) & (s <= 1.0))
    peak = int(np.argmax(s))
    assert np.all(np.diff(s[: peak + 1]) >= -1e-12) and np.all(np.diff(s[peak:]) <= 1e-12)
    rng = np.random.default_rng(0)
    for lower, upper in np.sort(rng.uniform(-4.0, 4.0, (200, 2)), axis=1):
        inside = np.linspace(lower, upper, 401)
        assert most(np.array(lower), np.array(upper)) >= slope(inside).max() - 1e-9


def test_a_gelu_network_is_refused_by_name():
    plant = Plant(folder_experiment(MODELS / "five_story_every_story"))
    size, m = plant.layout.size, plant.building.n_actuators
    layer = Layer(np.zeros((m, size), np.float32), np.zeros(m, np.float32), "GELU")
    with pytest.raises(ValueError, match="GELU is not monotone"):
        feedback_graph(
            PolicyController(Actor((layer,), squash=False)), n_plant=plant.n_state, n_observation=size
        )
