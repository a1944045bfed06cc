"""A verdict's typed figures keep the verdict file's format: every shipped verdict read into them and written
back is the same file, byte for byte; a row's figures are read by name and refused when no run can give
them."""

import pytest
import yaml
from conftest import REPOSITORY

from rlcontroller.evaluation.figures import MotionFigures, RestFigures, StabilityFigures, SuiteFigures
from rlcontroller.evaluation.verdict import Verdict

VERDICTS = sorted((REPOSITORY / "models").glob("*/best_check.yaml"))


@pytest.mark.parametrize("path", VERDICTS, ids=lambda path: path.parent.name)
def test_a_shipped_verdict_read_into_figures_and_written_back_is_the_same_file(path):
    text = path.read_text(encoding="utf-8")
    verdict = Verdict.read(yaml.safe_load(text))
    assert verdict.to_yaml() == text
    kinds = {name: type(item) for name, item in verdict.criteria.items()}
    assert kinds["check suite"] is SuiteFigures and kinds["at rest"] is RestFigures
    assert kinds["closed-loop stability"] is StabilityFigures


def test_the_shipped_verdicts_cover_every_kind_of_row():
    """The round trip above is only as good as the rows it meets: wind loads, spectral shapes, permanent
    drift."""
    rows = [
        row
        for path in VERDICTS
        for item in yaml.safe_load(path.read_text())["criteria"].values()
        for row in item.get("per_motion", {}).values()
    ]
    assert any("load" in row for row in rows) and any("sa_over_pga" in row for row in rows)
    assert any("residual_ratio" in row for row in rows) and any("over_bound" in row for row in rows)


def test_a_row_is_significant_by_its_ratio_and_reads_its_figures_by_name():
    row = {
        "pga_g": 0.31,
        "J1": 0.7,
        "J2": 0.9,
        "ratio": 0.8,
        "drift_ratio": 0.004,
        "reference_drift_ratio": 0.005,
    }
    figures = MotionFigures.read("m0", row)
    assert figures.significant and not figures.yields and figures.strength() == "PGA 0.31 g"
    assert figures.row() == row and list(figures.row()) == list(row)
    quiet = MotionFigures.read("m1", {"load": "wind 30 m/s", "over_bound": 0.4})
    assert not quiet.significant and quiet.strength() == "wind 30 m/s"
    with pytest.raises(KeyError, match="reference_drift_ratio"):
        MotionFigures.read("m2", {key: value for key, value in row.items() if key != "reference_drift_ratio"})
    with pytest.raises(KeyError, match="reference_residual_ratio"):
        MotionFigures.read("m3", row | {"residual_ratio": 0.001})
    with pytest.raises(ValueError, match=r"^m4\.ratio -0\.1 is no possible figure"):
        MotionFigures.read("m4", row | {"ratio": -0.1})
