import csv

import numpy as np
import pytest

from rlcontroller.config import KanaiTajimiConfig, NearFaultConfig, NoiseImpulsesConfig
from rlcontroller.physics.motions.excitation import (
    STANDARD_GRAVITY,
    Load,
    MotionError,
    on_control_grid,
    read_at2,
    read_csv,
    resample,
    scale_to_pga,
)
from rlcontroller.physics.motions.generators import GroundModel, generate_suite, kanai_tajimi, noise_impulses

WEST2 = (
    "PEER NGA STRONG MOTION DATABASE RECORD\nTest, 1/1/2000, Station, 0\n"
    "ACCELERATION TIME SERIES IN UNITS OF G\n"
)


def write(path, text, newline="\n"):
    path.write_bytes(text.replace("\n", newline).encode())
    return path


def test_the_seven_records_match_the_manifest(records):
    with open(records / "manifest.csv") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 7
    for row in rows:
        motion = read_at2(records / row["file"])
        assert motion.acceleration.size == int(row["npts"]), row["file"]
        assert motion.dt == pytest.approx(float(row["dt_s"]), rel=1e-9)
        assert motion.pga / STANDARD_GRAVITY == pytest.approx(float(row["pga_g"]), rel=1e-3), row["file"]


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
@pytest.mark.parametrize(
    "header",
    ["NPTS=      4, DT=   .0100 SEC,", "NPTS =      4 , DT =   .010 SEC ,", "    4    0.0100    NPTS, DT"],
)
def test_at2_header_variants_and_line_endings(tmp_path, header, newline):
    path = write(tmp_path / "r.AT2", WEST2 + header + "\n  .1E+00  -.2E+00\n   .3E+00\n  -.5E-01\n", newline)
    motion = read_at2(path)
    assert motion.dt == 0.01
    np.testing.assert_allclose(motion.acceleration, np.array([0.1, -0.2, 0.3, -0.05]) * STANDARD_GRAVITY)


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        (
            "NPTS=      5, DT=   .0100 SEC\n .1 .2 .3\n .4\n",
            "NPTS=5 but the file holds 4 values (truncated?)",
        ),
        (
            "NPTS=      3, DT=   .0100 SEC\n .1 .2 .3\n .4\n",
            "NPTS=3 but the file holds 4 values (extra values?)",
        ),
        ("NPTS=      4, DT=   .0100 SEC\n .1 .2\n .3 abc\n", "r.AT2:6: expected a number, got 'abc'"),
        ("GARBAGE\n .1 .2\n", "r.AT2:4: expected 'NPTS=..., DT=...'"),
        ("NPTS=      0, DT=   .0100 SEC\n", "r.AT2:4: NPTS = 0, expected at least 2 samples"),
        ("NPTS=      1, DT=   .0100 SEC\n .1\n", "r.AT2:4: NPTS = 1, expected at least 2 samples"),
        ("NPTS=      2, DT=   1e999 SEC\n .1 .2\n", "r.AT2:4: DT = 1e999 s, expected 0.0001 to 1 s"),
        ("NPTS=      2, DT=   1.2.3 SEC\n .1 .2\n", "r.AT2:4: DT must be a number, got '1.2.3'"),
        ("NPTS=      2, DT=   1e-300 SEC\n .1 .2\n", "r.AT2:4: DT = 1e-300 s, expected 0.0001 to 1 s"),
        ("NPTS=      2, DT=   1000 SEC\n .1 .2\n", "r.AT2:4: DT = 1000 s, expected 0.0001 to 1 s"),
        (
            "NPTS= 400000, DT=   .0100 SEC\n .1 .2\n",
            "r.AT2:4: NPTS = 400000, expected at least 2 samples and at most",
        ),
        ("NPTS=      3, DT=   .0100 SEC\n 0 0 0\n", "every sample is zero"),
        ("NPTS=      3, DT=   .0100 SEC\n 0 1e6 0\n", "PGA 1e+06 g, expected at most 10.2 g (wrong unit?)"),
        ("NPTS=      3, DT=   .0100 SEC\n 0 nan 0\n", "non-finite values"),
    ],
)
def test_broken_at2_files_give_clear_errors(tmp_path, body, expected):
    path = write(tmp_path / "r.AT2", WEST2 + body)
    with pytest.raises(MotionError, match=None) as error:
        read_at2(path)
    assert expected in str(error.value) and str(path) in str(error.value)
    assert "\n" not in str(error.value)


def test_at2_in_other_units_is_refused(tmp_path):
    path = write(
        tmp_path / "r.AT2", WEST2.replace("UNITS OF G", "UNITS OF CM/S/S") + "NPTS= 1, DT= .01 SEC\n .1\n"
    )
    with pytest.raises(MotionError, match=r"r.AT2:3: expected"):
        read_at2(path)


def test_binary_bytes_are_not_a_record(tmp_path):
    path = tmp_path / "r.AT2"
    path.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(MotionError, match=r"r.AT2:3: expected 'ACCELERATION"):
        read_at2(path)


def test_a_motion_shorter_than_one_control_step_is_refused():
    motion = Load("short", 0.005, np.array([0.0, 1.0, 0.0]))
    with pytest.raises(MotionError, match="short: lasts 0.01 s, shorter than one control step"):
        on_control_grid(motion, 0.02)


def test_truncated_header(tmp_path):
    with pytest.raises(MotionError, match="4-line PEER header"):
        read_at2(write(tmp_path / "r.AT2", "PEER\n"))


@pytest.mark.parametrize(
    ("header", "factor"),
    [
        ("acceleration [g]", STANDARD_GRAVITY),
        ("acc_m/s2", 1.0),
        ("a (cm/s2)", 0.01),
        ("acc_cm_s2", 0.01),
        ("accel_m_s2", 1.0),
        ("a [cm/s/s]", 0.01),
        ("a (m/s²)", 1.0),
        ("a_gal", 0.01),
    ],
)
def test_csv_units(tmp_path, header, factor):
    path = write(tmp_path / "m.csv", f"time,{header}\n0.0,0.0\n0.01,1.0\n0.02,-2.0\n")
    motion = read_csv(path)
    assert motion.dt == pytest.approx(0.01)
    np.testing.assert_allclose(motion.acceleration, np.array([0.0, 1.0, -2.0]) * factor)


def test_csv_errors(tmp_path):
    with pytest.raises(MotionError, match="cannot tell the acceleration unit"):
        read_csv(write(tmp_path / "m.csv", "time,acceleration\n0,0\n0.01,1\n"))
    with pytest.raises(MotionError, match=r"m.csv:3: expected two numbers"):
        read_csv(write(tmp_path / "m.csv", "time,acc [g]\n0,0\n0.01,x\n"))
    with pytest.raises(MotionError, match=r"m.csv:4: time must increase"):
        read_csv(write(tmp_path / "m.csv", "time,acc [g]\n0,0\n0.01,1\n0.01,2\n"))


def test_uneven_csv_is_interpolated(tmp_path):
    motion = read_csv(write(tmp_path / "m.csv", "t,acc [m/s2]\n0,0\n0.01,1\n0.02,2\n0.04,4\n"))
    assert motion.dt == pytest.approx(0.01)
    np.testing.assert_allclose(motion.acceleration, [0, 1, 2, 3, 4])


def test_resample_preserves_a_piecewise_linear_motion():
    motion = Load("m", 0.02, np.array([0.0, 1.0, -1.0, 0.5]))
    fine = resample(motion, 0.005)
    assert fine.acceleration.size == 13
    np.testing.assert_allclose(fine.acceleration[::4], motion.acceleration)
    np.testing.assert_allclose(fine.acceleration[1:4], [0.25, 0.5, 0.75])


def test_control_step_keeps_every_sample_and_subdivides_odd_steps():
    grid = on_control_grid(Load("m", 0.005, np.arange(9.0)), 0.02)
    samples, substeps = grid.ground, grid.substeps
    assert substeps == 4 and samples.size == 9
    grid = on_control_grid(Load("m", 0.015, np.arange(5.0)), 0.02)
    samples, substeps = grid.ground, grid.substeps
    assert substeps == 2 and np.isclose(samples[1], 0.01 / 0.015)
    substeps = on_control_grid(Load("m", 0.02, np.arange(5.0)), 0.02).substeps
    assert substeps == 1


def test_scale_to_pga():
    motion = scale_to_pga(Load("m", 0.01, np.array([0.0, -2.0, 1.0])), 3.0)
    np.testing.assert_allclose(motion.acceleration, [0.0, -3.0, 1.5])


def test_noise_impulses_are_seeded_and_respect_the_ranges():
    config = NoiseImpulsesConfig(duration=(20.0, 20.0), noise_std=(1.0, 1.0), impulses=(0, 0))
    first = noise_impulses(config, np.random.default_rng(5))
    second = noise_impulses(config, np.random.default_rng(5))
    np.testing.assert_array_equal(first.acceleration, second.acceleration)
    assert first.duration == pytest.approx(20.0) and first.synthetic
    assert np.std(first.acceleration) == pytest.approx(1.0, rel=0.05)
    pulse = NoiseImpulsesConfig(
        duration=(10.0, 10.0), noise_std=(0.0, 0.0), impulses=(1, 1), impulse_amplitude=(3.0, 3.0)
    )
    assert noise_impulses(pulse, np.random.default_rng(1)).pga == pytest.approx(3.0, rel=0.01)


def test_kanai_tajimi_spectrum_peaks_near_the_ground_frequency():
    config = KanaiTajimiConfig(
        duration=(200.0, 200.0),
        ground_frequency=(15.0, 15.0),
        ground_damping=(0.3, 0.3),
        pga=(2.0, 2.0),
        rise_time=(0.5, 0.5),
        strong_duration=(200.0, 200.0),
        dt=0.01,
    )
    motion = kanai_tajimi(config, np.random.default_rng(2))
    assert motion.pga == pytest.approx(2.0)
    assert motion.acceleration[0] == 0.0  # the envelope starts from rest
    spectrum = np.abs(np.fft.rfft(motion.acceleration)) ** 2
    omega = 2 * np.pi * np.fft.rfftfreq(motion.acceleration.size, motion.dt)
    smoothed = np.convolve(spectrum, np.ones(400) / 400, mode="same")
    assert 11.0 < omega[np.argmax(smoothed)] < 17.0


def test_generated_suites_are_reproducible():
    first = generate_suite(KanaiTajimiConfig(), 3, seed=7)
    second = generate_suite(KanaiTajimiConfig(), 3, seed=7)
    assert [m.name for m in first] == [m.name for m in second]
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a.acceleration, b.acceleration)
    assert not np.array_equal(first[0].acceleration[:100], first[1].acceleration[:100])


def test_a_mixture_draws_from_its_components_by_weight():
    from rlcontroller.config import MixtureConfig
    from rlcontroller.physics.motions.generators import generate

    mixture = MixtureConfig(
        components=[
            {"weight": 3.0, "generator": {"kind": "kanai_tajimi", "duration": [30.0, 30.0]}},
            {"weight": 1.0, "generator": {"kind": "noise_impulses", "duration": [10.0, 10.0]}},
        ]
    )
    rng = np.random.default_rng(0)
    durations = [generate(mixture, rng).duration for _ in range(400)]
    share = np.mean(np.isclose(durations, 30.0))
    assert 0.68 < share < 0.82


def test_a_log_uniform_pga_spans_weak_to_strong_motions():
    from rlcontroller.config import KanaiTajimiConfig

    config = KanaiTajimiConfig(pga=(0.05, 10.0), pga_log=True)
    pgas = np.array([motion.pga for motion in generate_suite(config, 200, seed=3)])
    assert pgas.min() >= 0.05 and pgas.max() <= 10.0 + 1e-9
    below_half = np.mean(pgas < np.sqrt(0.05 * 10.0))  # the geometric middle splits a log-uniform draw in two
    assert 0.4 < below_half < 0.6
    with pytest.raises(ValueError, match="pga_log needs pga low > 0"):
        KanaiTajimiConfig(pga=(0.0, 1.0), pga_log=True)


def test_ground_model_spectrum_is_its_filters_power_gain():
    """The spectrum against the filter as the estimator uses it (states [x_f, x_f'], a_g = output @ state)."""
    model = GroundModel(frequency=12.0, damping=0.6)
    w, z = model.frequency, model.damping
    a = np.array([[0.0, 1.0], [-(w**2), -2.0 * z * w]])
    b = np.array([0.0, -1.0])  # x_f'' + 2 z w x_f' + w^2 x_f = -w
    frequencies = np.array([0.0, 0.5, 1.0, 1.9, 5.0, 20.0])
    gain = [model.output @ np.linalg.solve(2j * np.pi * f * np.eye(2) - a, b) for f in frequencies]
    np.testing.assert_allclose(model.spectrum(frequencies), np.abs(gain) ** 2, rtol=1e-12)
    assert model.spectrum(np.array([0.0]))[0] == pytest.approx(1.0)


def test_generated_samples_are_the_same_when_the_arithmetic_differs_in_its_last_bits():
    """Two CPUs' BLAS kernels give a generator's float64 samples that differ by about 1e-13 of the peak; after
    `same_on_every_cpu` they are the same bits (so the same noise seed), within 2^-16 of the power of two
    above the peak of the unrounded samples."""
    from rlcontroller.physics.motions.excitation import SAME_BITS, content_seed, same_on_every_cpu

    samples = np.random.default_rng(3).normal(size=20_000) * 3.7
    other = samples * (1.0 + 1e-13 * np.random.default_rng(4).uniform(-1.0, 1.0, samples.size))
    assert np.any(samples != other)
    rounded, rounded_other = same_on_every_cpu(samples), same_on_every_cpu(other)
    np.testing.assert_array_equal(rounded, rounded_other)
    above = 2.0 ** np.ceil(np.log2(np.max(np.abs(samples))))
    assert np.max(np.abs(rounded - samples)) <= 0.5 * above * 2.0**-SAME_BITS
    seeds = {content_seed(Load("a", 0.02, values)) for values in (rounded, rounded_other)}
    assert len(seeds) == 1
    np.testing.assert_array_equal(same_on_every_cpu(np.zeros(5)), np.zeros(5))


def test_every_generator_gives_samples_the_same_on_every_cpu():
    """A generated motion is already its own rounding (a fixed point of `same_on_every_cpu`)."""
    from rlcontroller.config import Experiment
    from rlcontroller.physics.motions.excitation import same_on_every_cpu
    from rlcontroller.physics.motions.loads import generate

    for generator in (Experiment().excitation.generator, KanaiTajimiConfig(), NearFaultConfig()):
        motion = generate(generator, np.random.default_rng(0), None)
        np.testing.assert_array_equal(same_on_every_cpu(motion.acceleration), motion.acceleration)
