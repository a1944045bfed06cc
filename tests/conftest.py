import os
from pathlib import Path

import pytest

from rlcontroller.config import BuildingConfig, Experiment
from rlcontroller.physics.structure import Building, build

REPOSITORY = Path(__file__).resolve().parents[1]
# A PPO residual network policy with its config and failing verdict: the retired `five_story` model (worse
# than no control on 73 of the safety check's 320 motions), kept only as a fixture of the policy file format.
NETWORK_POLICY = REPOSITORY / "tests" / "data" / "retired_five_story"


def records_folder() -> Path:
    """The seven PEER records: $RLC_RECORDS, by default ../shared/records beside the clone."""
    return Path(os.environ.get("RLC_RECORDS", REPOSITORY.parent / "shared" / "records"))


@pytest.fixture
def records() -> Path:
    folder = records_folder()
    if not (folder / "manifest.csv").is_file():
        pytest.skip(f"no PEER records at {folder} (set RLC_RECORDS to the folder holding manifest.csv)")
    return folder


@pytest.fixture
def paper_building() -> Building:
    experiment = Experiment()
    return build(experiment.building, experiment.actuators)


def sdof(mass: float, stiffness: float, damping: float, force_limit: float = 1.0e5) -> Building:
    from rlcontroller.config import ActuatorConfig

    config = BuildingConfig(masses=[mass], stiffnesses=[stiffness], damping={"matrix": [[damping]]})
    return build(config, [ActuatorConfig(story=1, force_limit=force_limit)])
