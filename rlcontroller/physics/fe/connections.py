"""The member ends of an FE model where it may yield ("connections"), read each control step for the
benchmark's criteria (Ohtori et al. 2004: ductility, dissipated energy, plastic connections;
`evaluation.benchmark`).

A connection is either an end section of a beam-column with sections (its first and last integration points:
the member's ends under Lobatto integration), read as (curvature, moment, flexural tangent stiffness) about
the section's z axis (a 2-D frame's only one), or one material of a zero-length element (a concentrated hinge
or spring), read as (deformation, force, tangent). Both in the model's units: the criteria use them only as
ratios to the connection's own yield values. Elements of other kinds (elastic members, trusses) cannot yield
here and are not connections. Which of these do yield is decided by the criteria from the histories (the
tangent falling below half its initial value), so rigid links and elastic springs drop out there.
"""

from __future__ import annotations

import numpy as np

VALUES = ("deformation", "force", "tangent")  # per connection, per control step


def connection_probes(ops) -> list[tuple]:
    """The eleResponse arguments that read each connection of the model in `ops`' domain: per section end
    (`section`, i, ...) two calls, per zero-length material one."""
    probes: list[tuple] = []
    for element in ops.getEleTags():
        points = ops.eleResponse(element, "integrationPoints") or []
        if len(points) > 0 and ops.eleResponse(element, "section", "1", "deformation"):
            for section in sorted({1, len(points)}):
                probes.append(("section", element, str(section)))
            continue
        if ops.eleType(element).lower().startswith("zerolength"):
            for material in range(1, len(ops.eleResponse(element, "deformation") or []) + 1):
                probes.append(("material", element, str(material)))
    return probes


def read_connections(ops, probes: list[tuple]) -> np.ndarray:
    """(connections, 3): deformation, force, tangent of each probe now (model units)."""
    values = np.empty((len(probes), 3))
    for row, (kind, element, index) in enumerate(probes):
        # deformations (axial strain, curvature about z, ...), then forces (N, M_z, ...)
        if kind == "section":
            deformation_force = ops.eleResponse(element, "section", index, "forceAndDeformation")
            tangent = ops.eleResponse(element, "section", index, "stiffness")  # k x k, row by row
            k = len(deformation_force) // 2
            values[row] = deformation_force[1], deformation_force[k + 1], tangent[k + 1]
        else:
            stress, strain, tangent = ops.eleResponse(element, "material", index, "stressStrainTangent")
            values[row] = strain, stress, tangent
    return values
