"""The standard's rules on hand-made figures: performance levels by FEMA 356's limits with the tolerance at a
limit, the Clopper-Pearson bound against its closed form and at the 320-motion threshold (k = 9 passes,
k = 10 fails), the strict rule, dominance, and permanent drift on a yielding plant."""

import pytest
from conftest import REPOSITORY

from rlcontroller.config import load_safety_check
from rlcontroller.evaluation.figures import MotionFigures
from rlcontroller.evaluation.standard import DRIFT_LIMITS, level, risk_upper_bound, suite_figures

STANDARD = load_safety_check(REPOSITORY / "configs" / "checks" / "standard.yaml")
STEEL = "steel_moment_frame"


def row(ratio: float = 0.5, drift: float = 0.003, reference: float = 0.003, **more) -> dict:
    return {
        "pga_g": 0.3,
        "J1": min(ratio, 0.5),
        "J2": 0.8,
        "ratio": ratio,
        "drift_ratio": drift,
        "reference_drift_ratio": reference,
    } | more


def read(rows: dict[str, dict]) -> dict[str, MotionFigures]:
    return {name: MotionFigures.read(name, item) for name, item in rows.items()}


def figures(rows: list[dict], standard=STANDARD, system: str = STEEL) -> dict:
    """The suite criterion of verdict-file rows, as the file's fields."""
    rows = read({f"m{index}": item for index, item in enumerate(rows)})
    return suite_figures(rows, "no control", system, standard).fields()


def test_the_levels_are_fema_356_s_limits_for_the_lateral_system():
    steel, concrete = DRIFT_LIMITS[STEEL]["transient"], DRIFT_LIMITS["concrete_moment_frame"]["transient"]
    assert steel == (0.007, 0.025, 0.05) and concrete == (0.01, 0.02, 0.04)
    assert [level(ratio, steel) for ratio in (0.006, 0.007, 0.0071, 0.03, 0.051)] == [
        "IO",
        "IO",
        "LS",
        "CP",
        "beyond CP",
    ]
    assert level(0.015, concrete) == "LS" and level(0.015, steel) == "LS" and level(0.022, concrete) == "CP"


def test_a_motion_that_crosses_a_limit_the_reference_does_not_fails_beyond_the_tolerance():
    """The reference at 0.69 % stays in Immediate Occupancy; the controlled building at 0.706 % is within 1 %
    of the 0.7 % limit (IO still), at 0.708 % beyond it (Life Safety): one motion at a higher level fails the
    check, though its ratio to the reference (1.026) alone would be one of the few allowed."""
    within = figures([row(1.02, 0.00706, 0.0069)] + [row()] * 319)
    beyond = figures([row(1.026, 0.00708, 0.0069)] + [row()] * 319)
    assert within["passed"] and within["higher_level"] == {}
    assert not beyond["passed"] and beyond["higher_level"] == {"m0": ["LS", "IO"]}
    assert beyond["failure_count"] == 1 and "1 at a higher performance level" in beyond["summary"]
    both_collapsed = figures([row(1.2, 0.09, 0.06)] + [row()] * 319)  # both beyond CP: the same level
    assert both_collapsed["passed"] and both_collapsed["higher_level"] == {}


def test_the_bound_is_clopper_pearson_s():
    """k = 0: the one-sided bound solves (1 - p)^n = 1 - confidence; k = n: 1."""
    for n in (11, 40, 303, 320):
        assert risk_upper_bound(0, n, 0.95) == pytest.approx(1.0 - 0.05 ** (1.0 / n), rel=1e-9)
    assert risk_upper_bound(5, 5, 0.95) == 1.0 and risk_upper_bound(0, 0, 0.95) == 1.0
    assert risk_upper_bound(9, 320, 0.95) == pytest.approx(0.04856, abs=1e-5)
    from scipy.stats import beta  # the textbook's form

    for n, k in ((11, 0), (320, 0), (5000, 0), (11, 1), (273, 3), (320, 9), (1000, 40)):
        assert risk_upper_bound(k, n, 0.95) == pytest.approx(beta.ppf(0.95, k + 1, n - k), rel=1e-12)


@pytest.mark.parametrize(("k", "passed"), [(9, True), (10, False)])
def test_nine_motions_worse_of_320_pass_and_ten_fail(k, passed):
    verdict = figures([row(1.05)] * k + [row(0.5)] * (320 - k))
    assert (verdict["failure_count"], verdict["significant_motions"], verdict["passed"]) == (k, 320, passed)
    assert (verdict["failure_probability_bound"] <= 0.05) is passed and not verdict["dominates"]
    assert sorted(verdict["failures"]) == sorted(f"m{index}" for index in range(k))


def test_the_tolerance_keeps_a_motion_out_of_k_and_only_k_0_dominates():
    """1.009 is within the 1 % tolerance (counted as worse at all, not in k): the controller dominates; the
    strict rule (risk_bound 0) fails on one motion beyond it."""
    verdict = figures([row(1.009)] + [row()] * 319)
    assert (
        verdict["passed"]
        and verdict["dominates"]
        and (verdict["failure_count"], verdict["strict_failure_count"]) == (0, 1)
    )
    strict = STANDARD.model_copy(update={"risk_bound": 0.0})
    assert not figures([row(1.011)] + [row()] * 319, strict)["passed"]
    assert figures([row(1.009)] + [row()] * 319, strict)["passed"]


def test_mean_j1_and_an_insignificant_motion_above_its_bound_still_fail():
    above_one = figures([{**row(), "J1": 1.02}] * 320)
    loud = figures([row()] * 320 + [{"pga_g": 0.002, "over_bound": 1.3}])
    assert not above_one["passed"] and above_one["failure_count"] == 0
    assert (
        not loud["passed"]
        and loud["insignificant_above_bound"] == ["m320"]
        and loud["insignificant_motions"] == 1
    )


def test_a_yielding_plant_s_level_is_the_higher_of_its_transient_and_permanent_drift_s():
    """Steel moment frame: Life Safety allows 2.5 % transient and 1 % permanent drift. A controlled building
    left leaning 1.2 % where the reference leans 0.8 %, both peaking near 2 %, is at Collapse Prevention by
    its permanent drift, the reference at Life Safety: a higher level. Where the reference's peak already took
    it to Collapse Prevention (3 %), the same lean leaves the level as it was."""
    quiet = row(residual_ratio=0.0, reference_residual_ratio=0.0)
    leaning = row(0.9, 0.02, 0.022, residual_ratio=0.012, reference_residual_ratio=0.008)
    verdict = figures([leaning] + [quiet] * 319)
    assert verdict["higher_level"] == {"m0": ["CP", "LS"]} and not verdict["passed"]
    after_a_larger_peak = figures(
        [row(0.9, 0.02, 0.03, residual_ratio=0.012, reference_residual_ratio=0.008)] + [quiet] * 319
    )
    assert after_a_larger_peak["higher_level"] == {} and after_a_larger_peak["passed"]


@pytest.mark.parametrize(
    ("figure", "value"),
    [
        ("ratio", float("nan")),
        ("drift_ratio", float("nan")),
        ("J1", -0.5),
        ("J2", float("inf")),
        ("ratio", True),
        ("reference_drift_ratio", "0.01"),
    ],
)
def test_a_figure_no_run_can_give_is_named_and_never_judged(figure, value):
    with pytest.raises(ValueError, match=rf"m1\.{figure} .* is no possible figure"):
        figures([row(), row(**({"J1": 0.5} | {figure: value}))])


def test_a_suite_that_judged_no_significant_motion_does_not_pass():
    quiet = figures([{"pga_g": 0.001, "over_bound": 0.2}] * 5)
    assert quiet["significant_motions"] == 0 and not quiet["passed"] and not quiet["dominates"]


def test_a_boolean_is_no_number_in_a_standard(tmp_path):
    from rlcontroller.config import ConfigError

    text = (REPOSITORY / "configs" / "checks" / "standard.yaml").read_text()
    path = tmp_path / "standard.yaml"
    path.write_text(text.replace("risk_bound: 0.05", "risk_bound: no"))
    with pytest.raises(ConfigError, match="risk_bound: False is a boolean, expected a number"):
        load_safety_check(path)


def test_a_suite_states_the_spread_of_its_spectral_shapes_at_the_building_s_periods():
    """16 %, median and 84 % of each motion's Sa / PGA at each period, over every motion (quiet ones too: a
    shape is the same at any scale), in the figures and the summary; a shape no motion can have is refused
    like any figure."""
    import numpy as np

    shapes = [[0.2 + 0.1 * index, 1.0 + index, 2.0] for index in range(11)]
    rows = {f"m{index}": row(sa_over_pga=shape) for index, shape in enumerate(shapes[:10])}
    rows["quiet"] = {"pga_g": 0.001, "over_bound": 0.2, "sa_over_pga": shapes[10]}
    derived = suite_figures(read(rows), "no control", STEEL, STANDARD, periods=[1.44, 0.55, 0.35]).fields()
    expected = np.percentile(np.array(shapes), [16, 50, 84], axis=0)
    assert derived["spectral_periods_s"] == [1.44, 0.55, 0.35]
    for key, values in zip(("p16", "median", "p84"), expected, strict=True):
        assert derived["spectral_shape"][key] == pytest.approx(values, abs=1e-3)
    assert "Sa/PGA (2% damped, median (16-84 %)) 0.70 (0.36-1.04) at 1.44 s" in derived["summary"]
    rows["m0"]["sa_over_pga"] = [float("nan"), 1.0, 2.0]
    with pytest.raises(ValueError, match=r"^m0\.sa_over_pga \[nan, 1\.0, 2\.0\] is no possible figure"):
        suite_figures(read(rows), "no control", STEEL, STANDARD, periods=[1.44, 0.55, 0.35])


def test_stability_is_judged_on_the_standard_s_scenarios_and_reported_on_the_rest():
    """The design model and each scenario of `stable_on` must be below 1; another scenario's radius is
    reported; a named scenario the experiment lacks is said, not judged; a radius no matrix has is refused."""
    from rlcontroller.evaluation.standard import stability_figures

    radii = {"actuator lag 20 ms": 0.99, "delay 1 step (20 ms)": 1.0018, "delay 2 steps (40 ms)": 1.03}
    judged = ["actuator lag 20 ms", "delay 1 step (20 ms)"]
    reported = stability_figures(0.99, radii, False, 0.999)
    assert reported.passed and "unstable on delay 1 step (20 ms), delay 2 steps (40 ms)" in reported.summary
    figures = stability_figures(0.99, radii, False, 0.999, stable_on=judged)
    assert not figures.passed and figures.judged_scenarios == judged
    assert (
        "judged on actuator lag 20 ms, delay 1 step (20 ms): unstable on delay 1 step (20 ms)"
        in figures.summary
    )
    stable = stability_figures(0.99, radii | {"delay 1 step (20 ms)": 0.995}, False, 0.999, stable_on=judged)
    assert stable.passed and stable.summary.endswith(
        "judged on actuator lag 20 ms, delay 1 step (20 ms): stable"
    )
    dampers = stability_figures(
        0.99999998, {"stiffness x 0.7": 0.99999998}, False, 0.99999998, stable_on=judged
    )
    assert dampers.passed and dampers.judged_scenarios == []
    assert "delay 1 step (20 ms): not among this experiment's linear scenarios" in dampers.summary
    with pytest.raises(ValueError, match="a spectral radius that no matrix has"):
        stability_figures(
            0.99, radii | {"delay 1 step (20 ms)": float("nan")}, False, 0.999, stable_on=judged
        )
