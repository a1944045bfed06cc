"""Runtime assurance (`control.assurance`) as ONNX nodes: the fail-safe twin and the switching rule, computed
as the Python supervisor does from the observation as the env stores it (float32)."""

from __future__ import annotations

import numpy as np

from rlcontroller.control.assurance import RuntimeAssurance
from rlcontroller.physics.plant import Plant


def assurance_state_size(plant: Plant) -> int:
    """Values the graph's state carries for the assurance: the difference x_u, the twin's running story
    peaks and whether the devices are handed back (0 without assurance)."""
    supervisor = plant.experiment.supervisor
    if supervisor is None or supervisor.assurance is None:
        return 0
    layout = plant.layout
    return (layout.estimate.stop - layout.estimate.start) + plant.building.n_floors + 1


def assured(g, plant: Plant, stored: str, action: str, *, start: int) -> tuple[str, list[str]]:
    """The action the actuators receive after runtime assurance, and the next state's assurance values;
    the previous ones are the graph's input `state` from column `start` on. `g` is export's graph writer."""
    rule = RuntimeAssurance(plant.experiment.supervisor.assurance, plant, 1)
    model = rule.twin_model
    size, floors = model.phi_t.shape[0], rule.peak.shape[1]
    difference = g.columns("state", start, start + size, "previous_difference")
    previous_peak = g.columns("state", start + size, start + size + floors, "previous_twin_peak")
    was_released = g.node(  # stored as released (1), so that the zero state is engaged, as at a Python reset
        "Cast",
        [g.columns("state", start + size + floors, start + size + floors + 1, "previous_released")],
        "was_released",
        to=9,  # bool
    )
    was_engaged = g.node("Not", [was_released], "was_engaged")
    estimate = g.columns(stored, plant.layout.estimate.start, plant.layout.estimate.stop, "assured_estimate")
    controlled = g.node("Mul", [estimate, g.constant("assurance_scale", rule.scale)], "controlled_estimate")
    twin = g.node("Sub", [controlled, difference], "twin_estimate")

    def envelope(z: str, name: str) -> str:
        drift = g.node("MatMul", [z, g.constant(f"{name}_drift_map", rule.drift_t)], f"{name}_drift")
        rate = g.node("MatMul", [z, g.constant(f"{name}_rate_map", rule.velocity_t)], f"{name}_rate")
        square = g.node(
            "Add",
            [g.node("Mul", [drift, drift], f"{name}_d2"), g.node("Mul", [rate, rate], f"{name}_r2")],
            f"{name}_square",
        )
        return g.node("Sqrt", [square], f"{name}_envelope")

    twin_drift = g.node(
        "Abs", [g.node("MatMul", [twin, "twin_drift_map"], "twin_story_drift")], "twin_story_magnitude"
    )
    peak = g.node("Max", [previous_peak, twin_drift], "twin_peak")
    reference = g.node(
        "Max", [envelope(twin, "twin"), peak, g.constant("assurance_floor", rule.floor)], "reference"
    )
    ratio = g.node("Div", [envelope(controlled, "controlled"), reference], "risk_per_story")
    risk = g.node("ReduceMax", [ratio], "risk", axes=[1], keepdims=1)
    stays = g.node("LessOrEqual", [risk, g.constant("release", rule.release)], "stays_engaged")
    returns = g.node("Less", [risk, g.constant("engage", rule.engage)], "engages_again")
    engaged = g.node(  # was ? stays : returns, in logic (onnxruntime's Where takes no booleans)
        "Or",
        [
            g.node("And", [was_engaged, stays], "kept_engaged"),
            g.node("And", [g.node("Not", [was_engaged], "was_off"), returns], "engaged_again"),
        ],
        "engaged",
    )
    recovery = g.clip(
        g.node(
            "Neg",
            [g.node("MatMul", [difference, g.constant("recovery_gain", rule.feedback_t)], "recovery_raw")],
            "recovery_sum",
        ),
        -1.0,
        1.0,
        output="recovery_action",
    )
    action = g.node("Where", [engaged, action, recovery], "assured_action")
    new_difference = g.node(
        "Add",
        [
            g.node("MatMul", [difference, g.constant("difference_map", model.phi_t)], "difference_free"),
            g.node("MatMul", [action, g.constant("difference_input", model.gamma_t)], "difference_forced"),
        ],
        "difference",
    )
    released = g.node("Cast", [g.node("Not", [engaged], "released")], "released_value", to=11)
    return action, [new_difference, peak, released]


def assurance_values(supervisor) -> np.ndarray:
    """The Python supervisor's assurance state of its first building, as the graph's state holds it."""
    rule = supervisor.assurance
    return np.concatenate([rule.twin_model.difference[0], rule.peak[0], [float(not rule.engaged[0])]])
