"""A proven region of stability for a controller on a linear plant, by quadratic constraints on its units.

The closed loop is s_{k+1} = A s_k + B a(s_k) (`simulation.linearised.OpenLoop`), a(s) the controller's
feedback graph (`control.feedback_graph`). Around its equilibrium s*, on the ellipsoid
E_c = {ds: ds' P ds <= c}, bounds on every unit's pre-activation give a local sector [alpha, beta] for its
output's deviation (Yin, Seiler & Arcak, IEEE TAC 2022): (dw - alpha dv)(beta dv - dw) >= 0. If multipliers
lambda >= 0 make

    M(lambda) = Ns' P Ns - (1 - delta) Es' P Es + sum_j lambda_j sym(p_j q_j')  <=  0        (an LMI)

(Ns zeta = ds_{k+1}, Es zeta = ds, p_j = e_j - alpha_j F_j, q_j = beta_j F_j - e_j), then V = ds' P ds falls
by at least the share delta every step from every start in E_c (the S-procedure), so E_c is invariant and
every start in it returns to s*. P is fixed (a Lyapunov equation of the loop linearised at s*); the LMI in
lambda is solved by minimising its largest eigenvalue (L-BFGS-B on a smoothed maximum) and the answer is
re-checked with `eigvalsh`; the largest such c is found by bisection. The engineer's figure X: the largest
story drift such that every start with drifts up to X and drift velocities up to omega_1 X (the first
mode's) lies in E_c. docs/certificate.md has the method, its sources and its limits."""

from __future__ import annotations

from contextlib import suppress
from dataclasses import dataclass
from itertools import product

import numpy as np
from scipy.linalg import solve_discrete_lyapunov
from scipy.optimize import minimize

from rlcontroller.control.feedback_graph import UNITS, FeedbackGraph
from rlcontroller.simulation.linearised import OpenLoop

DECREASE = 1e-4  # delta: the least share of V lost per step inside the region


@dataclass(frozen=True)
class Region:
    """The certified region on one plant: E_c around the equilibrium, X in the engineer's units, and the
    response bound within it (`response_bound`)."""

    level: float  # c (0: none found)
    drift_m: float  # X: every start with story drifts up to X ...
    velocity_m_s: float  # ... and drift velocities up to omega_1 X returns to rest
    largest_eigenvalue: float  # of M(lambda) at c, scaled (< 0: proven); nan when no c was tried
    spectral_radius: float  # of the loop linearised at the equilibrium
    equilibrium_drift_m: float  # the largest story drift at the equilibrium (a bias holds it off zero)
    reason: str  # why no region was found ("" when one was)
    lyapunov: np.ndarray  # P
    equilibrium: np.ndarray  # s*
    gain_s2: float = float(
        "nan"
    )  # ||story drifts||_2 <= gain ||ground acceleration||_2 (m per m/s^2 = s^2) ...
    energy_m2_s3: float = 0.0  # ... for every ground acceleration with sum(g^2) dt up to this from rest


def equilibrium(loop: OpenLoop, graph: FeedbackGraph) -> np.ndarray:
    """s* = A s* + B a(s*) by Newton's method from rest (zero for an odd controller)."""
    state, eye = np.zeros(loop.state.shape[0]), np.eye(loop.state.shape[0])
    for _ in range(50):
        residual = loop.state @ state + loop.action @ graph.forward(state)[2] - state
        if np.max(np.abs(residual)) < 1e-13:
            break
        state = state - np.linalg.solve(loop.state + loop.action @ graph.jacobian(state) - eye, residual)
    return state


def _sector(kind: str, center: np.ndarray, lower: np.ndarray, upper: np.ndarray):
    """(alpha, beta) of units of `kind` at `center` over [lower, upper]: alpha the least chord slope from the
    center (at an end of the interval, or the slope at the center: phi' rises then falls), beta the largest
    slope on the interval."""
    phi, slope, most = UNITS[kind]
    at = phi(center)

    def chord(v: np.ndarray) -> np.ndarray:
        width = v - center
        apart = np.abs(width) > 1e-12
        return np.where(apart, (phi(v) - at) / np.where(apart, width, 1.0), slope(center))

    alpha = np.minimum.reduce([slope(center), chord(lower), chord(upper)])
    return alpha, np.maximum(most(lower, upper), alpha)


def sectors(graph: FeedbackGraph, rest: np.ndarray, inverse: np.ndarray, level: float):
    """(alpha, beta, the largest |dv|) of every unit over E_c (`inverse` = P^-1). Each pre-activation's range
    is the tighter of two bounds: intervals (the state's direct part exact on the ellipsoid, earlier units'
    by their ranges), and the linear part dv = L ds exact on the ellipsoid plus earlier units' departures
    from their mid slopes, |r_j| <= (beta_j - alpha_j) / 2 |dv_j| (small while sectors are narrow)."""
    zeta, pre, _ = graph.forward(rest)
    n, total = graph.n_state, graph.size - graph.n_state
    low_w, up_w = np.zeros(total), np.zeros(total)
    linear, departures, spread = np.zeros((total, n)), np.zeros((total, total)), np.zeros(total)
    alphas, betas, reaches, start = [], [], [], 0

    def on_ellipsoid(rows: np.ndarray) -> np.ndarray:
        return np.sqrt(level * np.einsum("ij,jk,ik->i", rows, inverse, rows))

    for stage in graph.stages:
        units = stage.bias.size
        direct, earlier = stage.weight[:, :n], stage.weight[:, n:]
        middle, half = (low_w + up_w) / 2.0, (up_w - low_w) / 2.0
        center = pre[start : start + units]
        interval = on_ellipsoid(direct) + np.abs(earlier) @ half
        lower = center + earlier @ middle - interval
        upper = center + earlier @ middle + interval
        through = earlier @ departures
        deviation = on_ellipsoid(direct + earlier @ linear) + np.abs(through) @ spread
        lower, upper = np.maximum(lower, center - deviation), np.minimum(upper, center + deviation)
        alpha, beta = _sector(stage.kind, center, lower, upper)
        reach = np.maximum(upper - center, center - lower)
        mid = (alpha + beta) / 2.0
        rows = slice(start, start + units)
        linear[rows] = mid[:, None] * (direct + earlier @ linear)
        departures[rows] = mid[:, None] * through
        departures[rows, rows] += np.eye(units)
        spread[rows] = (beta - alpha) / 2.0 * reach
        phi = UNITS[stage.kind][0]
        low_w[rows], up_w[rows] = phi(lower) - phi(center), phi(upper) - phi(center)
        alphas.append(alpha)
        betas.append(beta)
        reaches.append(reach)
        start += units
    return np.concatenate(alphas), np.concatenate(betas), np.concatenate(reaches)


def _following(loop: OpenLoop, graph: FeedbackGraph) -> np.ndarray:
    """Ns: the next state as a map of zeta, ds+ = A ds + B da with da = G dzeta."""
    n = graph.n_state
    return np.hstack([loop.state, np.zeros((n, graph.size - n))]) + loop.action @ graph.output


class _Feasible(Exception):
    pass


def decrease_lmi(
    loop: OpenLoop, graph: FeedbackGraph, lyapunov: np.ndarray, level: float, alpha, beta, reach
):
    """M0 and the vectors p_j, q_j of the LMI, divided by c, in coordinates zeta = T eta with eta = [xi; r]:
    xi = (P / c)^1/2 ds (its unit ball is the region) and r_j = dw_j - m_j dv_j the unit's departure from its
    sector's mid slope m_j, scaled by its largest size (`reach` = the largest |dv_j|). The LMI is the same in
    any coordinates; in these a narrow sector needs no large multiplier, so the search is well conditioned."""
    n, size = graph.n_state, graph.size
    following = _following(loop, graph)
    rows = np.vstack([stage.weight for stage in graph.stages])  # F_j on zeta
    middle = (alpha + beta) / 2.0
    spread = np.maximum((beta - alpha) / 2.0 * reach, 1e-12)
    values, vectors = np.linalg.eigh(lyapunov)
    scale = np.zeros((size, size))
    scale[:n, :n] = vectors * np.sqrt(level / values)
    for unit in range(size - n):  # w_j = m_j F_j zeta + r_j, in order (F_j reads earlier units only)
        scale[n + unit] = middle[unit] * (rows[unit] @ scale)
        scale[n + unit, n + unit] += spread[unit]
    m0 = scale.T @ (following.T @ lyapunov @ following) @ scale / level
    m0[:n, :n] -= (1.0 - DECREASE) * np.eye(n)
    rows = rows @ scale
    own = scale[n:]
    p = own - alpha[:, None] * rows
    q = beta[:, None] * rows - own
    return m0, p / np.sqrt(level), q / np.sqrt(level), scale


def _matrix(m0, p, q, multipliers):
    half = (p.T * multipliers) @ q
    return m0 + 0.5 * (half + half.T)


def find_multipliers(m0, p, q, start=None, iterations: int = 400):
    """lambda >= 0 minimising the largest eigenvalue of M(lambda), stopping once it is negative; returns
    (lambda, that eigenvalue by eigvalsh)."""
    norms = np.linalg.norm(p, axis=1) * np.linalg.norm(q, axis=1) + 1e-300
    best = {"x": None, "value": np.inf}

    def smoothed(x):
        multipliers = x / norms
        values, vectors = np.linalg.eigh(_matrix(m0, p, q, multipliers))
        if values[-1] < best["value"]:
            best["x"], best["value"] = x.copy(), values[-1]
        if values[-1] < -1e-9:
            raise _Feasible
        width = max(1e-3 * (values[-1] - values[0]), 1e-6)
        weights = np.exp((values - values[-1]) / width)
        total = weights.sum()
        pv, qv = p @ vectors, q @ vectors
        gradient = (pv * qv) @ weights / total / norms
        return values[-1] + width * np.log(total), gradient

    x0 = np.ones(p.shape[0]) if start is None else start * norms
    with suppress(_Feasible):
        minimize(
            smoothed,
            x0,
            jac=True,
            method="L-BFGS-B",
            bounds=[(0.0, None)] * p.shape[0],
            options={"maxiter": iterations, "maxfun": 2 * iterations},
        )
    multipliers = best["x"] / norms
    return multipliers, float(np.linalg.eigvalsh(_matrix(m0, p, q, multipliers))[-1])


def lyapunov_matrix(loop: OpenLoop, graph: FeedbackGraph, linearised: np.ndarray) -> np.ndarray:
    """P with (A_cl / r)' P (A_cl / r) - P = -Q, r = rho + 3 (1 - rho) / 4 (rho = rho(A_cl) < 1): V falls by
    at least the share 1 - r^2 every step of the linearised loop, in every direction (the margin the units'
    sectors spend). Q = D + F1' F1 (scaled to the same trace): D the inverse of each state's stationary
    variance under white ground acceleration in the linearised loop (every state weighs by its typical
    size), F1 what the first stage of units reads (the region is kept thin where units would leave their
    sectors). Measured on the default controller (docs/certificate.md): X 0.169 mm; 0.133 mm with
    r = (1 + rho) / 2 (0.131 mm with F1' F1 scaled by 0.1), 0.071 mm with r = rho + (1 - rho) / 100."""
    variance = np.diag(solve_discrete_lyapunov(linearised, np.outer(loop.ground, loop.ground)))
    floor = 1e-9 * max(float(variance.max()), 1e-30)
    weight = 1.0 / np.maximum(variance, floor)
    weight = weight / weight.max()
    reads = graph.stages[0].weight[:, : graph.n_state]
    emphasis = reads.T @ reads
    emphasis *= weight.sum() / max(float(np.trace(emphasis)), 1e-300)
    slowest = float(np.max(np.abs(np.linalg.eigvals(linearised))))
    scaled = linearised / (slowest + 0.75 * (1.0 - slowest))
    lyapunov = solve_discrete_lyapunov(scaled.T, np.diag(weight) + emphasis)
    return (lyapunov + lyapunov.T) / 2.0


def start_box(loop: OpenLoop, drift: np.ndarray, omega: float) -> np.ndarray:
    """The vertices (2^(2 floors), n) of the starts with story drifts +/-1 m and drift velocities
    +/- omega m/s (the plant's dofs from the drifts by least squares; the rest of the state at rest)."""
    floors, dofs = drift.shape
    to_dofs = np.linalg.pinv(drift)
    corners = np.array(list(product((-1.0, 1.0), repeat=2 * floors)))
    starts = np.zeros((corners.shape[0], loop.state.shape[0]))
    starts[:, :dofs] = corners[:, :floors] @ to_dofs.T
    starts[:, dofs : 2 * dofs] = omega * corners[:, floors:] @ to_dofs.T
    return starts


def region(loop: OpenLoop, graph: FeedbackGraph, *, drift: np.ndarray, omega: float) -> Region:
    """The largest certified E_c (bisection on c over six decades) and its X; `drift` (floors, dofs) maps the
    plant's displacements to story drifts, `omega` (rad/s) the first mode's circular frequency."""
    rest = equilibrium(loop, graph)
    linearised = loop.state + loop.action @ graph.jacobian(rest)
    radius = float(np.max(np.abs(np.linalg.eigvals(linearised))))
    offset = float(np.max(np.abs(drift @ rest[: drift.shape[1]])))
    none = dict(level=0.0, drift_m=0.0, velocity_m_s=0.0, spectral_radius=radius, equilibrium_drift_m=offset)
    if radius >= 1.0:
        reason = f"the loop linearised at its equilibrium is unstable (spectral radius {radius:.4f})"
        return Region(
            **none,
            largest_eigenvalue=float("nan"),
            reason=reason,
            lyapunov=np.eye(rest.size),
            equilibrium=rest,
        )
    lyapunov = lyapunov_matrix(loop, graph, linearised)
    inverse = np.linalg.inv(lyapunov)
    box = start_box(loop, drift, omega)
    per_metre = float(np.max(np.einsum("ij,jk,ik->i", box, lyapunov, box)))  # V at X = 1 m
    multipliers, proven, eigenvalue, proof = None, 0.0, float("nan"), []

    def proves(level: float) -> bool:
        nonlocal multipliers, proven, eigenvalue
        alpha, beta, reach = sectors(graph, rest, inverse, level)
        m0, p, q, scale = decrease_lmi(loop, graph, lyapunov, level, alpha, beta, reach)
        found, value = find_multipliers(m0, p, q, multipliers)
        if value < 0.0:
            multipliers, proven, eigenvalue = found, level, value
            proof[:] = [_matrix(m0, p, q, found), scale]
        elif proven == 0.0:
            eigenvalue = value
        return value < 0.0

    # from a micrometre of drift up by decades while proven, then bisection (in log) to 5 %
    low, high = 0.0, 1e-12 * per_metre
    while high <= per_metre and proves(high):
        low, high = high, high * 100.0
    while low > 0.0 and high / low > 1.05:
        middle = np.sqrt(low * high)
        low, high = (middle, high) if proves(middle) else (low, middle)
    proven_level = proven
    if proven_level == 0.0:
        return Region(
            **none,
            largest_eigenvalue=eigenvalue,
            reason="the LMI is infeasible already for starts of a micrometre of drift",
            lyapunov=lyapunov,
            equilibrium=rest,
        )
    x = float(np.sqrt(proven_level / per_metre))
    gain, energy = response_bound(loop, graph, lyapunov, proven_level, *proof, drift=drift)
    return Region(
        level=proven_level,
        drift_m=x,
        velocity_m_s=omega * x,
        largest_eigenvalue=eigenvalue,
        spectral_radius=radius,
        equilibrium_drift_m=offset,
        reason="",
        lyapunov=lyapunov,
        equilibrium=rest,
        gain_s2=gain,
        energy_m2_s3=energy * loop.dt,
    )


def response_bound(loop: OpenLoop, graph: FeedbackGraph, lyapunov, level, matrix, scale, *, drift):
    """(gamma, E): from rest, every ground acceleration g with sum(g_k^2) <= E keeps the state in E_c, and
    then sum |story drifts|^2 <= gamma^2 sum g_k^2: the dissipation inequality
    sigma (V+ - V) + |z|^2 - gamma^2 g^2 <= 0 on the proven LMI's multipliers (sigma scales them), by a Schur
    complement, the best sigma on a log grid. (nan, 0) where no sigma gives one."""
    n = graph.n_state
    following = _following(loop, graph)
    cross = scale.T @ following.T @ lyapunov @ loop.ground / level
    own = float(loop.ground @ lyapunov @ loop.ground) / level
    drifts = np.zeros((drift.shape[0], n))
    drifts[:, : drift.shape[1]] = drift
    output = drifts @ scale[:n]
    weight = output.T @ output / level
    best = (np.inf, 0.0)
    for sigma in np.logspace(-3, 9, 49):
        values, vectors = np.linalg.eigh(sigma * matrix + weight)
        if values[-1] >= 0.0:
            continue
        projected = vectors.T @ cross
        ratio = sigma * own + sigma**2 * float(np.sum(projected**2 / -values))  # gamma^2 / c
        best = min(best, (ratio, sigma / ratio))
    if not np.isfinite(best[0]):
        return float("nan"), 0.0
    return float(np.sqrt(best[0] * level)), float(best[1])


def boundary_starts(region: Region, count: int, seed: int) -> np.ndarray:
    """`count` starts s* + ds drawn uniformly in direction on the region's boundary ds' P ds = c."""
    rng = np.random.default_rng(seed)
    directions = rng.standard_normal((count, region.equilibrium.size))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    values, vectors = np.linalg.eigh(region.lyapunov)
    return region.equilibrium + directions @ (vectors * np.sqrt(region.level / values)).T


def levels(region: Region, states: np.ndarray) -> np.ndarray:
    """V / c along runs (steps, starts, n): 1 on the boundary, 0 at the equilibrium."""
    deviation = states - region.equilibrium
    return np.einsum("...i,ij,...j->...", deviation, region.lyapunov, deviation) / region.level
