"""The ASCE nine-story benchmark building's north-south moment frame as an OpenSees model (2-D).

The benchmark: Ohtori, Christenson, Spencer and Dyke (2004), "Benchmark control problems for seismically
excited nonlinear buildings", J. Eng. Mech. 130(4), 366-385 — the SAC project's 9-story pre-Northridge
steel moment frame for Los Angeles. Numbers, with their source:

- Geometry (Ohtori et al. 2004): five bays of 9.15 m; a basement story of 3.65 m under the ground level,
  a first story of 5.49 m, eight of 3.96 m (37.19 m above ground); column bases pinned at the basement
  level; the ground level restrained horizontally (foundation walls and soil); column splices 1.83 m above
  levels 1, 3, 5 and 7.
- Steel (Ohtori et al. 2004): columns 345 MPa, beams 248 MPa; E = 200 GPa.
- Members: the SAC LA 9-story pre-Northridge design as tabulated by Gupta and Krawinkler (1999), "Seismic
  demands for performance evaluation of steel moment resisting frame structures", Blume Center report 132,
  and drawn in Ohtori et al. (2004), Fig. 3 (below: STORIES); section properties from the AISC Manual.
- Seismic masses (Ohtori et al. 2004), of the whole building: level 1 1.01e6 kg, levels 2-8 9.89e5 kg,
  level 9 (the roof) 1.07e6 kg; a north-south frame takes half. The ground level's mass is restrained.
- Published periods to reproduce: first natural frequencies 0.443, 1.18 and 2.05 Hz (Ohtori et al. 2004),
  periods 2.26, 0.847, 0.488 s (tests/test_opensees_plant.py holds the model to 5 %).

Modelling choices of ours (not the benchmark's): every beam is an elastic element between two
concentrated plastic hinges (zero-length rotational springs, bilinear with 3 % hardening at M_p = Z F_y,
the stiffness split n = 10 as Ibarra and Krawinkler 2005 do); columns are elastic with a P-Delta
transformation, the last column line turned to bend about its weak axis (the frame's corner column, which
it shares with the perpendicular frame, as the SAC models orient it), the others about their strong axis; a
leaning column carries the half building's floor weights (its P-Delta) on pinned segments tied to each
floor; each floor is rigid in its plane
(its nodes follow the first one laterally); Rayleigh damping of 2 % in the first two modes.

This file is code: rlc runs it only when you name an experiment that names it (docs/opensees.md).
"""

import math

INCH = 0.0254  # m
E = 200.0e9  # Pa
FY_COLUMN, FY_BEAM = 345.0e6, 248.0e6  # Pa
G = 9.80665  # m/s^2
BAY, BAYS = 9.15, 5  # m, count
BASEMENT, FIRST, TYPICAL = 3.65, 5.49, 3.96  # m, story heights
SPLICE = 1.83  # m above the floor where a story's columns change section
MASSES = [1.01e6 / 2] + [9.89e5 / 2] * 7 + [1.07e6 / 2]  # kg per frame, levels 1-9
DAMPING = ((1, 0.02), (2, 0.02))  # (mode, ratio)
HINGE_STIFFNESS = 10.0  # n: the spring is n times as stiff as the member (6 E I / L)
HARDENING = 0.03

# AISC: area (in^2), strong-axis inertia (in^4), plastic modulus (in^3)
SECTIONS = {
    "W14x500": (147.0, 8210.0, 1050.0),
    "W14x455": (134.0, 7190.0, 936.0),
    "W14x370": (109.0, 5440.0, 736.0),
    "W14x283": (83.3, 3840.0, 542.0),
    "W14x257": (75.6, 3400.0, 487.0),
    "W14x233": (68.5, 3010.0, 436.0),
    "W36x160": (47.0, 9760.0, 624.0),
    "W36x135": (39.7, 7800.0, 509.0),
    "W30x99": (29.1, 3990.0, 312.0),
    "W27x84": (24.8, 2850.0, 244.0),
    "W24x68": (20.1, 1830.0, 177.0),
}
WEAK_AXIS_INERTIA = {"W14x370": 1990.0, "W14x283": 1440.0, "W14x257": 1290.0, "W14x233": 1150.0}  # AISC, in^4

# Per story from the basement (Gupta and Krawinkler 1999): exterior columns, interior columns (below and
# above the splice where they change), and the beam of the floor it carries.
STORIES = [
    (("W14x370",), ("W14x500",), "W36x160"),  # basement, carries the ground level
    (("W14x370",), ("W14x500",), "W36x160"),  # story 1, carries level 1
    (("W14x370",), ("W14x500", "W14x455"), "W36x160"),
    (("W14x370",), ("W14x455",), "W36x135"),
    (("W14x370", "W14x283"), ("W14x455", "W14x370"), "W36x135"),
    (("W14x283",), ("W14x370",), "W36x135"),
    (("W14x283", "W14x257"), ("W14x370", "W14x283"), "W36x135"),
    (("W14x257",), ("W14x283",), "W30x99"),
    (("W14x257", "W14x233"), ("W14x283", "W14x257"), "W27x84"),
    (("W14x233",), ("W14x257",), "W24x68"),
]


def section(name):
    area, inertia, modulus = SECTIONS[name]
    return area * INCH**2, inertia * INCH**4, modulus * INCH**3


def build_model(ops):
    """Build the frame in the OpenSees domain, at rest under its gravity loads; return what rlc needs."""
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    heights = [BASEMENT, FIRST] + [TYPICAL] * 8
    levels = [0.0]
    for height in heights:
        levels.append(levels[-1] + height)
    lines = BAYS + 1
    lean = lines  # the leaning column's line
    ops.geomTransf("PDelta", 1)
    ops.geomTransf("Linear", 2)
    tags = {"element": 0, "material": 0, "node": 10000}

    def next_tag(kind):
        tags[kind] += 1
        return tags[kind]

    def node_at(line, level):
        return 100 * level + line + 1

    for level, y in enumerate(levels):
        for line in range(lines + 1):
            ops.node(node_at(line, level), line * BAY, y)
    for line in range(lines):
        ops.fix(node_at(line, 0), 1, 1, 0)  # pinned column bases at the basement level
        ops.fix(node_at(line, 1), 1, 0, 0)  # the ground level: no horizontal displacement
    # the leaning column: no bending (its nodes do not turn, its inertia is nil), only its P-Delta
    ops.fix(node_at(lean, 0), 1, 1, 1)
    ops.fix(node_at(lean, 1), 1, 0, 1)
    for level in range(2, len(levels)):
        ops.fix(node_at(lean, level), 0, 0, 1)

    def column(bottom, top, name, line):
        area, inertia, _ = section(name)
        if line == lines - 1:
            inertia = WEAK_AXIS_INERTIA[name] * INCH**4
        ops.element("elasticBeamColumn", next_tag("element"), bottom, top, area, E, inertia, 1)

    for story, (exterior, interior, beam) in enumerate(STORIES):
        base, top = story, story + 1
        for line in range(lines):
            names = exterior if line in (0, lines - 1) else interior
            if len(names) == 1:
                column(node_at(line, base), node_at(line, top), names[0], line)
                continue
            splice = next_tag("node")
            ops.node(splice, line * BAY, levels[base] + SPLICE)
            column(node_at(line, base), splice, names[0], line)
            column(splice, node_at(line, top), names[1], line)
        _beams(ops, top, beam, node_at, next_tag)
        ops.element("elasticBeamColumn", next_tag("element"), node_at(lean, base), node_at(lean, top), 1.0, E, 1e-12, 1)
    for level in range(2, len(levels)):  # levels 1-9 above ground: rigid in their plane
        for line in range(1, lines + 1):
            ops.equalDOF(node_at(0, level), node_at(line, level), 1)
        ops.mass(node_at(0, level), MASSES[level - 2], 0.0, 0.0)
    _gravity(ops, [node_at(lean, level) for level in range(2, len(levels))])
    circular = [math.sqrt(value) for value in ops.eigen(max(mode for mode, _ in DAMPING))]
    (i, zeta_i), (j, zeta_j) = DAMPING
    w_i, w_j = circular[i - 1], circular[j - 1]
    a1 = 2.0 * (zeta_j * w_j - zeta_i * w_i) / (w_j**2 - w_i**2)
    a0 = 2.0 * zeta_i * w_i - a1 * w_i**2
    ops.rayleigh(a0, 0.0, a1, 0.0)  # stiffness part on the initial stiffness: no damping jump at yield
    return {
        "floors": [[node_at(line, level) for line in range(lines + 1)] for level in range(2, len(levels))],
        "direction": 1,
        "story_heights": heights[1:],
        "rayleigh": [a0, a1],
        # the time steps' solver (docs/opensees.md, "Speed"): the only multi-point constraints are equalDOF, the
        # tangent is symmetric (elastic members, P-Delta, uncoupled hinges), and a test on the unbalanced force
        # (1 N in forces of MN) needs fewer iterations than one on the displacement increment
        "constraints": ["Plain"],
        "system": ["SparseSYM"],
        "test": ["NormUnbalance", 1.0, 30],
    }


def _beams(ops, level, name, node_at, next_tag):
    """The beams of `level`: elastic members between rotational hinge springs at both ends."""
    area, inertia, modulus = section(name)
    n = HINGE_STIFFNESS
    member = (n + 1.0) / n * inertia  # the member's share of the flexibility (Ibarra and Krawinkler 2005)
    spring = n * 6.0 * E * inertia / BAY
    hardening = HARDENING / (1.0 + n * (1.0 - HARDENING))
    hinge_material, rigid = next_tag("material"), next_tag("material")
    ops.uniaxialMaterial("Steel01", hinge_material, modulus * FY_BEAM, spring, hardening)
    ops.uniaxialMaterial("Elastic", rigid, 1.0e3 * E * area / BAY)  # the hinge does not slide
    for bay in range(BAYS):
        ends = []
        for line in (bay, bay + 1):
            hinge = next_tag("node")
            ops.node(hinge, *ops.nodeCoord(node_at(line, level)))
            ops.element(
                "zeroLength",
                next_tag("element"),
                node_at(line, level),
                hinge,
                "-mat",
                rigid,
                rigid,
                hinge_material,
                "-dir",
                1,
                2,
                6,
            )
            ends.append(hinge)
        ops.element("elasticBeamColumn", next_tag("element"), ends[0], ends[1], area, E, member, 2)


def _gravity(ops, lean_nodes):
    """The floors' weights on the leaning column, applied in ten load steps and then held (time reset)."""
    ops.timeSeries("Linear", 1)
    ops.pattern("Plain", 1, 1)
    for node, mass in zip(lean_nodes, MASSES, strict=True):
        ops.load(node, 0.0, -mass * G, 0.0)
    ops.constraints("Transformation")
    ops.numberer("RCM")
    ops.system("UmfPack")
    ops.test("NormDispIncr", 1.0e-10, 20)
    ops.algorithm("Newton")
    ops.integrator("LoadControl", 0.1)
    ops.analysis("Static")
    if ops.analyze(10) != 0:
        raise RuntimeError("the gravity analysis did not converge")
    ops.loadConst("-time", 0.0)
    ops.wipeAnalysis()
