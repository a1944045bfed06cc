"""Kept uncontrolled responses of an FE plant: the same numbers read back, a new file when the model's folder
or the suite changes, recomputed when the file is damaged; other plants keep nothing."""

import shutil
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import OPENSEES_FAILURES, OPENSEES_MISSING

pytest.importorskip("openseespy.opensees", reason=OPENSEES_MISSING, exc_type=OPENSEES_FAILURES)

from rlcontroller import api  # noqa: E402
from rlcontroller.physics.motions.excitation import Load  # noqa: E402
from rlcontroller.physics.plant import Plant  # noqa: E402
from rlcontroller.simulation import kept  # noqa: E402

pytestmark = pytest.mark.slow


def short_motions() -> list[Load]:
    time = np.arange(0.0, 2.0, 0.01)
    return [
        Load(f"m{i}", 0.01, a * np.sin(2 * np.pi * f * time))
        for i, (a, f) in enumerate([(1.0, 1.5), (2.0, 0.8)])
    ]


def test_kept_responses_read_back_and_follow_the_model_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("RLC_CACHE", str(tmp_path / "cache"))
    folder = tmp_path / "model"
    shutil.copytree(Path("configs/opensees"), folder)
    shutil.copy(Path("studies/opensees/five_story_opensees.yaml"), tmp_path / "experiment.yaml")
    text = (tmp_path / "experiment.yaml").read_text().replace("../../configs/opensees/", "model/")
    text = text.replace("../../configs/", f"{Path('configs').resolve()}/")
    (tmp_path / "experiment.yaml").write_text(text)
    plant = Plant(api.load(tmp_path / "experiment.yaml")).bare
    motions = short_motions()
    done: list[int] = []  # the progress bar's advances: each FE run as it ends, a kept suite at once
    first = kept.uncontrolled(plant, motions, done.append)
    files = list((tmp_path / "cache").iterdir())
    assert len(files) == 1 and sum(done) == len(motions)
    again = kept.uncontrolled(plant, motions, done.append)  # read back: the same arrays
    assert sum(done) == 2 * len(motions) and done[-1] == len(motions)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a.drift, b.drift)
        np.testing.assert_array_equal(a.absolute_acceleration, b.absolute_acceleration)
    (folder / "notes.yaml").write_text("# a neighbour the model may source\n")
    kept.uncontrolled(plant, motions)
    assert len(list((tmp_path / "cache").iterdir())) == 2  # another key
    kept.uncontrolled(plant, motions[:1])
    assert len(list((tmp_path / "cache").iterdir())) == 3
    newest = max((tmp_path / "cache").iterdir(), key=lambda p: p.stat().st_mtime_ns)
    newest.write_bytes(b"not a zip")
    damaged = kept.uncontrolled(plant, motions[:1])  # computed again
    np.testing.assert_array_equal(damaged[0].drift, first[0].drift)


def test_a_plant_of_rlc_own_keeps_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("RLC_CACHE", str(tmp_path / "cache"))
    from rlcontroller.config import Experiment

    kept.uncontrolled(Plant(Experiment()), short_motions())
    assert not (tmp_path / "cache").exists()


def test_a_model_the_ground_does_not_move_is_refused_in_one_line(tmp_path, monkeypatch):
    """An FE model whose masses feel no ground motion (the published benchmark frame under the Transformation
    handler stood still: docs/opensees.md) is refused before its runs are kept, naming the model."""
    from dataclasses import replace

    from rlcontroller.errors import ModelError

    monkeypatch.setenv("RLC_CACHE", str(tmp_path / "cache"))
    plant = Plant(api.load(Path("studies/opensees/five_story_opensees.yaml"))).bare
    moving = kept.uncontrolled_responses

    # the FE runs at 1e-4 of their drift: the benchmark frame's
    def standing(plant, motions, on_motions=None):
        scale = 1.0e-4 if plant.fe_model is not None else 1.0  # (0.006 mm against 56 mm), well above 1e-12 m
        return [
            replace(response, drift=scale * response.drift) for response in moving(plant, motions, on_motions)
        ]

    monkeypatch.setattr(kept, "uncontrolled_responses", standing)
    with pytest.raises(
        ModelError, match=r"five_story_shear\.py: the model stands still under m0's ground motion"
    ):
        kept.uncontrolled(plant, short_motions())
    assert not (tmp_path / "cache").exists()


def test_a_model_that_stands_still_is_refused_before_any_run_and_by_rlc_info(tmp_path, monkeypatch):
    """A unit ground pulse, stepped in this process, finds the stand-still before a single motion runs (the
    benchmark frame had run a whole suite and printed 24 OpenSees failures first), and `rlc info` says it
    too."""
    from rlcontroller.api.describe import describe
    from rlcontroller.errors import ModelError
    from rlcontroller.physics.fe.integrator import OpenSeesIntegrator

    monkeypatch.setenv("RLC_CACHE", str(tmp_path / "cache"))
    experiment = api.load(Path("studies/opensees/five_story_opensees.yaml"))
    moving, true_state = OpenSeesIntegrator.step, {}

    # the FE model's floors at 1e-4 of their motion, as the frame's stood
    def standing(self, state, *arguments):
        state = moving(self, true_state[id(self)] if state.any() else state, *arguments)
        true_state[id(self)] = state
        return 1e-4 * state

    monkeypatch.setattr(OpenSeesIntegrator, "step", standing)
    runs, responses = [], kept.uncontrolled_responses
    monkeypatch.setattr(
        kept, "uncontrolled_responses", lambda plant, *a, **k: runs.append(plant) or responses(plant, *a, **k)
    )
    message = r"five_story_shear\.py: the model stands still under a unit ground pulse"
    with pytest.raises(ModelError, match=message):
        kept.uncontrolled(Plant(experiment).bare, short_motions())
    with pytest.raises(ModelError, match=message):
        describe(experiment)
    # the design model's pulse, no FE run
    assert runs and not any(plant.fe_model is not None for plant in runs)
