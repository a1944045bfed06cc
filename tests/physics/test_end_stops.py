"""End-stops of mass devices: a free mass between two stops loses the restitution's square of its energy at
each impact; the stopped building agrees with scipy's Radau on the equations written per floor and device,
with the contacts located as events; below the stops every path steps exactly the linear plant; the stops'
force reaches the floor accelerations."""

import numpy as np
import pytest
import scipy.integrate
from numpy.lib.stride_tricks import sliding_window_view

from rlcontroller.config import Experiment, SimulationConfig
from rlcontroller.devices.tuned_mass import MassDevice, stop_damping_ratio
from rlcontroller.physics.dynamics import step_map
from rlcontroller.physics.end_stops import EndStops
from rlcontroller.physics.motions.excitation import Load, on_control_grid, read_at2
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.structure import Building, with_devices


def driver_experiment(**plant) -> Experiment:
    """The five-story building with the roof's active mass driver (1 m stroke limit, 10 kN)."""
    raw = Experiment().model_dump()
    raw["actuators"] = []
    raw["devices"] = [
        {"type": "active_mass", "floor": 5, "mass_ratio": 0.02, "force_limit": 1e4, "stroke_limit": 1.0}
    ]
    if plant:
        raw["plant"] = plant
    return Experiment.model_validate(raw)


def free_mass_between_stops(restitution: float) -> EndStops:
    """A 1 kg mass with no spring or dashpot between stops at +-0.1 m, on a floor of 10^9 kg held by a stiff
    story (it barely moves), its stops ringing at 10 Hz."""
    floor = Building(
        mass=np.array([[1e9]]),
        stiffness=np.array([[1e14]]),
        damping=np.array([[0.0]]),
        actuator_matrix=np.zeros((1, 0)),
        force_limits=np.zeros(0),
    )
    stiffness = (2 * np.pi * 10.0) ** 2
    device = MassDevice(
        kind="tuned_mass",
        floor=1,
        mass=1.0,
        stiffness=0.0,
        damping=0.0,
        frequency_ratio=1.0,
        damping_ratio=0.0,
        mass_ratio=1e-9,
        stroke_limit=0.1,
        force_limit=None,
        stop_stiffness=stiffness,
        stop_damping=2 * stop_damping_ratio(restitution) * np.sqrt(stiffness),
    )
    building = with_devices(floor, (device,))
    simulation = SimulationConfig(control_dt=0.02)
    return EndStops.of(
        building,
        simulation,
        n_linear=4,
        time_constant=0.0,
        delay_steps=0,
        linear_step=lambda r: step_map(building, simulation, r),
    )


@pytest.mark.parametrize("restitution", [0.3, 0.5, 0.8, 1.0])
def test_a_free_mass_between_two_stops_loses_the_restitutions_square_at_each_impact(restitution):
    stops = free_mass_between_stops(restitution)
    state = np.zeros(4 + 3)
    state[3] = 1.0  # the mass leaves the middle at 1 m/s
    speeds, contacts = [], 0
    in_flight = True
    while len(speeds) < 4:
        state = stops.step(state, np.zeros(0), np.zeros(2), 0.02)
        contacts += state[-1]
        free = abs(state[1] - state[0]) < 0.1 - 0.01  # well clear of both stops
        if free and not in_flight:
            speeds.append(abs(state[3] - state[2]))
        in_flight = free
    assert contacts == 4
    energies = np.square(speeds)
    np.testing.assert_allclose(energies[1:] / energies[:-1], restitution**2, rtol=0.01)
    assert speeds[0] == pytest.approx(restitution, rel=0.01)  # the first impact from 1 m/s


def radau_reference(plant: Plant, grid, forces: np.ndarray, steps: int):
    """The stopped building by Radau on M x'' + C x' + K x = -M 1 a_g + F + Gamma u + P f (F the floor forces,
    if any), f the stop's force while the stroke is past its limit; each contact's start and end located as an
    event. Returns the states at the control steps and the number of contacts."""
    building, stops = plant.building, plant.end_stops
    n, r, dt = building.n_dofs, grid.substeps, plant.control_dt / grid.substeps
    mass_inverse, contact = np.linalg.inv(building.mass), stops.contact_matrix()[:, 0]
    stroke_row = building.stroke_matrix()[0]
    limit, k, c = stops.limits[0], stops.stiffness[0], stops.damping[0]
    floors = (
        np.zeros((grid.ground.size, building.n_floors)) if grid.floor_forces is None else grid.floor_forces
    )
    on_floors = np.eye(n)[:, : building.n_floors]

    def rates(t, z, u, start, slope, side):
        s, rate = stroke_row @ z[:n], stroke_row @ z[n:]
        f = -k * (s - side * limit) - c * rate if side else 0.0
        force = (
            building.actuator_matrix @ u + contact * f - building.damping @ z[n:] - building.stiffness @ z[:n]
        )
        force = force + on_floors @ (start[1] + slope[1] * t)
        return np.concatenate([z[n:], mass_inverse @ force - (start[0] + slope[0] * t)])

    z, states, contacts = np.zeros(2 * n), [np.zeros(2 * n)], 0
    for k_step in range(steps):
        for i in range(r):
            t, end = 0.0, dt
            sample = k_step * r + i
            start = (grid.ground[sample], floors[sample])
            slope = ((grid.ground[sample + 1] - start[0]) / dt, (floors[sample + 1] - start[1]) / dt)
            while t < end:
                s = stroke_row @ z[:n]
                side = 0 if abs(s) < limit else int(np.sign(s))
                faces = (1, -1) if side == 0 else (side,)
                events = [lambda t, z, *_, b=b: stroke_row @ z[:n] - b * limit for b in faces]
                for event in events:
                    event.terminal = True
                    event.direction = 0
                arguments = (forces[k_step], start, slope, side)
                solution = scipy.integrate.solve_ivp(
                    rates, (t, end), z, method="Radau", rtol=1e-10, atol=1e-12, events=events, args=arguments
                )
                z, t = solution.y[:, -1], solution.t[-1]
                if solution.status == 1:  # a contact starts or ends: cross the stop's face by a hair
                    contacts += side == 0
                    z = z + 1e-12 * rates(t, z, forces[k_step], start, slope, side)
                    t += 1e-12
        states.append(z)
    return np.array(states), contacts


def test_the_stopped_driver_matches_radau_with_located_contacts(records):
    plant = Plant(driver_experiment())
    motion = read_at2(records / "RSN1106_KOBE_KJM000.AT2")
    motion = Load("Kobe x 2", motion.dt, 2.0 * motion.acceleration)  # strong enough to hit the stops
    grid = on_control_grid(motion, plant.control_dt)
    steps = 700  # the strong part, with several impacts on both stops
    windows = sliding_window_view(grid.ground, grid.substeps + 1)[:: grid.substeps]
    actions = np.random.default_rng(1).uniform(-1.0, 1.0, (steps, 1))
    states = [np.zeros(plant.n_state)]
    for k in range(steps):
        states.append(plant.integrator.step(states[-1], actions[k], windows[k], plant.control_dt))
    states = np.array(states)
    reference, contacts = radau_reference(plant, grid, actions * plant.force_limits, steps)
    building, n = plant.building, plant.building.n_dofs
    stroke_row = building.stroke_matrix()[0]
    strokes, reference_strokes = states[:, :n] @ stroke_row, reference[:, :n] @ stroke_row
    assert contacts >= 4
    assert states[:, -1].sum() == contacts  # every contact counted, none twice
    assert np.max(np.abs(strokes)) > 1.0  # the stops bind
    assert np.max(np.abs(strokes)) == pytest.approx(np.max(np.abs(reference_strokes)), rel=1e-3)
    # the floors' peak accelerations, the stops' force in them (without it the roof's would be far lower)
    c, d = plant.outputs("absolute_acceleration")
    held = np.vstack([np.zeros((1, 1)), actions]) * plant.force_limits
    accelerations = states @ c.T + held @ d.T
    stops = plant.end_stops
    sides = np.sign(reference_strokes) * (np.abs(reference_strokes) > stops.limits[0])
    f = -stops.stiffness[0] * (reference_strokes - sides * stops.limits[0]) - stops.damping[0] * (
        reference[:, n:] @ stroke_row
    )
    f *= sides != 0
    mass_inverse = np.linalg.inv(building.mass)
    pushes = building.actuator_matrix @ held.T + np.outer(stops.contact_matrix()[:, 0], f)
    forces = pushes - building.damping @ reference[:, n:].T - building.stiffness @ reference[:, :n].T
    reference_accelerations = (mass_inverse @ forces).T[:, : building.n_floors]
    np.testing.assert_allclose(
        np.max(np.abs(accelerations), axis=0), np.max(np.abs(reference_accelerations), axis=0), rtol=2e-3
    )
    from_the_stop = states[:, plant.n_linear] * c[-1, plant.n_linear]  # the roof's, from the stop's force
    assert np.max(np.abs(from_the_stop)) > 0.2 * np.max(np.abs(accelerations[:, -1]))


PLANT_PARTS = {
    "none": {},
    "lag": {"actuators": {"time_constant": 0.02}},
    "delay": {"actuators": {"delay_steps": 2}},
    "lag and delay": {"actuators": {"time_constant": 0.02, "delay_steps": 1}},
}


@pytest.mark.parametrize("name", PLANT_PARTS)
def test_short_of_the_stops_every_plant_steps_as_its_linear_map(name):
    plant = Plant(driver_experiment(**PLANT_PARTS[name]))
    linear = plant.sampled(2).step
    rng = np.random.default_rng(0)
    state, free = np.zeros(plant.n_state), np.zeros(plant.n_linear)
    ground = rng.normal(0.0, 0.3, 2 * 300 + 1)
    for k in range(300):
        action, window = rng.uniform(-0.1, 0.1, 1), ground[2 * k : 2 * k + 3]
        state = plant.integrator.step(state, action, window, plant.control_dt)
        free = (
            linear.phi @ free
            + linear.force_gain @ (action * plant.force_limits)
            + linear.ground_gain @ window
        )
    np.testing.assert_allclose(state[: plant.n_linear], free, rtol=0, atol=1e-12 * np.max(np.abs(free)))
    assert np.all(state[plant.n_linear :] == 0.0)  # no contact: no force, no count


def test_the_inner_maps_end_where_the_linear_step_does():
    """The strokes the stops see at the step's end equal the linear step's, for each actuator dynamics and
    for Newmark: the within-step path and the step agree."""
    cases = [(part, "exact") for part in PLANT_PARTS.values()] + [({}, "newmark")]
    for part, method in cases:
        experiment = driver_experiment(**part)
        experiment = experiment.model_copy(
            update={"simulation": SimulationConfig(control_dt=0.02, method=method)}
        )
        plant = Plant(experiment)
        maps = plant.end_stops.maps(2, plant.control_dt)
        linear = plant.sampled(2).step
        stroke = np.zeros((1, plant.building.n_states))
        stroke[0, : plant.building.n_dofs] = plant.building.stroke_matrix()[0]
        size = stroke.shape[1]
        expected = np.hstack(
            [
                stroke @ linear.phi[:size],
                stroke @ linear.force_gain[:size],
                stroke @ linear.ground_gain[:size],
            ]
        )
        # Newmark at the finer sub-step is a little off its step
        tolerance = 1e-9 if method == "exact" else 1e-3
        np.testing.assert_allclose(maps.strokes[-1, :1], expected, atol=tolerance * np.max(np.abs(expected)))


def test_the_batch_steps_many_as_one():
    plant = Plant(driver_experiment())
    rng = np.random.default_rng(3)
    states = np.zeros((4, plant.n_state))
    states[:, : plant.n_linear] = rng.normal(0.0, 0.1, (4, plant.n_linear))
    states[:2, 5] = states[:2, 4] + np.array([1.05, -1.1])  # two drivers past their stops
    actions, grounds = rng.uniform(-1, 1, (4, 1)), rng.normal(0, 3.0, (4, 2))
    many = plant.end_stops.step_many(states, actions, grounds, plant.control_dt)
    for member in range(4):
        one = plant.integrator.step(states[member], actions[member], grounds[member], plant.control_dt)
        np.testing.assert_array_equal(many[member], one)
    assert np.all(many[:2, -3] != 0.0) and np.all(many[2:, -3] == 0.0)


def test_a_free_mass_says_so_and_has_no_stops():
    raw = driver_experiment().model_dump()
    raw["devices"][0]["type"] = "tuned_mass"
    raw["devices"][0].pop("force_limit")
    raw["devices"][0]["stroke_limit"] = None
    experiment = Experiment.model_validate(raw)
    plant = Plant(experiment)
    assert plant.end_stops is None and plant.integrator is None
    assert "a free mass" in experiment.devices[0].describe(plant.building.devices[0], 1.0)
    stopped = Plant(driver_experiment())
    assert stopped.design.end_stops is None and stopped.elastic.end_stops is None
    assert stopped.design.n_state == stopped.n_linear


@pytest.mark.slow
def test_under_floor_forces_the_stops_see_them_within_the_step():
    """Wind-like floor forces (linear between their samples) push the roof's driver into its stops: its
    strokes and contacts are Radau's, the forces taken inside the step as the ground is."""
    plant = Plant(driver_experiment())
    rng = np.random.default_rng(7)
    samples, dt = 401, 0.05  # 20 s
    gusts = np.cumsum(rng.normal(0.0, 1.0, (samples, 5)), axis=0)
    forces = 4e4 * np.sin(2 * np.pi * 0.68 * np.arange(samples) * dt)[:, None] + 2e3 * gusts
    load = Load("gusts", dt, np.zeros(samples), floor_forces=forces)
    grid = on_control_grid(load, plant.control_dt)
    ground, loads = grid.step_windows()
    steps = grid.n_steps
    actions = np.zeros((steps, 1))
    states = [np.zeros(plant.n_state)]
    for k in range(steps):
        states.append(
            plant.integrator.step(states[-1], actions[k], ground[k], plant.control_dt, floor_forces=loads[k])
        )
    states = np.array(states)
    reference, contacts = radau_reference(plant, grid, actions * plant.force_limits, steps)
    n = plant.building.n_dofs
    stroke_row = plant.building.stroke_matrix()[0]
    strokes, reference_strokes = states[:, :n] @ stroke_row, reference[:, :n] @ stroke_row
    assert contacts >= 2 and states[:, -1].sum() == contacts
    assert np.max(np.abs(strokes)) == pytest.approx(np.max(np.abs(reference_strokes)), rel=1e-3)
    # the whole stroke history, through 100-odd impacts (a velocity at an instant mid-impact swings too fast
    # to compare), and the floors' drifts
    np.testing.assert_allclose(strokes, reference_strokes, atol=2e-3 * np.max(np.abs(reference_strokes)))
    drifts = plant.building.drift_matrix()
    reference_drifts = reference[:, :n] @ drifts.T
    np.testing.assert_allclose(
        states[:, :n] @ drifts.T, reference_drifts, atol=2e-4 * np.max(np.abs(reference_drifts))
    )
