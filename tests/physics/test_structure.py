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


def test_the_seventy_six_story_benchmark_has_its_published_frequencies_and_damping(tmp_path):
    from conftest import REPOSITORY

    from rlcontroller.config import load_experiment

    experiment = tmp_path / "tower.yaml"
    building = REPOSITORY / "configs" / "buildings" / "seventy_six_story.yaml"
    experiment.write_text(f"building: {building}\nactuators: [{{story: 76}}]\n")
    tower = build(load_experiment(experiment).building, [ActuatorConfig(story=76)])
    frequencies = 1.0 / tower.periods()
    np.testing.assert_allclose(frequencies[:3], [0.160, 0.765, 1.992], atol=5e-4)  # Hz, Yang et al. 2004
    np.testing.assert_allclose(tower.modal_damping_ratios()[:5], 0.01, rtol=2e-3)
    assert tower.n_floors == 76 and np.sum(tower.mass) == pytest.approx(2.10863e8, rel=1e-5)  # kg (1' M 1)
    assert tower.story_heights.sum() == pytest.approx(306.0, rel=1e-3)


def test_a_shear_building_written_as_matrices_is_the_same_building(tmp_path):
    from rlcontroller.config import load_experiment

    shear = build(BuildingConfig(), [ActuatorConfig(story=1)])
    np.savez(tmp_path / "five.npz", M=shear.mass / 1e3, K=shear.stiffness / 1e3, C=shear.damping / 1e3)
    (tmp_path / "e.yaml").write_text(
        "building: {matrices: five.npz, units: {mass: t, force: kN, length: m}, story_heights: [3, 3, 3, 3, "
        "3]}\nactuators: [{story: 1}]\n"
    )
    matrices = build(load_experiment(tmp_path / "e.yaml").building, [ActuatorConfig(story=1)])
    for name in ("mass", "stiffness", "damping", "actuator_matrix"):
        np.testing.assert_allclose(getattr(matrices, name), getattr(shear, name), rtol=1e-12)
    np.testing.assert_allclose(matrices.periods(), shear.periods(), rtol=1e-12)


def test_modal_damping_gives_each_mode_its_ratio():
    from rlcontroller.physics.structure import modal_damping_matrix

    shear = build(BuildingConfig(), [ActuatorConfig(story=1)])
    damping = modal_damping_matrix(shear.mass, shear.stiffness, [0.02, 0.03])
    omega, shapes = shear.modes()
    np.testing.assert_allclose(
        shapes.T @ damping @ shapes, np.diag(2 * omega * [0.02, 0.03, 0.03, 0.03, 0.03]), atol=1e-12
    )
