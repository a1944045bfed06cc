"""The measured stroke velocities and the dampers' fallback (`control.fallback`) as ONNX nodes, computed as
the Python supervisor does from the observation as the env stores it (float32)."""

from __future__ import annotations

import numpy as np

from rlcontroller.control.fallback import DamperFallback, MeasuredStrokeVelocity
from rlcontroller.physics.plant import Plant


def fallback_state_size(plant: Plant) -> int:
    """Values the graph's state carries: each actuator's measured stroke velocity (with `dissipative:
    measured` or a fallback) and whether the fallback has taken over (0 or 1)."""
    supervisor = plant.experiment.supervisor
    if supervisor is None or not supervisor.measured:
        return 0
    return plant.building.n_actuators + (supervisor.fallback is not None)


def measured_velocity(g, plant: Plant, stored: str, start: int) -> str:
    """The new measured stroke velocities (m/s), the previous ones read from the graph's input `state` from
    column `start` on. `g` is export's graph writer."""
    rule = MeasuredStrokeVelocity(plant, 1)
    m = rule.stroke_map.shape[1]
    floors = g.node(
        "Mul",
        [
            g.columns(stored, rule.readings.start, rule.readings.stop, "floor_readings"),
            g.constant("floor_scale", rule.reading_scale),
        ],
        "floor_accelerations",
    )
    ground = g.node(
        "Mul",
        [
            g.columns(stored, rule.ground, rule.ground + 1, "measured_ground"),
            g.constant("measured_ground_scale", [rule.ground_scale]),
        ],
        "ground_acceleration",
    )
    relative = g.node("Sub", [floors, ground], "relative_floor_accelerations")
    stroke = g.node("MatMul", [relative, g.constant("stroke_map", rule.stroke_map)], "stroke_acceleration")
    previous = g.columns("state", start, start + m, "previous_stroke_velocity")
    leaked = g.node("Mul", [previous, g.constant("leak", rule.leak)], "leaked")
    increment = g.node("Mul", [stroke, g.constant("control_dt", rule.dt)], "velocity_increment")
    return g.node("Add", [leaked, increment], "measured_stroke_velocity")


def fallen_back(g, plant: Plant, stored: str, action: str, *, velocity: str, start: int) -> tuple[str, str]:
    """The action after the fallback and the next state's latch (1.0 once handed over); the previous latch is
    the graph's input `state` at column `start`."""
    rule = DamperFallback(plant.experiment.supervisor.fallback, plant, 1)
    # bool
    was = g.node("Cast", [g.columns("state", start, start + 1, "previous_fallback")], "was_fallen_back", to=9)
    displacements = g.columns(
        stored, rule.displacements.start, rule.displacements.stop, "fallback_displacements"
    )
    drift = g.node(
        "MatMul", [displacements, g.constant("fallback_drift_map", rule.drift_t)], "fallback_drift"
    )
    size = g.node("Abs", [drift], "fallback_drift_size")
    largest = g.node("ReduceMax", [size], "largest_drift", axes=[1], keepdims=1)
    beyond_level = g.node("Greater", [largest, g.constant("fallback_level", rule.threshold)], "drift_beyond")
    latched = g.node("Or", [was, beyond_level], "fallen_back")
    speed = g.node(
        "Sub",
        [g.node("Abs", [velocity], "stroke_speed_measured"), g.constant("deadband", rule.deadband)],
        "speed_beyond_deadband",
    )
    # one Clip, not Relu then Clip: onnxruntime's Relu-Clip fusion refuses double bounds
    kept = (
        g.clip(speed, 0.0, rule.saturation, output="speed_kept")
        if np.isfinite(rule.saturation)
        else g.node("Relu", [speed], "speed_kept")
    )
    beyond = g.node("Mul", [g.node("Sign", [velocity], "stroke_direction"), kept], "damped_velocity")
    dampers = g.node("Mul", [beyond, g.constant("damper_gain", -rule.gain)], "damper_action")
    action = g.node("Where", [latched, dampers, action], "fallback_action")
    return action, g.node("Cast", [latched], "fallback_value", to=11)  # double
