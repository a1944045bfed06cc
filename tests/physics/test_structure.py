import numpy as np
import pytest

from rlcontroller.config import ActuatorConfig, BuildingConfig, DampingConfig, RayleighPair
from rlcontroller.physics.structure import actuator_matrix, build, shear_stiffness_matrix


def test_paper_building_periods(paper_building):
    np.testing.assert_allclose(paper_building.periods(), [1.444, 0.549, 0.351, 0.281, 0.242], atol=6e-4)


def test_rayleigh_ratios_hit_the_chosen_modes(paper_building):
    ratios = paper_building.modal_damping_ratios()
    np.testing.assert_allclose(ratios[[0, 4]], [0.01, 0.05], rtol=1e-10)
    assert np.all((ratios[1:4] > 0.01) & (ratios[1:4] < 0.05))
    assert np.allclose(paper_building.damping, paper_building.damping.T)


def test_rayleigh_with_other_modes_and_modal_orthogonality():
    config = BuildingConfig(
        damping=DampingConfig(rayleigh=(RayleighPair(mode=2, ratio=0.03), RayleighPair(mode=3, ratio=0.04)))
    )
    building = build(config, [ActuatorConfig(story=1)])
    np.testing.assert_allclose(building.modal_damping_ratios()[[1, 2]], [0.03, 0.04], rtol=1e-10)
    _, shapes = building.modes()
    np.testing.assert_allclose(shapes.T @ building.mass @ shapes, np.eye(5), atol=1e-12)
    modal_damping = shapes.T @ building.damping @ shapes
    np.testing.assert_allclose(modal_damping - np.diag(np.diag(modal_damping)), 0.0, atol=1e-9)


def test_explicit_damping_matrix_is_used():
    matrix = [[100.0, -20.0], [-20.0, 50.0]]
    config = BuildingConfig(masses=[1.0, 1.0], stiffnesses=[1.0, 1.0], damping={"matrix": matrix})
    building = build(config, [ActuatorConfig(story=2)])
    np.testing.assert_array_equal(building.damping, matrix)


def test_stiffness_matrix_of_a_two_story_building():
    np.testing.assert_array_equal(shear_stiffness_matrix(np.array([3.0, 2.0])), [[5.0, -2.0], [-2.0, 2.0]])


def test_actuator_matrix_mounts():
    actuators = [ActuatorConfig(story=1), ActuatorConfig(story=3), ActuatorConfig(story=2, mount="floor")]
    gamma = actuator_matrix(3, actuators)
    np.testing.assert_array_equal(gamma, [[1, 0, 0], [0, -1, 1], [0, 1, 0]])


def test_force_limits_and_stories(paper_building):
    np.testing.assert_array_equal(paper_building.force_limits, [1e5, 1e5, 1e5])


@pytest.mark.parametrize("heights", [[3.0] * 5, None])
def test_story_heights_are_optional(heights):
    building = build(BuildingConfig(story_heights=heights), [ActuatorConfig(story=1)])
    assert (building.story_heights is None) == (heights is None)
