"""What rlc reads of an FE model beside the model: its units convert the solver's SI tolerance, and what it
says of its floors, direction and damping is checked in one line (the domain checks are in
test_opensees_plant.py)."""

import re

import pytest

from rlcontroller.errors import ModelError
from rlcontroller.physics.fe.description import FEDescription

ONE_STORY = {"floors": [[1]], "direction": 1, "story_heights": [3.0], "modal_damping": [0.02]}


@pytest.mark.parametrize(
    ("test", "units", "expected"),
    [
        (None, {"length": "in", "force": "kip"}, ("NormDispIncr", 1e-10 / 0.0254, 30)),  # 1e-10 m in inches
        (
            ["NormUnbalance", 1.0, 10],
            {"length": "in", "force": "kip"},
            ("NormUnbalance", 1.0 / 4448.2216152605, 10),
        ),
        (["EnergyIncr", 1e-8, 20], {"length": "mm", "force": "kN"}, ("EnergyIncr", 1e-8 / (1e3 * 1e-3), 20)),
        (["NormDispIncr", 1e-6, 10], {}, ("NormDispIncr", 1e-6, 10)),  # an SI model: as given
    ],
)
def test_the_solver_tolerance_is_si_converted_into_the_model_units(test, units, expected):
    raw = ONE_STORY | {"units": units} | ({"test": test} if test else {})
    got = FEDescription.of(raw, "model.yaml").test_in_model_units
    assert got[0] == expected[0] and got[2] == expected[2] and got[1] == pytest.approx(expected[1], rel=1e-12)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"direction": True}, "direction: expected the lateral degree of freedom as a number"),
        (
            {"rayleigh": [0.1, -1.0], "modal_damping": None},
            "rayleigh: expected [a0, a1], two coefficients >= 0",
        ),
        ({"modal_damping": [1.5]}, "modal_damping: expected damping ratios in [0, 1)"),
        ({"floors": [[1, True]]}, "floors: floor 1: expected node tags (whole numbers), got [1, True]"),
        ({"floors": "1"}, "floors: expected a list with the nodes of each floor, got '1'"),
        ({"story_heights": [-3.0]}, "story_heights: expected one positive height per floor (1), got [-3.0]"),
        (
            {"unit": {"length": "ft", "force": "kip"}},
            "unknown key 'unit': did you mean units? expected floors,",
        ),
        ({"colour": "red"}, "unknown key 'colour': expected floors, direction,"),
    ],
)
def test_a_description_that_says_nonsense_is_one_line(change, message):
    with pytest.raises(ModelError, match="^" + re.escape(f"model.yaml: {message}")):
        FEDescription.of(ONE_STORY | change, "model.yaml")
