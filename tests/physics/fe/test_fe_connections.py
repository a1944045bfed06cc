"""The member ends read for the benchmark's criteria (`physics.fe.connections`), against beam theory: a fibre
section's curvature and moment in a pushed cantilever, and where it yields; the nine-story frame's hinges
yielding at their beams' plastic moments Z F_y."""

from pathlib import Path

import numpy as np
import pytest

from tests.conftest import OPENSEES_FAILURES, OPENSEES_MISSING

pytest.importorskip("openseespy.opensees", reason=OPENSEES_MISSING, exc_type=OPENSEES_FAILURES)

from rlcontroller.evaluation.benchmark import YIELDED  # noqa: E402
from rlcontroller.physics.fe.build import build_model  # noqa: E402
from rlcontroller.physics.fe.connections import connection_probes, read_connections  # noqa: E402
from rlcontroller.physics.fe.opensees import opensees  # noqa: E402

CONFIGS = Path(__file__).resolve().parents[3] / "configs"
E, FY = 200.0e9, 250.0e6  # Pa
WIDTH, DEPTH, LENGTH = 0.1, 0.2, 2.0  # m
CANTILEVER = f"""
def build_model(ops):
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    ops.node(1, 0.0, 0.0)
    ops.node(2, 0.0, {LENGTH})
    ops.fix(1, 1, 1, 1)
    ops.mass(2, 1000.0, 1000.0, 0.0)
    ops.uniaxialMaterial("Steel01", 1, {FY}, {E}, 0.0)
    ops.section("Fiber", 1)
    ops.patch("rect", 1, 200, 1, -{DEPTH / 2}, -{WIDTH / 2}, {DEPTH / 2}, {WIDTH / 2})
    ops.geomTransf("Linear", 1)
    ops.beamIntegration("Lobatto", 1, 1, 5)
    ops.element("forceBeamColumn", 1, 1, 2, 1, 1)
    return {{"floors": [[2]], "direction": 1, "story_heights": [{LENGTH}], "rayleigh": [0.0, 0.0]}}
"""


def _push(ops, node: int, load: float, steps: int, read, displacement: float = 0.0) -> list:
    """A lateral load at `node` raised to `load` (N) in `steps` equal steps, or (with `displacement`, m) as
    much as moves the node that far; `read()` after each."""
    ops.timeSeries("Linear", 901)
    ops.pattern("Plain", 901, 901)
    ops.load(node, load, 0.0, 0.0)
    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1e-10, 50)
    ops.algorithm("Newton")
    if displacement:
        ops.integrator("DisplacementControl", node, 1, displacement / steps)
    else:
        ops.integrator("LoadControl", 1.0 / steps)
    ops.analysis("Static")
    readings = []
    for _ in range(steps):
        assert ops.analyze(1) == 0
        readings.append(read())
    return readings


def test_a_fibre_sections_curvature_moment_and_knee_are_beam_theorys(tmp_path):
    model = tmp_path / "cantilever.py"
    model.write_text(CANTILEVER)
    build_model(model, "build_model")
    ops = opensees()
    probes = connection_probes(ops)
    assert probes == [("section", 1, "1"), ("section", 1, "5")]  # the member's two ends
    inertia, yield_moment = WIDTH * DEPTH**3 / 12.0, FY * WIDTH * DEPTH**2 / 6.0
    loads = np.arange(1, 141) / 140 * 1.4 * yield_moment / LENGTH  # to 1.4 M_y at the base (M_p = 1.5 M_y)
    readings = np.array(_push(ops, 2, loads[-1], loads.size, lambda: read_connections(ops, probes)))
    base = readings[:, 0]
    assert np.all(np.sign(base[:, 0]) == np.sign(base[:, 1]))  # curvature and moment of one sign convention
    base = np.abs(base)
    np.testing.assert_allclose(base[:, 1], loads * LENGTH, rtol=1e-6)  # the moment at the fixed end
    elastic = loads * LENGTH < 0.9 * yield_moment
    np.testing.assert_allclose(base[elastic, 0], loads[elastic] * LENGTH / (E * inertia), rtol=1e-3)
    np.testing.assert_allclose(base[0, 2], E * inertia, rtol=1e-3)
    # the knee: half the flexural stiffness gone where the elastic core is 0.5^(1/3) of the depth,
    # M = 1.5 M_y (1 - core^2 / 3) for a rectangle of elastic-perfectly-plastic fibres
    knee = int(np.argmax(base[:, 2] < YIELDED * base[0, 2]))
    core = 0.5 ** (1.0 / 3.0)
    assert base[knee, 1] == pytest.approx(1.5 * yield_moment * (1.0 - core**2 / 3.0), rel=0.02)
    # the free end carries none
    assert np.all(readings[:, 1, 1] == pytest.approx(0.0, abs=1e-6 * yield_moment))


def test_the_frames_hinges_yield_at_their_beams_plastic_moments():
    import importlib.util

    path = CONFIGS / "opensees" / "nine_story_frame.py"
    spec = importlib.util.spec_from_file_location("nine_story_frame", path)
    frame = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(frame)
    description = build_model(path, "build_model")
    ops = opensees()
    probes = connection_probes(ops)
    assert {kind for kind, *_ in probes} == {"material"}  # elastic members; hinges and their rigid links
    roof = description.control_nodes[-1]
    readings = np.array(_push(ops, roof, 1.0e6, 100, lambda: read_connections(ops, probes), displacement=0.6))
    initial = readings[0, :, 2]
    yielded = np.flatnonzero(np.any(readings[:, :, 2] < YIELDED * initial, axis=0))
    assert yielded.size >= 10
    plastic_moments = np.array([frame.section(name)[2] * frame.FY_BEAM for name in frame.SECTIONS])
    for j in yielded:
        first = int(np.argmax(readings[:, j, 2] < YIELDED * initial[j]))
        moment = abs(readings[first, j, 1])
        assert np.min(np.abs(moment / plastic_moments - 1.0)) < 0.01, moment
