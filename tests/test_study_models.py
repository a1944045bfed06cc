"""The learned controllers of the control-quality study (docs/results/models/): committed as data so
that the study's numbers can be checked, never shipped — each fails the safety check."""

from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from rlcontroller.cli import app

STUDY = Path(__file__).resolve().parents[1] / "docs" / "results" / "models"
FOLDERS = sorted(folder for folder in STUDY.iterdir() if folder.is_dir())
RECORDS_J1 = {  # the learned controller's mean J1 on the seven records, as the study's README states
    "five_story_amd": 0.785,  # with its end-stops (round 7); 0.606 as a free mass
    "five_story_mr": 0.400,
}


def test_every_study_model_is_described_and_none_is_listed_by_rlc_models():
    readme = (STUDY / "README.md").read_text()
    listed = CliRunner().invoke(app, ["models"]).output
    assert [folder.name for folder in FOLDERS] == sorted(RECORDS_J1)
    for folder in FOLDERS:
        assert f"`{folder.name}`" in readme and f"{RECORDS_J1[folder.name]:.3f}" in readme
        # not shipped
        assert f"  {folder.name}:" not in listed and f"  {folder.name} (default):" not in listed


@pytest.mark.slow
@pytest.mark.parametrize("folder", FOLDERS, ids=lambda folder: folder.name)
def test_a_study_model_fails_the_check_and_reproduces_its_stated_j1(folder, records, tmp_path):
    verdict = yaml.safe_load((folder / "best_check.yaml").read_text())
    assert verdict["passed"] is False and not (folder / "best_model.zip").exists()  # data only, no pickle
    out = tmp_path / "evaluation"
    result = CliRunner().invoke(app, ["evaluate", str(folder), "--records", str(records), "--out", str(out)])
    assert result.exit_code == 0, result.output
    summary = (out / "summary.csv").read_text().splitlines()
    row = next(line for line in summary if line.startswith("RL,"))
    assert float(row.split(",")[1]) == pytest.approx(RECORDS_J1[folder.name], abs=5e-4)
