"""The supervisor between controllers and actuators: off at rest, scaled by its trigger, passing only
forces that take energy out of the building; env and batch apply it alike; with it, LQG on a
building actuated on every story passes a safety check it fails without it."""

import numpy as np
import pytest
from conftest import REPOSITORY

from rlcontroller.config import ConfigError, Experiment, build_experiment, load_safety_check
from rlcontroller.control.controllers import LQGController
from rlcontroller.control.lqg import design_lqg_ground_model
from rlcontroller.evaluation.safety import safety_check
from rlcontroller.learning.env import BuildingEnv
from rlcontroller.physics.motions.excitation import Load
from rlcontroller.physics.motions.records import synthetic_suite
from rlcontroller.physics.plant import Plant

EVERY_STORY = [{"story": story, "force_limit": 1.0e5} for story in range(1, 6)]
SENSORS = {"state_estimate": True, "ground_model": True}
SUPERVISOR = {"trigger": [0.25, 1.0], "dissipative": True}


def experiment(supervisor=SUPERVISOR, actuators=EVERY_STORY) -> Experiment:
    return Experiment.model_validate({"actuators": actuators, "sensors": SENSORS, "supervisor": supervisor})


def lqg(plant: Plant) -> LQGController:
    return LQGController(design_lqg_ground_model(plant.design), plant, "LQG + ground model")


def run(env: BuildingEnv, controller, motion: Load, seed: int = 3):
    """Each step's observation before it, the controller's action and the action applied."""
    observation, info = env.reset(seed=seed, options={"motion": motion})
    controller.reset()
    seen, wanted, applied = [], [], []
    for _ in range(info["steps"]):
        action = controller.act(observation)
        seen.append(observation)
        wanted.append(action)
        observation, *_ = env.step(action)
        applied.append(observation[env.layout.action].astype(float))
    return np.array(seen), np.array(wanted), np.array(applied)


def test_at_rest_the_trigger_keeps_every_force_at_zero():
    still = Load("at rest", 0.02, np.zeros(3001), synthetic=True)
    supervised = BuildingEnv(experiment())
    _, wanted, applied = run(supervised, lqg(supervised.plant), still)
    assert np.abs(wanted).max() > 1e-3  # LQG reacts to the sensor noise...
    assert np.all(applied == 0.0)  # ...and the supervisor keeps it from the actuators


def test_the_applied_action_is_the_controller_s_gated_by_dissipation_and_scaled_by_the_trigger():
    env = BuildingEnv(experiment())
    layout, n = env.layout, 5
    motion = synthetic_suite(count=1)[0]
    seen, wanted, applied = run(env, lqg(env.plant), motion)
    peak_ground = np.maximum.accumulate(np.abs(seen[:, layout.ground] * layout.ground_scale))
    gain = np.clip((peak_ground - 0.25) / 0.75, 0.0, 1.0)
    velocity = seen[:, layout.estimate][:, n : 2 * n]  # floor velocities (scaled), relative to the ground
    story_velocity = velocity - np.hstack([np.zeros((len(velocity), 1)), velocity[:, :-1]])
    feeds_energy = np.clip(wanted, -1, 1) * story_velocity > 0.0
    expected = np.where(feeds_energy, 0.0, np.clip(wanted, -1, 1)) * gain[:, None]
    np.testing.assert_allclose(applied, expected, rtol=1e-6, atol=1e-7)  # float32 observation
    assert 0.1 < feeds_energy.mean() < 0.9 and gain[-1] == 1.0 and gain[0] == 0.0


def test_under_wind_the_trigger_also_watches_the_floors():
    """The ground reading does not see wind: in an experiment trained under wind the trigger's gain follows
    the largest of the floor accelerations instead, so the controller acts in wind (the ground reading alone
    stays at sensor noise) and, behind the experiment's trigger, stays off at rest."""
    from rlcontroller.assets import CONFIGS
    from rlcontroller.config import load_experiment
    from rlcontroller.control.lqg import design_lqg_wind_model
    from rlcontroller.physics.motions.loads import generate_suite

    wind = load_experiment(CONFIGS / "experiments" / "five_story_wind.yaml")
    low = wind.supervisor.model_copy(update={"trigger": (0.1, 0.3)})
    env = BuildingEnv(wind.model_copy(update={"supervisor": low}))
    layout, controller = (
        env.layout,
        LQGController(design_lqg_wind_model(env.plant.design), env.plant, "LQG + wind"),
    )
    gust = generate_suite(wind.excitation.generator, 1, 2, env.plant.building)[0]
    seen, wanted, applied = run(env, controller, gust)
    floors, ground = (
        seen[:, layout.readings] * layout.reading_scale,
        seen[:, layout.ground] * layout.ground_scale,
    )
    gain = np.clip((np.maximum.accumulate(np.abs(floors).max(axis=1)) - 0.1) / 0.2, 0.0, 1.0)
    np.testing.assert_allclose(applied, np.clip(wanted, -1, 1) * gain[:, None], rtol=1e-6, atol=1e-7)
    ground_alone = np.clip((np.maximum.accumulate(np.abs(ground)) - 0.1) / 0.2, 0.0, 1.0)
    assert gain[-1] == 1.0 and ground_alone[-1] < 0.75  # on sensor noise (0.05 m/s^2) the ground gives a part
    from rlcontroller.control.supervisor import trigger_readings

    drift = wind.sensors.measurements[0].model_copy(update={"quantity": "drift", "scale": 0.01})
    drifts = wind.sensors.model_copy(update={"measurements": [drift]})
    blind = Plant(wind.model_copy(update={"sensors": drifts}))  # no floor acceleration read: the ground still
    assert [list(part) for part in trigger_readings(blind)] == [
        [blind.layout.ground],
        [blind.layout.ground_scale],
    ]
    own = BuildingEnv(wind)  # its own trigger, 0.3-1.0 m/s^2: six standard deviations of the noise
    _, _, applied = run(own, controller, Load("at rest", 0.02, np.zeros(3001), synthetic=True))
    assert np.all(applied == 0.0)


def test_dissipative_forces_take_energy_out_of_the_building():
    """The rule judges by the filter's estimate; on the true story velocities the power the
    actuators put into the building is still negative overall and far below the unsupervised one's."""
    motion = synthetic_suite(count=1)[0]
    power = {}
    for name, supervisor in (("dissipative", {"dissipative": True}), ("free", None)):
        env = BuildingEnv(experiment(supervisor))
        controller = lqg(env.plant)
        observation, info = env.reset(seed=3, options={"motion": motion})
        controller.reset()
        total = 0.0
        for _ in range(info["steps"]):
            observation, *_ = env.step(controller.act(observation))
            velocity = env.state[5:]
            total += env.held_force @ (env.plant.building.actuator_matrix.T @ velocity)
        power[name] = total
    assert power["dissipative"] < 0.0
    assert power["free"] > 0.0 or power["dissipative"] < 0.5 * power["free"]


FADED = {"trigger": [0.15, 0.6], "dissipative": True, "fade_velocity": 0.1}  # configs/supervisors/faded.yaml


@pytest.mark.slow
def test_supervised_lqg_passes_a_check_it_fails_without_the_supervisor():
    """Behind the default's faded supervisor; the hard cut (SUPERVISOR) passes the drift criteria on round 7's
    suite too, but its force steps raise mean J2 above 1 (1.22 on these 40 motions: docs/safety_check.md)."""
    standard = load_safety_check(REPOSITORY / "configs" / "checks" / "standard.yaml")
    # too few for 5 %: strict
    small = {"motions": 40, "rest_runs": 2, "rest_duration": 20.0, "risk_bound": 0.0}
    standard = standard.model_copy(update=small)
    free, supervised = Plant(experiment(None)), Plant(experiment(FADED))
    failed = safety_check(free, lqg(free), standard, [])
    passed = safety_check(supervised, lqg(supervised), standard, [])
    assert not failed.criteria["at rest"].passed
    assert passed.passed, passed.lines()


@pytest.mark.parametrize(
    ("supervisor", "message"),
    [
        ({"trigger": [1.0, 0.5]}, "<config>: supervisor.trigger: expected [low, high] with low <= high"),
        (
            {"trigger": [0.25, float("inf")]},
            "<config>: supervisor.trigger[1]: Input should be a finite number",
        ),
        (
            {"trigger": [-1.0, 1.0]},
            "<config>: supervisor.trigger[0]: Input should be greater than or equal to 0",
        ),
        ({"deadband": 1.0}, "<config>: supervisor.deadband: unknown key"),
    ],
)
def test_a_bad_supervisor_is_one_line_naming_the_field(supervisor, message):
    with pytest.raises(ConfigError) as error:
        build_experiment({"sensors": SENSORS, "supervisor": supervisor})
    assert str(error.value).startswith(message) and "\n" not in str(error.value)


def test_a_dissipative_supervisor_needs_the_state_estimate():
    with pytest.raises(
        ConfigError, match=r"^<config>: supervisor.dissipative: needs sensors.state_estimate: true"
    ):
        build_experiment({"supervisor": {"dissipative": True}})


def test_a_faded_rule_scales_a_force_that_feeds_energy_by_the_stroke_speed():
    """With fade_velocity v_f a force that would feed its story passes scaled by 1 - |v| / v_f (none from
    v_f on): continuous where the hard rule switches at every velocity reversal."""
    fade = 0.05  # m/s
    env = BuildingEnv(experiment({"trigger": [0.25, 1.0], "dissipative": True, "fade_velocity": fade}))
    layout, n = env.layout, 5
    seen, wanted, applied = run(env, lqg(env.plant), synthetic_suite(count=1)[0])
    peak_ground = np.maximum.accumulate(np.abs(seen[:, layout.ground] * layout.ground_scale))
    gain = np.clip((peak_ground - 0.25) / 0.75, 0.0, 1.0)
    velocity = seen[:, layout.estimate][:, n : 2 * n] * layout.estimate_scale[n : 2 * n]  # m/s
    story_velocity = velocity - np.hstack([np.zeros((len(velocity), 1)), velocity[:, :-1]])
    action = np.clip(wanted, -1, 1)
    feeds_energy = action * story_velocity > 0.0
    kept = np.where(feeds_energy, np.clip(1.0 - np.abs(story_velocity) / fade, 0.0, 1.0), 1.0)
    # float32 observation
    np.testing.assert_allclose(applied, action * kept * gain[:, None], rtol=1e-5, atol=1e-6)
    partly = feeds_energy & (np.abs(story_velocity) < fade) & (gain[:, None] > 0)
    assert partly.sum() > 10  # forces that the hard rule would have cut pass in part


def test_a_fade_without_the_dissipative_rule_is_refused():
    with pytest.raises(
        ConfigError, match=r"^<config>: supervisor: .*fade_velocity fades the dissipative rule"
    ):
        build_experiment({"sensors": SENSORS, "supervisor": {"trigger": [0.25, 1.0], "fade_velocity": 0.1}})


def test_dampers_take_no_supervisor():
    dampers = [{"type": "mr_damper", "story": 1, "capacity": 1.0e5}]
    with pytest.raises(ConfigError, match=r"^<config>: supervisor: not with semi-active dampers"):
        build_experiment({"actuators": [], "devices": dampers, "supervisor": {"trigger": [0.25, 1.0]}})
