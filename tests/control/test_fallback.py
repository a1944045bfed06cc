"""Model-free damping: the measured stroke velocities follow the true ones on a yielding building; the
fallback hands over once for good at its drift and then acts as dampers that take energy out; env and
batch apply it alike; a bad fallback section is one line."""

import numpy as np
import pytest
from conftest import assert_env_and_batch_agree

from rlcontroller.config import ConfigError, Experiment, build_experiment
from rlcontroller.control.controllers import LQGController, Uncontrolled
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.learning.env import BuildingEnv, rollout
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant
from rlcontroller.simulation.rollout import batch_rollout

EVERY_STORY = [{"story": story, "force_limit": 1.0e5} for story in range(1, 6)]
SENSORS = {"state_estimate": True, "ground_model": True}
YIELDING = {"hysteresis": {"yield_drift": 0.03, "post_yield_ratio": 0.1, "exponent": 2.0}}
DAMPING = [3.0e5, 3.0e5, 1.5e5, 1.0e5, 0.5e5]  # N s/m
FALLBACK = {"drift": 0.02, "damping": DAMPING, "deadband": 0.01}


def experiment(supervisor, actuators=EVERY_STORY) -> Experiment:
    return Experiment.model_validate(
        {"actuators": actuators, "sensors": SENSORS, "supervisor": supervisor, "plant": YIELDING}
    )


def strong(motion: Load, pga: float = 8.0) -> Load:
    """`motion` scaled to `pga` (m/s^2): the yielding building's stories yield."""
    return Load(
        motion.name, motion.dt, motion.acceleration * pga / np.abs(motion.acceleration).max(), synthetic=True
    )


def lqg(plant: Plant) -> LQGController:
    return LQGController(design_lqg_ground_model(plant.design), plant, "LQG + ground model")


def stepped(env: BuildingEnv, controller, motion: Load):
    """Per step: the controller's action, the applied action, the measured and the true stroke velocities
    (m/s, at the readings the step's supervisor took in), the estimated story drifts (m) and the latch."""
    observation, info = env.reset(seed=3, options={"motion": motion})
    controller.reset()
    gamma, n = env.plant.building.actuator_matrix, env.plant.building.n_dofs
    supervisor = env.supervisor
    rows = []
    for _ in range(info["steps"]):
        wanted = np.clip(controller.act(observation), -1.0, 1.0)
        true_velocity = env.state[n : 2 * n] @ gamma
        estimate = observation[env.layout.estimate][:n] * env.layout.estimate_scale[:n]
        drift = np.diff(np.concatenate([[0.0], estimate]))
        observation, *_ = env.step(wanted)
        latched = supervisor.fallback is not None and supervisor.fallback.latched[0]
        applied = observation[env.layout.action].astype(float)
        rows.append((wanted, applied, supervisor.measured.velocity[0].copy(), true_velocity, drift, latched))
    return [np.array(column) for column in zip(*rows, strict=True)]


def test_the_measured_stroke_velocity_follows_the_true_one_on_a_yielding_building():
    """Leaky integration of the noisy floor accelerations, no model, through yielding: the true stroke
    velocities' amplitude within 5 % and their waveform (correlation 0.97-0.98 measured: the leak leads the
    first mode by 8 degrees and the rectangle rule by half a step)."""
    env = BuildingEnv(experiment({"dissipative": "measured"}))
    motion = strong(synthetic_suite(count=1)[0])
    _, _, measured, true, drift, _ = stepped(env, Uncontrolled(5), motion)
    assert np.abs(drift).max() > 1.5 * 0.03  # the stories yield (yield drift 3 cm)
    # least squares: measured ~ slope x true
    slope = np.sum(measured * true, axis=0) / np.sum(true * true, axis=0)
    np.testing.assert_allclose(slope, 1.0, atol=0.05)
    correlation = [np.corrcoef(measured[:, j], true[:, j])[0, 1] for j in range(5)]
    assert min(correlation) > 0.95, correlation


def test_the_fallback_hands_over_for_good_at_its_drift_and_then_acts_as_dampers():
    env = BuildingEnv(experiment({"fallback": FALLBACK}))
    motion = strong(synthetic_suite(count=1)[0])
    wanted, applied, measured, true, drift, latched = stepped(env, lqg(env.plant), motion)
    first = np.argmax(np.abs(drift).max(axis=1) > 0.02)
    assert 0 < first < len(drift) - 100 and not latched[first - 1] and latched[first:].all()
    assert (np.abs(drift[first:]).max(axis=1) < 0.02).any()  # it stays handed over when the drift falls back
    np.testing.assert_allclose(applied[:first], wanted[:first], atol=1e-7)  # float32 observation
    saturation = 1.0e5 / max(DAMPING)  # m/s: where the strongest damper reaches its actuator's limit
    assert (np.abs(measured[first:]) - 0.01 > saturation).any()  # so that the dampers saturate, in proportion
    beyond = np.sign(measured) * np.clip(np.abs(measured) - 0.01, 0.0, saturation)
    dampers = -np.array(DAMPING) / 1.0e5 * beyond
    np.testing.assert_allclose(applied[first:], dampers[first:], atol=1e-6)
    power = np.sum(applied[first:] * 1.0e5 * true[first:], axis=0)  # W summed over steps, per actuator
    assert np.all(power < 0.0), power  # the dampers take energy out of every story


def test_the_dampers_alone_cut_the_yielding_building_s_drift():
    motion = strong(synthetic_suite(count=1)[0])
    bare = rollout(BuildingEnv(experiment(None)), motion, Uncontrolled(5), seed=3)[0]
    always = BuildingEnv(experiment({"fallback": FALLBACK | {"drift": 1e-6}}))
    damped = rollout(always, motion, Uncontrolled(5), seed=3)[0]
    assert np.abs(damped.drift).max() < 0.9 * np.abs(bare.drift).max()


def test_a_measured_dissipative_rule_passes_only_forces_opposing_the_measured_stroke_velocity():
    env = BuildingEnv(experiment({"dissipative": "measured"}))
    wanted, applied, measured, *_ = stepped(env, lqg(env.plant), strong(synthetic_suite(count=1)[0]))
    expected = np.where(wanted * measured > 0.0, 0.0, wanted)
    np.testing.assert_allclose(applied, expected, atol=1e-7)
    assert 0.1 < np.mean(wanted * measured > 0.0) < 0.9


def test_env_and_batch_apply_the_fallback_alike():
    plant = Plant(
        experiment(
            {"trigger": [0.25, 1.0], "dissipative": "measured", "fade_velocity": 0.1, "fallback": FALLBACK}
        )
    )
    assert_env_and_batch_agree(plant, [strong(motion) for motion in synthetic_suite(count=2)], lqg)


@pytest.mark.parametrize(
    ("supervisor", "where", "message"),
    [
        (
            {"fallback": FALLBACK | {"damping": [1.0e5] * 3}},
            "supervisor.fallback.damping",
            "3 values, expected one",
        ),
        ({"fallback": FALLBACK | {"drift": 0.0}}, "supervisor.fallback.drift", "greater than 0"),
        (
            {"fallback": FALLBACK | {"damping": [-1.0] * 5}},
            "supervisor.fallback.damping[0]",
            "greater than or equal",
        ),
        ({"dissipative": "estimated"}, "supervisor.dissipative", "expected true, false or measured"),
    ],
)
def test_a_bad_fallback_is_one_line_naming_the_field(supervisor, where, message):
    with pytest.raises(ConfigError) as error:
        build_experiment({"actuators": EVERY_STORY, "sensors": SENSORS, "supervisor": supervisor})
    assert str(error.value).startswith(f"<config>: {where}") and message in str(error.value)
    assert "\n" not in str(error.value)


def test_measured_velocities_need_every_floor_s_acceleration_first():
    sensors = SENSORS | {"measurements": [{"quantity": "absolute_acceleration", "floors": [5], "scale": 5.0}]}
    with pytest.raises(
        ConfigError, match=r"^<config>: sensors.measurements: .*absolute_acceleration on every floor"
    ):
        build_experiment(
            {"actuators": EVERY_STORY, "sensors": sensors, "supervisor": {"dissipative": "measured"}}
        )


def test_the_fallback_needs_the_state_estimate():
    with pytest.raises(ConfigError, match=r"^<config>: supervisor.fallback: needs sensors.state_estimate"):
        build_experiment({"actuators": EVERY_STORY, "supervisor": {"fallback": FALLBACK}})


def test_measured_velocities_are_not_a_mass_device_s_stroke():
    devices = [{"type": "tuned_mass", "floor": 5, "mass_ratio": 0.02}]
    with pytest.raises(
        ConfigError, match=r"^<config>: supervisor.dissipative: measured stroke velocities are"
    ):
        build_experiment(
            {
                "actuators": EVERY_STORY,
                "devices": devices,
                "sensors": SENSORS,
                "supervisor": {"dissipative": "measured"},
            }
        )


def test_the_building_failed_safe_has_no_fallback():
    """The references (the uncontrolled building, the fail-safe one) run with the control system failed: the
    fallback's dampers act for controllers only."""
    plant = Plant(experiment({"fallback": FALLBACK | {"drift": 1e-6}}))
    motion = strong(synthetic_suite(count=1)[0])
    bare = rollout(BuildingEnv(experiment(None)), motion, Uncontrolled(5), seed=3)[0]
    for reference in (plant.bare, plant.failed_safe):
        assert reference.experiment.supervisor is None
        response = batch_rollout(reference, [motion], [Uncontrolled(5)], seeds=[3])[0][0][0]
        np.testing.assert_array_equal(response.drift, bare.drift)
    supervised = batch_rollout(plant, [motion], [Uncontrolled(5)], seeds=[3])[0][0][0]
    # the dampers act behind zero commands
    assert np.abs(supervised.drift).max() < 0.9 * np.abs(bare.drift).max()
