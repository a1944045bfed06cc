"""The training state a checkpoint carries: written and read back whole, refused when damaged."""

import json

import pytest

from rlcontroller.learning.run_folder import TrainingState


def test_the_state_round_trips_through_its_checkpoint_file_without_the_invocation_s_flags():
    state = TrainingState(12.5, {"eval_J1": 0.41, "eval_reward": -3.0}, 4096, time_limit_reached=True)
    saved = json.loads(json.dumps(state.to_json(steps=8192)))
    assert saved["steps"] == 8192
    assert TrainingState.from_json(saved) == TrainingState(12.5, {"eval_J1": 0.41, "eval_reward": -3.0}, 4096)


@pytest.mark.parametrize(
    "saved",
    [
        [],
        {"best": None},
        {"wall_time_s": "10"},
        {"wall_time_s": 1.0, "best": [1]},
        {"wall_time_s": 1, "best_steps": 2.5},
    ],
)
def test_a_damaged_state_is_refused(saved):
    with pytest.raises(ValueError):
        TrainingState.from_json(saved)
