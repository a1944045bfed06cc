"""Runs fanned out over processes (`simulation.fanout`): the local and Dask engines give what one process
gives."""

import os
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from rlcontroller.config import ConfigError
from rlcontroller.simulation.fanout import engine, fanned_map
from tests.conftest import OPENSEES_FAILURES, OPENSEES_MISSING

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
FIVE_STORY_FE = CONFIGS.parent / "studies" / "opensees" / "five_story_opensees.yaml"


def _power(shared: dict, item: int) -> tuple[int, int]:
    return item, shared["base"] ** item


@pytest.mark.parametrize("name", ["local", "dask"])
def test_fanned_map_returns_every_item_in_order(name):
    if name == "dask":
        pytest.importorskip("distributed", reason="the Dask engine needs the distributed extra")
    with engine(name):
        results = list(fanned_map(_power, {"base": 3}, list(range(7))))
    assert results == [(i, 3**i) for i in range(7)]


def test_an_address_needs_the_dask_engine():
    with pytest.raises(ConfigError, match="only with --engine dask"), engine("local", "tcp://h:1"):
        pass


@pytest.mark.slow
def test_an_fe_plant_fanned_out_on_dask_equals_local_processes(records):
    """Each controller on each record alone, in processes forked here or in Dask's workers: the same
    numbers."""
    pytest.importorskip("openseespy.opensees", reason=OPENSEES_MISSING, exc_type=OPENSEES_FAILURES)
    pytest.importorskip("distributed", reason="the Dask engine needs the distributed extra")
    from rlcontroller.config import load_experiment
    from rlcontroller.control.controllers import LQGController, Uncontrolled
    from rlcontroller.control.lqg import design_lqg_ground_model
    from rlcontroller.physics.motions.records import load_records
    from rlcontroller.physics.plant import Plant
    from rlcontroller.simulation.rollout import batch_rollout

    plant = Plant(load_experiment(FIVE_STORY_FE))
    motions = [
        replace(m, acceleration=m.acceleration[: int(5.0 / m.dt)]) for m in load_records(records)[0][:3]
    ]
    lqg = LQGController(design_lqg_ground_model(plant.design), plant)
    controllers = [Uncontrolled(plant.building.n_actuators), lqg]
    runs = {}
    for name in ("local", "dask"):
        with engine(name):
            runs[name] = batch_rollout(plant, motions, controllers)
    for local, dask in zip(runs["local"], runs["dask"], strict=True):
        for (one, reward_one), (other, reward_other) in zip(local, dask, strict=True):
            np.testing.assert_array_equal(one.drift, other.drift)
            assert reward_one == reward_other
    assert np.abs(runs["local"][1][0][0].force).max() > 0.0  # the controller acted


def test_local_workers_end_with_their_parent(tmp_path):
    """A SIGTERM to the command that fanned runs out ends its workers too (they were left running an FE
    model)."""
    script = (
        "import os, time\n"
        "from rlcontroller.simulation.fanout import fanned_map\n"
        "def work(folder, item):\n"
        "    open(os.path.join(folder, str(os.getpid())), 'w').close(); time.sleep(120)\n"
        f"list(fanned_map(work, {str(tmp_path)!r}, [1, 2]))\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", script])
    deadline = time.monotonic() + 60
    while len(list(tmp_path.iterdir())) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    workers = [int(path.name) for path in tmp_path.iterdir()]
    assert len(workers) == 2
    parent.send_signal(signal.SIGTERM)
    parent.wait(timeout=30)
    deadline = time.monotonic() + 10
    while any(_alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(_alive(pid) for pid in workers)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as handle:  # a zombie (exited, not yet reaped by init) is gone
        return handle.read().split()[2] != "Z"
