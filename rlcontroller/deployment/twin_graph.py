"""The fail-safe twin's block of the observation (`sensors.twin`, `control.twin`) as ONNX nodes, computed as
the env does: the difference x_u is the previous step's estimate less the twin's estimate (both in the
graph's state, which holds the previous observation in float64), advanced over the step on the action the
actuators held."""

from __future__ import annotations

from rlcontroller.control.twin import FailSafeTwin
from rlcontroller.physics.plant import Plant


def twin_block(g, plant: Plant, held: str, scaled_estimate: str) -> str:
    """The twin's estimate and running story peaks, scaled as the observation holds them, from this step's
    scaled estimate and the held action (m). `g` is export's graph writer."""
    layout, model = plant.layout, FailSafeTwin(plant, 1)
    start, size, stop = layout.twin.start, layout.estimate.stop - layout.estimate.start, layout.twin.stop
    estimate_scale = g.constant("twin_estimate_scale", layout.estimate_scale)
    previous_estimate = g.columns(
        "state", layout.estimate.start, layout.estimate.stop, "twin_previous_estimate"
    )
    previous_twin = g.columns("state", start, start + size, "twin_previous_twin")
    scaled_difference = g.node("Sub", [previous_estimate, previous_twin], "twin_previous_scaled_difference")
    difference = g.node("Mul", [scaled_difference, estimate_scale], "twin_previous_difference")
    advanced = g.node(
        "Add",
        [
            g.node("MatMul", [difference, g.constant("twin_phi", model.phi_t)], "twin_free_difference"),
            g.node("MatMul", [held, g.constant("twin_gamma", model.gamma_t)], "twin_forced_difference"),
        ],
        "twin_difference",
    )
    estimate = g.node("Mul", [scaled_estimate, estimate_scale], "twin_controlled_estimate")
    twin = g.node("Sub", [estimate, advanced], "twin_estimate")
    peak_scale = g.constant("twin_peak_scale", layout.twin_scale[size:])
    previous_peak = g.node(
        "Mul",
        [g.columns("state", start + size, stop, "twin_previous_scaled_peak"), peak_scale],
        "twin_previous_peak",
    )
    drift = g.node(
        "Abs",
        [g.node("MatMul", [twin, g.constant("twin_drift_map", model.drift_t)], "twin_drift")],
        "twin_drift_magnitude",
    )
    peak = g.node("Max", [previous_peak, drift], "twin_peak")
    return g.node(
        "Concat",
        [
            g.node("Div", [twin, estimate_scale], "twin_scaled"),
            g.node("Div", [peak, peak_scale], "twin_scaled_peak"),
        ],
        "twin_block",
        axis=1,
    )
