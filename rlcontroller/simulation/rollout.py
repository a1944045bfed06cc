"""Whole loads simulated: every controller on every load (`batch_rollout`: batches of similar length, all
controllers stepping together, or fanned out over processes for a plant of one model per process), and the
building left alone (`uncontrolled_responses`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from rlcontroller.control.controllers import Controller, LQGBank, LQGController, Uncontrolled
from rlcontroller.physics.fe.opensees import NonConvergence
from rlcontroller.physics.motions.excitation import Load, LoadGrid, on_control_grid
from rlcontroller.physics.plant import Plant
from rlcontroller.physics.response import Response
from rlcontroller.simulation.batch import BuildingBatch, episode_generator
from rlcontroller.simulation.fanout import fanned_map

ROWS_PER_BATCH = 400_000  # members x control steps simulated at once (bounds the memory to ~150 MB)


def batch_rollout(
    plant: Plant,
    motions: list[Load],
    controllers: list[Controller],
    *,
    seeds: list[int] | None = None,
    randomize: bool = False,
    on_motions: Callable[[int], None] | None = None,
) -> list[list[tuple[Response, float]]]:
    """Run every controller on every motion (motion i with its noise, and with `randomize` its plant,
    drawn from seeds[i], default i, the same for every controller): the (response, total reward) that
    `rollout` gives on each motion in turn, computed in batches of motions of similar length, all
    controllers stepping together; one list per controller. `on_motions(count)` is called as each
    batch of `count` motions is done (a progress bar)."""
    if not controllers:
        return []
    seeds = list(range(len(motions))) if seeds is None else list(seeds)
    grids = [on_control_grid(motion, plant.control_dt) for motion in motions]
    if plant.fe_model is not None:
        return _fanned_rollout(
            plant, list(zip(motions, grids, strict=True)), controllers, seeds, randomize, on_motions
        )
    lengths = [grid.n_steps for grid in grids]  # control steps
    order = sorted(range(len(motions)), key=lambda i: lengths[i])
    results: list[list] = [[None] * len(motions) for _ in controllers]
    while order:
        chunk = [order.pop(0)]
        while order and len(controllers) * (len(chunk) + 1) * lengths[order[0]] <= ROWS_PER_BATCH:
            chunk.append(order.pop(0))
        responses = _rollout_chunk(
            plant, [(motions[i], grids[i]) for i in chunk], controllers, [seeds[i] for i in chunk], randomize
        )
        for c, runs in enumerate(responses):
            for index, response in zip(chunk, runs, strict=True):
                results[c][index] = response
        if on_motions is not None:
            on_motions(len(chunk))
    return results


def _fanned_rollout(
    plant: Plant,
    loads: list[tuple[Load, LoadGrid]],
    controllers: list[Controller],
    seeds: list[int],
    randomize: bool,
    on_motions: Callable[[int], None] | None,
) -> list[list[tuple[Response, float]]]:
    """`batch_rollout` on a plant that holds one model per process (an OpenSees model): each controller on
    each load alone, fanned out over processes (`simulation.fanout`)."""
    runs = [(c, i) for i in range(len(loads)) for c in range(len(controllers))]
    results: list[list] = [[None] * len(loads) for _ in controllers]
    left = [len(controllers)] * len(loads)
    finished = fanned_map(_fanned_run, (plant, loads, controllers, seeds, randomize), runs)
    for (c, i), result in zip(runs, finished, strict=True):
        results[c][i] = result
        left[i] -= 1
        if on_motions is not None and left[i] == 0:
            on_motions(1)
    return results


def _fanned_run(shared: tuple, run: tuple[int, int]) -> tuple[Response, float]:
    plant, loads, controllers, seeds, randomize = shared
    c, i = run
    try:
        return _rollout_chunk(plant, [loads[i]], [controllers[c]], [seeds[i]], randomize)[0][0]
    except NonConvergence as error:
        raise NonConvergence(f"{loads[i][0].name}, {controllers[c].name}: {error}") from None


def _rollout_chunk(
    plant: Plant,
    loads: list[tuple[Load, LoadGrid]],
    controllers: list[Controller],
    seeds: list[int],
    randomize: bool,
) -> list[list[tuple[Response, float]]]:
    count = len(loads)
    batch = BuildingBatch(plant, count * len(controllers), randomize=randomize)
    for member in reversed(range(batch.size)):  # the longest motion first: the batch is sized once
        motion = member % count
        batch.start(member, episode_generator(seeds[motion]), *loads[motion])
    n_steps = int(batch.steps.max())
    states = np.zeros((n_steps + 1, batch.size, batch.plant_states().shape[1]))
    commands = np.zeros((n_steps + 1, batch.size, batch.m))
    for controller in controllers:
        controller.reset()
    lanes = [(controller, slice(c * count, (c + 1) * count)) for c, controller in enumerate(controllers)]
    observations, actions = batch.observations, np.zeros((batch.size, batch.m))
    acting = fused_lanes(lanes, count)
    reward_rows = batch.rows.reward
    outputs = np.zeros((n_steps + 1, batch.size, reward_rows.stop - reward_rows.start))  # their reward rows
    for k in range(1, n_steps + 1):
        for controller, lane in acting:
            actions[lane] = controller.act(observations[lane])
        outputs[k] = batch.advance(actions)[:, reward_rows]
        states[k] = batch.plant_states()
        commands[k] = batch.held_actions()
    rewards = np.zeros((n_steps + 1, batch.size))
    rewards[1:] = batch.rewards(outputs[1:], commands[1:], commands[:-1])
    commands *= plant.force_limits
    rewards[np.arange(n_steps + 1)[:, None] > batch.steps] = 0.0
    totals = rewards.cumsum(axis=0)[-1]  # step by step, in order
    responses: list[list[tuple[Response, float]]] = []
    for _, lane in lanes:
        runs = []
        for member in range(lane.start, lane.stop):
            member_plant, steps = batch.plants[member], batch.steps[member]
            response = member_plant.sampled().response(
                states[: steps + 1, member, : member_plant.n_state],
                commands[: steps + 1, member],
                np.arange(steps + 1) * plant.control_dt,
                ground=batch.ground_samples[member],
                floor_forces=batch.floor_forces[member],
            )
            if plant.fe_model is not None and plant.fe_model.record_connections:  # one run per process
                response = replace(response, connections=plant.fe_model.connection_history())
            runs.append((response, float(totals[member])))
        responses.append(runs)
    return responses


def fused_lanes(lanes: list[tuple[Controller, slice]], rows: int) -> list[tuple[Controller | LQGBank, slice]]:
    """The lanes with each run of consecutive LQG controllers acting as one `LQGBank`."""
    fused: list[tuple[Controller | LQGBank, slice]] = []
    run: list[tuple[LQGController, slice]] = []
    for controller, lane in [*lanes, (None, None)]:
        if isinstance(controller, LQGController):
            run.append((controller, lane))
            continue
        if len(run) > 1:
            fused.append((LQGBank([c for c, _ in run], rows), slice(run[0][1].start, run[-1][1].stop)))
        else:
            fused += run
        run = []
        if controller is not None:
            fused.append((controller, lane))
    return fused


def uncontrolled_responses(
    plant: Plant, motions: list[Load], on_motions: Callable[[int], None] | None = None
) -> list[Response]:
    """`plant` with no command (`plant.bare` is the building without its devices): whole-record
    simulations with the step map, or a batch through the non-linear step for yielding stories (and an FE
    model's runs, each motion reported to `on_motions` as it is done)."""
    if plant.integrator is not None:
        runs = batch_rollout(
            plant, motions, [Uncontrolled(plant.building.n_actuators)], on_motions=on_motions
        )[0]
        return [response for response, _ in runs]
    grids = [on_control_grid(motion, plant.control_dt) for motion in motions]
    return [plant.sampled(grid.substeps).simulate(grid) for grid in grids]
