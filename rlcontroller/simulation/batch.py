"""Many buildings stepped together: the batched counterpart of `BuildingEnv`.

A batch of N members shares the experiment (sensors, history, reward, the design model's Kalman
filter); each member has its own plant (randomised per episode with `randomize=True`), motion,
length and noise generator. A control step of the whole batch is one matrix product
[x | action] @ T + forcing for every member at once (T per member when the members' plants or
sampling differ), one batched Kalman update and one batched reward: the observations, rewards and
states are those of N `BuildingEnv`s fed the same actions, member i seeded as env i.

States of plants of different size (actuator delays drawn per episode) are zero-padded to the
largest; a member whose motion has ended keeps stepping on zero forcing until it is restarted, and
its outputs are not used.
"""

from __future__ import annotations

import numpy as np

from rlcontroller.config import ConfigError, PlantConfig
from rlcontroller.config.base import location
from rlcontroller.control.estimation import observation_filter, update_on_block
from rlcontroller.control.supervisor import supervisor
from rlcontroller.control.twin import FailSafeTwin
from rlcontroller.physics.motions.excitation import Load, LoadGrid, on_control_grid
from rlcontroller.physics.motions.loads import generate
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.variations import draw_plant
from rlcontroller.simulation.outputs import StepOutputs, noisy_readings, step_outputs

DRAWN_KEPT = 64  # drawn plants kept by a batch before it starts afresh (continuous draws never repeat)


class BuildingBatch:
    """N buildings of one experiment, stepped as one.

    Parameters
    ----------
    plant : the plant every member simulates (the base of the draws with `randomize=True`).
    size : number of members N.
    motions : motions drawn from at each start (else the experiment's generator).
    randomize : draw a new plant at each start from `plant_randomization`, as `BuildingEnv` does.

    Attributes (one row per member): `observations` (N, obs) float32, `states` (N, S + m) the padded
    plant states x then the clipped actions, `plants`, `steps` (K per member), `k` (steps taken).
    """

    def __init__(
        self, plant: Plant, size: int, motions: list[Load] | None = None, randomize: bool = False
    ) -> None:
        experiment = plant.experiment
        self.plant, self.size, self.motions = plant, size, motions
        self.randomization = experiment.plant_randomization if randomize else None
        self.layout = layout = plant.layout
        self.rows = step_outputs(plant)  # slices and reward rules: the same for every member's plant
        self.control_dt = plant.control_dt
        self.m = plant.building.n_actuators
        self.kalman = observation_filter(plant)
        self.supervisor = supervisor(plant, size)
        self.twin = FailSafeTwin(plant, size) if experiment.sensors.twin else None
        if self.kalman is not None:
            self._filter_matrices = self.kalman.on_observations(layout)
            self.estimates = np.zeros((size, self.kalman.size))
            self.previous_ground = np.zeros(size)  # the last ground reading, as the observation holds it
        self.plants = [plant] * size
        self.steps = np.zeros(size, dtype=int)
        self.k = np.zeros(size, dtype=int)
        self.ground_samples: list[np.ndarray] = [np.zeros(1)] * size
        self.floor_forces: list[np.ndarray | None] = [None] * size  # the floor loads at the control steps (N)
        self.term_factors = np.ones((size, len(self.rows.reward_names)))  # `reward.per_motion`
        self.baseline = experiment.reward.baseline == "uncontrolled"
        self._uncontrolled_cost = np.zeros((size, 1) if self.baseline else (0, 0))  # per member and step
        self.observations = np.zeros((size, layout.size), dtype=np.float32)
        self.previous_action = np.zeros((size, self.m))
        self._n_outputs = self.rows.c.shape[0]
        self._state_size = plant.n_state  # S: every member's state is zero-padded to it
        self.states = np.zeros((size, plant.n_state + self.m))
        self._forcing = np.zeros((size, 1, plant.n_state + self._n_outputs))  # per member and step
        self._stacked: np.ndarray | None = None  # the transitions of all members, padded to S
        self._transitions: list[np.ndarray | None] = [None] * size  # each member's own T (unpadded)
        self._cache: dict[int, np.ndarray] = {}  # sub-steps -> T of the base plant
        self._drawn: dict[str, tuple] = {}  # a drawn plant part's JSON -> `_drawn_plant`
        self._ground_cache: dict[int, tuple] = {}  # id(load) -> (load, sub-steps, its forcing)
        self._windows: list[np.ndarray | None] = [None] * size  # non-linear members: ground per step
        self._load_windows: list[np.ndarray | None] = [None] * size  # and floor forces per step, if any
        self._member_rows = [self.rows] * size  # each member's output rows (its drawn plant's)
        self._members = np.arange(size)

    def _resize(self, state_size: int, length: int) -> None:
        """Make room for plant states of `state_size` and motions of `length` control steps."""
        old_size, old_length = self._state_size, self._forcing.shape[1]
        state_size, length = max(state_size, old_size), max(length, old_length)
        if (state_size, length) == (old_size, old_length):
            return
        states = np.zeros((self.size, state_size + self.m))
        states[:, :old_size] = self.states[:, :old_size]
        states[:, state_size:] = self.states[:, old_size:]
        forcing = np.zeros((self.size, length, state_size + self._n_outputs))
        forcing[:, :old_length, :old_size] = self._forcing[:, :, :old_size]
        forcing[:, :old_length, state_size:] = self._forcing[:, :, old_size:]
        self._state_size, self.states, self._forcing = state_size, states, forcing
        if self.baseline:
            cost = np.zeros((self.size, length))
            cost[:, :old_length] = self._uncontrolled_cost[:, :old_length]
            self._uncontrolled_cost = cost
        self._stacked = None

    def _drawn_plant(self, drawn: PlantConfig) -> tuple[Plant, StepOutputs, dict[int, np.ndarray]]:
        """The plant of a drawn plant part with its output rows and its transitions per sampling, built once
        per distinct draw (a whole-number draw, such as a delay, repeats; continuous ones are kept up to
        DRAWN_KEPT)."""
        key = drawn.model_dump_json()
        if key not in self._drawn:
            if len(self._drawn) >= DRAWN_KEPT:
                self._drawn.clear()
            plant = Plant(self.plant.experiment.model_copy(update={"plant": drawn}))
            self._drawn[key] = (plant, step_outputs(plant), {})
        return self._drawn[key]

    def start(
        self, member: int, rng: np.random.Generator, motion: Load | None = None, grid: LoadGrid | None = None
    ) -> None:
        """Start `member` from rest: draw its plant (with randomisation) and motion (unless given, with
        its `grid` when known), then its sensor noise, from `rng`, in the order `BuildingEnv.reset` draws
        them."""
        plant, rows, transitions = self.plant, self.rows, self._cache
        if self.randomization is not None:
            plant, rows, transitions = self._drawn_plant(
                draw_plant(self.randomization, plant.experiment.plant, rng)
            )
        reused = motion is not None or bool(self.motions)  # a motion other members may start with too
        if motion is None:
            if self.motions:
                motion = self.motions[int(rng.integers(len(self.motions)))]
            else:
                motion = generate(plant.experiment.excitation.generator, rng, plant.building)
        grid = on_control_grid(motion, self.control_dt) if grid is None else grid
        sampled, base = plant.sampled(grid.substeps), plant is self.plant
        # the load's forcing, kept for the members that start with the same load object on the base plant
        # (every controller's lane does); the transition kept per sampling of each plant
        cached = self._ground_cache.get(id(motion))
        if cached is not None and cached[0] is motion and cached[1] == grid.substeps:
            load_forcing = cached[2]
        else:
            load_forcing = sampled.forcing(grid, rows.c, rows.load)
            if reused and base:
                self._ground_cache[id(motion)] = (motion, grid.substeps, load_forcing)  # its id stays its own
        transition = None
        if plant.integrator is None:
            if grid.substeps not in transitions:
                transitions[grid.substeps] = sampled.transition(rows.c, rows.d)
            transition = transitions[grid.substeps]
        n_steps = grid.n_steps
        self._resize(plant.n_state, n_steps + 1)  # the last row stays zero: the forcing after the end
        size = self._state_size
        forcing = self._forcing[member]
        forcing[:] = 0.0
        forcing[:n_steps, : plant.n_state] = load_forcing[:, : plant.n_state]
        forcing[:n_steps, size:] = load_forcing[:, plant.n_state :]
        self._transitions[member] = transition
        if plant.integrator is None:
            self._windows[member], self._load_windows[member] = None, None
        else:
            self._windows[member], self._load_windows[member] = grid.step_windows()
        self._stacked = None
        self.floor_forces[member] = grid.forces_at_steps
        ground = grid.ground_at_steps
        readings = noisy_readings(plant, ground, rng)
        forcing[:n_steps, size:][:, self.rows.readings] += readings[1:]
        self.plants[member] = plant
        self._member_rows[member] = rows
        self.ground_samples[member] = ground
        self.term_factors[member] = self.rows.term_factors(ground)
        if self.baseline:
            self._uncontrolled_cost[member] = 0.0
            self._uncontrolled_cost[member, :n_steps] = self._cost_left_alone(
                member, plant, transition, n_steps
            )
        self.steps[member], self.k[member] = n_steps, 0
        self.states[member] = 0.0
        self.previous_action[member] = 0.0
        if self.supervisor is not None:
            self.supervisor.reset(member)
        if self.twin is not None:
            self.twin.reset(member)
        self.layout.start(self.observations[member : member + 1], readings[:1])
        if self.kalman is not None:
            self.estimates[member] = 0.0
            self.previous_ground[member] = 0.0
            self._update_estimates(readings[0][None], self.previous_action[member][None], [member])

    def _padded(self, inner: np.ndarray) -> np.ndarray:
        """A member's T zero-padded to the batch's state size."""
        size, n = self._state_size, inner.shape[0] - self.m
        if n == size:
            return inner
        padded = np.zeros((size + self.m, size + self._n_outputs))
        padded[:n, :n] = inner[:n, :n]
        padded[:n, size:] = inner[:n, n:]
        padded[size:, :n] = inner[n:, :n]
        padded[size:, size:] = inner[n:, n:]
        return padded

    def _update_estimates(self, readings: np.ndarray, held: np.ndarray, members) -> None:
        """The filter's update from `readings` (the newest block, as the observation holds it)."""
        estimates = update_on_block(
            self._filter_matrices,
            self.layout,
            self.estimates[members],
            readings,
            held_action=held,
            previous_ground=self.previous_ground[members],
        )
        self.estimates[members] = estimates
        self.previous_ground[members] = readings[:, -1]
        self.observations[members, self.layout.estimate] = self.layout.scaled_estimate(estimates)
        if self.twin is not None:
            twin = self.layout.scaled_twin(*self.twin.observe(estimates, members))
            self.observations[members, self.layout.twin] = twin

    def read_back_estimates(self) -> None:
        """The filter's estimates and the twin's state as the observations hold them (after a caller wrote
        the observations: they are the controllers' whole state)."""
        if self.kalman is not None:
            self.estimates[:] = self.observations[:, self.layout.estimate] * self.layout.estimate_scale
        if self.twin is not None:
            twin = self.observations[:, self.layout.twin] * self.layout.twin_scale
            self.twin.restore(self.estimates, *np.split(twin, [self.estimates.shape[1]], axis=1))

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Apply `actions` (N, m), clipped to [-1, 1]; returns the new observations (N, obs) float32 (a
        view: copy to keep), the rewards (N,) and which members' motions have just ended (N,) bool."""
        outputs = self.advance(actions)
        held = self.held_actions()
        rewards = self.rewards(outputs[:, self.rows.reward], held, self.previous_action)
        if self.baseline:  # `reward.baseline`: the cost of the step left uncontrolled, added back
            rewards += self._uncontrolled_cost[self._members, np.minimum(self.k, self.steps) - 1]
        self.previous_action[:] = held
        return self.observations, rewards, self.k == self.steps

    def _cost_left_alone(
        self, member: int, plant: Plant, transition: np.ndarray | None, n_steps: int
    ) -> np.ndarray:
        """Each step's cost (the reward's terms, their sum) of `member`'s building under its load with no
        force: the same linear step map and forcing, the action zero (`reward.baseline`)."""
        if transition is None:
            where = location(*self.plant.experiment.origin("reward"), "baseline")
            raise ConfigError(
                f"{where}: uncontrolled needs a linear plant (no yielding stories, dampers or end-stops)"
            )
        n, size = plant.n_state, self._state_size
        forcing = self._forcing[member]
        state, outputs = np.zeros(n), np.empty((n_steps, self._n_outputs))
        for k in range(n_steps):
            new = state @ transition[:n]
            state = new[:n] + forcing[k, :n]
            outputs[k] = new[n:] + forcing[k, size:]
        zero = np.zeros((n_steps, self.m))
        terms = self.rows.reward_terms(outputs[:, self.rows.reward], zero, zero)
        return (terms * self.term_factors[member]).sum(axis=-1)

    def rewards(self, reward_rows: np.ndarray, held: np.ndarray, previous_held: np.ndarray) -> np.ndarray:
        """The rewards (..., N) of steps whose outputs' reward rows are `reward_rows` (..., N, rows),
        with the actions `held` over them and `previous_held` over the steps before (..., N, m)."""
        return -(self.rows.reward_terms(reward_rows, held, previous_held) * self.term_factors).sum(axis=-1)

    def advance(self, actions: np.ndarray) -> np.ndarray:
        """`step` without its rewards, for a caller that takes them for many steps at once (`rewards`):
        returns the new outputs (N, outputs), a view."""
        size, states = self._state_size, self.states
        clipped = states[:, size:]
        np.asarray(actions).clip(-1.0, 1.0, out=clipped)
        if self.supervisor is not None:
            self.supervisor(self.observations, clipped)
        if self.twin is not None:
            self.twin.advance(clipped)
        forcing = self._forcing[self._members, np.minimum(self.k, self._forcing.shape[1] - 1)]
        new = self._advance(clipped) + forcing
        states[:, :size] = new[:, :size]
        outputs = new[:, size:]
        self.k += 1

        observations, readings = self.observations, outputs[:, self.rows.readings]
        self.layout.advance(observations, readings, clipped)
        if self.kalman is not None:
            self._update_estimates(readings, clipped, slice(None))
        return outputs

    def _advance(self, clipped: np.ndarray) -> np.ndarray:
        """[x_{k+1} | outputs_{k+1}] without the forcing, for every member."""
        if self._windows[0] is not None:
            return self._advance_nonlinear(clipped)
        if self._stacked is None:
            first = self._transitions[0]
            if all(t is first for t in self._transitions):
                self._stacked = self._padded(first)
            else:
                self._stacked = np.stack([self._padded(t) for t in self._transitions])
        if self._stacked.ndim == 2:
            return self.states @ self._stacked
        return np.matmul(self.states[:, None, :], self._stacked)[:, 0, :]

    def _advance_nonlinear(self, clipped: np.ndarray) -> np.ndarray:
        size = self._state_size
        new = np.zeros((self.size, size + self._n_outputs))
        if hasattr(self.plant.integrator, "step_many") and all(plant is self.plant for plant in self.plants):
            return self._advance_many(clipped, new)
        for member, plant in enumerate(self.plants):
            n, windows, loads = plant.n_state, self._windows[member], self._load_windows[member]
            k = min(self.k[member], windows.shape[0] - 1)
            limits = plant.force_limits
            arguments = (self.states[member, :n], clipped[member], windows[k], self.control_dt)
            state = (
                plant.integrator.step(*arguments)
                if loads is None
                else plant.integrator.step(*arguments, floor_forces=loads[k])
            )
            rows = self._member_rows[member]
            new[member, :n] = state
            new[member, size:] = state @ rows.c.T + clipped[member] @ (rows.d * limits).T
        return new

    def _advance_many(self, clipped: np.ndarray, new: np.ndarray) -> np.ndarray:
        """Every member of one plant that steps many at once (dampers, end-stops) in one compiled call per
        ground sampling (members whose records share it)."""
        plant, size = self.plant, self._state_size
        n, rows = plant.n_state, self.rows
        groups: dict[tuple[int, bool], list[int]] = {}
        for member, windows in enumerate(self._windows):
            groups.setdefault((windows.shape[1], self._load_windows[member] is not None), []).append(member)
        for (_, loaded), members in groups.items():
            at = [min(self.k[m], self._windows[m].shape[0] - 1) for m in members]
            grounds = np.stack([self._windows[m][k] for m, k in zip(members, at, strict=True)])
            arguments = (self.states[members, :n], clipped[members], grounds, self.control_dt)
            if loaded:
                forces = np.stack([self._load_windows[m][k] for m, k in zip(members, at, strict=True)])
                states = plant.integrator.step_many(*arguments, floor_forces=forces)
            else:
                states = plant.integrator.step_many(*arguments)
            new[members, :n] = states
            new[members, size:] = states @ rows.c.T + clipped[members] @ (rows.d * plant.force_limits).T
        return new

    def held_actions(self) -> np.ndarray:
        """The clipped actions held over the step that ended now, per member (N, m): a view; times
        the force limits, the commands (N)."""
        return self.states[:, self._state_size :]

    def plant_states(self) -> np.ndarray:
        """The padded plant states x (N, S)."""
        return self.states[:, : self._state_size]


def episode_generator(seed: int) -> np.random.Generator:
    """The generator `BuildingEnv.reset(seed=seed)` draws an episode from (gymnasium's
    `seeding.np_random`: PCG64 on the seed's SeedSequence), made without importing gymnasium."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed)))
