"""The compiled (numba) integrators of the non-linear plants over one control step, one module per plant:
`yielding` (Bouc-Wen stories, `hysteresis.BoucWen`, and the fishbone frame, `fishbone.Fishbone`: classical
RK4, the fishbone's massless floor rotations in equilibrium), `dampers` (`semi_active.SemiActiveDampers`: the
building's exact linear map over sub-steps, implicit Euler on the MR damper's z) and `stops`
(`end_stops.EndStops`: a mass device's stroke against its end-stops). The equations are in those modules'
docstrings. Imported on first use: numba's own import (~0.2 s) is never paid by a linear plant.
"""
