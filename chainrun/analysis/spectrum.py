"""The linear spectrum of a line at rest in its static state: normal modes and bands.

This module owns the small-amplitude theory of a line (``chainrun.solver.Line``). At a
static state each contact j (the walls' included) is compressed by ``delta0_j`` and
carries ``F0_j = kappa_j delta0_j^alpha_j``; about that state its force changes by
``K_j`` times the change of its compression, with the linear stiffness

    K_j = alpha_j kappa_j delta0_j^(alpha_j - 1)        (delta0_j > 0, loaded)
    K_j = kappa_j                                        (delta0_j = 0, alpha_j = 1)
    K_j = 0                                              (otherwise: unloaded or open)

A linear contact that just touches (delta0 = 0, alpha = 1) sits on the kink of its law
``kappa max(delta, 0)``: it takes the stiffness of its compressed side, the limit of a
vanishing load, so a linear line has the same spectrum under any load (the chain of
springs the paper's alpha = 1 line is while its contacts stay compressed); the modes
then hold for motions that keep that contact compressed. An unloaded contact of alpha > 1
has no linear stiffness at all: a line with no load has only zero frequencies.

Small displacements ``x`` about the static state obey ``M x'' = -K x``, K symmetric
tridiagonal (a wall is a spring to a fixed point, a free end none), so the normal modes
solve ``K x = omega^2 M x``; with ``x = M^(-1/2) y`` that is the symmetric tridiagonal
eigenproblem ``M^(-1/2) K M^(-1/2) y = omega^2 y`` (``scipy.linalg.eigh_tridiagonal``).
The line is solved piece by piece between contacts of zero stiffness; a piece held by
no wall has one zero mode, its rigid translation, set exactly.

A line that repeats a unit cell of P balls (masses and linear stiffnesses; the period is
found, or given) has, as an infinite line, the dispersion relation omega(q) of the cell:
with ``x_{a,n} = u_a exp(i q n)`` for ball a of cell n, ``D(q) u = omega^2 u`` with the
P x P Hermitian dynamical matrix D. In one dimension with nearest-neighbour springs each
branch is monotonic in q on [0, pi], so its band runs between its values at q = 0 and
q = pi: the band edges are exact.

The strikers (the leading balls that move, ``chainrun.solver.model.strikers``) and the
contacts that touch them are left out: the spectrum is that of the rest of the line, at
rest (velocities are not part of the static state). Damping is left out too: the modes
are those of the elastic line.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
from scipy.linalg import eigh_tridiagonal

from chainrun.errors import ChainrunError
from chainrun.solver import Line
from chainrun.solver.model import strikers
from chainrun.units import PAPER, UNITS, format_value

__all__ = ["MAX_BALLS", "MAX_SHAPE_BALLS", "Q_POINTS", "STATIC_RTOL", "StaticState",
           "band_edges", "dispersion", "find_period", "line_spectrum", "normal_modes",
           "run_spectrum", "static_state"]

#: Longest line whose spectrum is computed: the frequencies take O(N^2) time (12 s for
#: 20000 balls on one core).
MAX_BALLS = 20_000
#: Longest line whose mode shapes are kept: they take N^2 numbers (32 MB for 2000 balls).
MAX_SHAPE_BALLS = 2_000
#: Wavenumbers of the dispersion relation, from 0 to pi inclusive.
Q_POINTS = 181
#: A ball is at rest in a static state when the forces on it add up to at most this
#: fraction of the largest force on the line (rounding in the positions is far smaller).
STATIC_RTOL = 1e-8
#: Displacements below this fraction of a mode's largest do not choose its sign.
SHAPE_FLOOR = 1e-6
#: Two masses or stiffnesses are the same for the period when they differ by at most this.
PERIOD_RTOL = 1e-9


@dataclass(frozen=True)
class StaticState:
    """The part of a line the spectrum is of, at rest, and its contacts' static state.

    Attributes
    ----------
    balls : ndarray of int, shape (M,)
        The balls kept, numbered from 1 (K+1 .. N: the strikers left out).
    mass : ndarray, shape (M,)
    contacts : ndarray of int, shape (C,)
        The contacts kept: contact j joins ball j and ball j+1, where ball 0 is the left
        wall and ball N+1 the right wall (so 0 is the left wall's contact, N the right's).
    compression, force, stiffness : ndarray, shape (C,)
        Static compression ``delta0``, static force ``kappa delta0_+^alpha`` and linear
        stiffness ``K`` of each contact kept.
    springs : ndarray, shape (M+1,)
        The linear stiffness on each side of each kept ball: ``springs[i]`` joins kept
        balls i-1 and i (0-based), ``springs[0]`` and ``springs[M]`` the ends (0 at a free
        end).
    left_out : int
        K, the strikers left out.
    """

    balls: np.ndarray
    mass: np.ndarray
    contacts: np.ndarray
    compression: np.ndarray
    force: np.ndarray
    stiffness: np.ndarray
    springs: np.ndarray
    left_out: int


def _linear_stiffness(kappa, alpha, delta):
    """``K`` of contacts of stiffness ``kappa``, exponent ``alpha`` compressed by
    ``delta`` (arrays alike): see the module's docstring."""
    with np.errstate(invalid="ignore", divide="ignore"):
        loaded = alpha * kappa * np.where(delta > 0.0, delta, 1.0) ** (alpha - 1.0)
    touching_linear = (delta == 0.0) & (alpha == 1.0)
    return np.where(delta > 0.0, loaded, np.where(touching_linear, kappa, 0.0))


def static_state(line: Line, units: str = "paper") -> StaticState:
    """The static state of ``line`` without its strikers (see the module's docstring).

    Parameters
    ----------
    line : Line
        At rest in a static state from its ``position`` (as ``chain.precompression``
        places it), strikers aside.
    units : {"paper", "si"}
        The line's units, for messages.

    Raises
    ------
    ChainrunError
        If every ball moves, or a kept ball is not at rest in a static state (the
        forces on it add up to more than ``STATIC_RTOL`` of the largest force).
    """
    n = line.n
    k = strikers(line)
    if k >= n:
        raise ChainrunError("chain.k: every ball is a striker (or moves, by chain.velocity); "
                            "the spectrum is of the balls at rest after the strikers, and "
                            "there are none")
    x = np.asarray(line.position, dtype=float)
    # contact c = 0..N joins ball c and ball c+1 (1-based; ball 0 and N+1 the walls)
    kappa = np.zeros(n + 1)
    alpha = np.ones(n + 1)
    delta = np.full(n + 1, -np.inf)  # a missing wall: never in contact
    kappa[1:n], alpha[1:n] = line.stiffness, line.alpha
    delta[1:n] = x[:-1] - x[1:] - line.gap
    for c, wall, compression in ((0, line.left, lambda w: -x[0] - w.gap),
                                 (n, line.right, lambda w: x[-1] - w.gap)):
        if wall is not None:
            kappa[c], alpha[c], delta[c] = wall.stiffness, wall.alpha, compression(wall)
    # the strikers' contacts are left out: contact c is kept when both its sides are
    kept = np.arange(n + 1) > k
    kept[0] |= k == 0
    present = np.isfinite(delta)
    force = np.where(kept & present, kappa * np.clip(delta, 0.0, None) ** alpha, 0.0)
    stiffness = np.where(kept & present, _linear_stiffness(kappa, alpha, delta), 0.0)

    external = np.asarray(line.force, dtype=float)[k:]
    net = force[k:n] - force[k + 1:] + external
    scale = max(float(np.max(force)), float(np.max(np.abs(external), initial=0.0)))
    off = np.flatnonzero(np.abs(net) > STATIC_RTOL * scale)
    if off.size:
        i = int(off[0])
        raise ChainrunError(
            f"ball {k + i + 1} is not at rest in a static state: the forces on it add up "
            f"to {format_value(float(net[i]), 'force', units)} (largest force on the line "
            f"{format_value(scale, 'force', units)}); the spectrum is of a line at rest "
            "(chain.precompression places one)")
    contacts = np.flatnonzero(kept & present)
    return StaticState(balls=np.arange(k + 1, n + 1), mass=np.asarray(line.mass[k:], float),
                       contacts=contacts, compression=delta[contacts] + 0.0,  # no -0.0
                       force=force[contacts],
                       stiffness=stiffness[contacts], springs=stiffness[k:].copy(),
                       left_out=k)


def normal_modes(mass, springs, shapes: bool = True):
    """Angular frequencies and shapes of the normal modes of a line of springs.

    Parameters
    ----------
    mass : ndarray, shape (M,)
    springs : ndarray, shape (M+1,)
        Linear stiffness between neighbours, ``springs[i]`` joining balls i-1 and i;
        ``springs[0]`` and ``springs[M]`` tie the end balls to fixed points (walls),
        0 for a free end.
    shapes : bool
        Whether to compute the mode shapes.

    Returns
    -------
    omega : ndarray, shape (M,)
        Ascending, >= 0 (exactly 0 for the rigid translation of each piece that no wall
        holds).
    shape : ndarray, shape (M, M), or None
        ``shape[m]`` is mode m's displacement of each ball, scaled so that its largest
        magnitude is 1 (max-normalised) and the first ball that moves (by more than
        ``SHAPE_FLOOR`` of that) moves forward.
    """
    m = np.asarray(mass, dtype=float)
    k = np.asarray(springs, dtype=float)
    size = m.size
    sq = np.sqrt(m)
    # pieces joined by springs of non-zero stiffness, solved one by one
    cuts = np.flatnonzero(k[1:-1] == 0.0) + 1
    starts = np.concatenate(([0], cuts))
    ends = np.concatenate((cuts, [size]))
    lam, vectors = [], []
    for a, b in zip(starts, ends):
        d = (k[a:b] + k[a + 1:b + 1]) / m[a:b]
        e = -k[a + 1:b] / (sq[a:b - 1] * sq[a + 1:b])
        if shapes:
            w, y = eigh_tridiagonal(d, e)
        else:
            w, y = eigh_tridiagonal(d, e, eigvals_only=True), None
        held = k[a] > 0.0 or k[b] > 0.0
        if not held:  # a free piece: its lowest mode is the rigid translation, omega = 0
            w[0] = 0.0
            if shapes:
                y[:, 0] = sq[a:b] / np.linalg.norm(sq[a:b])
        lam.append(w)
        if shapes:
            full = np.zeros((size, b - a))
            full[a:b] = y / sq[a:b, None]  # x = M^(-1/2) y
            vectors.append(full)
    lam = np.concatenate(lam)
    order = np.argsort(lam, kind="stable")
    omega = np.sqrt(np.clip(lam[order], 0.0, None))
    if not shapes:
        return omega, None
    x = np.concatenate(vectors, axis=1)[:, order].T
    top = np.max(np.abs(x), axis=1, keepdims=True)
    # the sign: the first ball that moves in the mode moves forward
    first = np.argmax(np.abs(x) > SHAPE_FLOOR * top, axis=1)
    sign = np.sign(x[np.arange(size), first])[:, None]
    return omega, x / (sign * top)


def find_period(mass, stiffness, period: int | None = None) -> int:
    """The number of balls in the unit cell a line repeats, 0 if it does not repeat.

    Parameters
    ----------
    mass : ndarray, shape (M,)
    stiffness : ndarray, shape (M-1,)
        Linear stiffness of the contacts between the balls (the walls' are not part of
        the cell).
    period : int, optional
        The period to use (checked); None finds the smallest one, with at least two
        cells in the line; 0 asks for none.

    Raises
    ------
    ChainrunError
        If ``period`` is given and the line does not repeat every ``period`` balls.
    """
    m = np.asarray(mass, dtype=float)
    k = np.asarray(stiffness, dtype=float)

    def differs(a: np.ndarray, p: int) -> int:
        """The first index i with a[i + p] unlike a[i], or -1."""
        bad = ~np.isclose(a[p:], a[:-p], rtol=PERIOD_RTOL, atol=0.0)
        return int(np.argmax(bad)) if bad.any() else -1

    if period is not None:
        if (isinstance(period, bool) or not isinstance(period, numbers.Real)
                or not math.isfinite(period) or int(period) != period or period < 0):
            raise ChainrunError(f"period: expected a number of balls >= 0, got {period!r}")
        period = int(period)
        if period == 0:
            return 0
        if not 2 * period <= m.size:
            raise ChainrunError(f"period: a cell of {period} balls needs a line of at "
                                f"least {2 * period} at rest, this one has {m.size}")
        i = differs(m, period)
        if i >= 0:
            raise ChainrunError(f"period: the line does not repeat every {period} balls: "
                                f"the mass of ball {i + period + 1} differs from ball "
                                f"{i + 1}'s (counting the balls at rest from 1)")
        i = differs(k, period)
        if i >= 0:
            raise ChainrunError(f"period: the line does not repeat every {period} balls: "
                                f"the linear stiffness of the contact after ball "
                                f"{i + period + 1} differs from that after ball {i + 1} "
                                "(counting the balls at rest from 1)")
        return period
    for p in range(1, m.size // 2 + 1):
        if differs(m, p) < 0 and differs(k, p) < 0:
            return p
    return 0


def _dynamical_matrix(mass, springs, q):
    """``D(q)``, shape (Q, P, P), of a cell of masses ``mass`` (P,) whose spring
    ``springs[a]`` joins its ball a to ball a+1, the last to the next cell's first."""
    m = np.asarray(mass, dtype=float)
    k = np.asarray(springs, dtype=float)
    p = m.size
    q = np.asarray(q, dtype=float)
    d = np.zeros((q.size, p, p), dtype=complex)
    idx = np.arange(p)
    d[:, idx, idx] = (k + np.roll(k, 1)) / m
    phase = np.exp(1j * q)
    for a in range(p):
        b = (a + 1) % p
        # ball a of cell n pulls on ball b of cell n (or n+1 across the cell's end)
        coupling = -k[a] / math.sqrt(m[a] * m[b]) * (phase if b == 0 else 1.0)
        d[:, a, b] += coupling
        d[:, b, a] += np.conj(coupling)
    return d


def dispersion(mass, springs, q) -> np.ndarray:
    """omega(q) of each branch of the infinite line of the cell, shape (Q, P), ascending.

    Parameters
    ----------
    mass : ndarray, shape (P,)
        The cell's masses.
    springs : ndarray, shape (P,)
        ``springs[a]`` joins the cell's ball a to ball a+1; ``springs[P-1]`` joins its
        last ball to the next cell's first.
    q : ndarray, shape (Q,)
        Wavenumbers: the phase from one cell to the next (rad).
    """
    q = np.asarray(q, dtype=float)
    lam = np.linalg.eigvalsh(_dynamical_matrix(mass, springs, q))
    lam[q == 0.0, 0] = 0.0  # at q = 0 the lowest mode is the rigid translation, exactly
    return np.sqrt(np.clip(lam, 0.0, None))


def band_edges(mass, springs) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest omega of each branch, shape (P,) each: its values at
    q = 0 and q = pi (each branch is monotonic in between)."""
    ends = dispersion(mass, springs, [0.0, math.pi])
    return ends.min(axis=0), ends.max(axis=0)


def _units_of(quantity: str, units: str) -> str:
    return UNITS["si"][quantity] if units == "si" else PAPER



#: The short ``long_name`` of each variable and coordinate, which xarray's plots take
#: for an axis label; the longer text it is built with is its ``description``.
_LABELS = {
    "omega": "angular frequency", "frequency": "frequency",
    "static_compression": "static compression", "static_force": "static force",
    "linear_stiffness": "linear stiffness", "shape": "mode shape", "mode": "mode",
    "ball": "ball", "contact": "contact", "q": "wavenumber", "branch": "branch",
    "dispersion": "angular frequency", "band_bottom": "band bottom", "band_top": "band top",
}


def line_spectrum(line: Line, units: str = "paper", *, period: int | None = None):
    """The linear spectrum of ``line`` at rest in its static state, as an xarray Dataset.

    Parameters
    ----------
    line : Line
        A line at rest in a static state (its strikers are left out).
    units : {"paper", "si"}
        The line's units: frequencies are in the inverse of its time unit.
    period : int, optional
        Balls per unit cell for the dispersion relation: None finds it (the smallest
        cell the masses and linear stiffnesses repeat, at least twice), 0 leaves it out.
        A cell with a contact of no stiffness has no dispersion relation.

    Returns
    -------
    xarray.Dataset
        Dimensions ``mode`` (1..M), ``ball`` (the balls kept, numbered as in the line),
        ``contact`` (0 the left wall, j between balls j and j+1, N the right wall) and,
        for a periodic line, ``q`` (0..pi, rad per cell) and ``branch`` (1..P).
        ``omega`` (mode), ascending angular frequencies, and ``frequency`` = omega / 2 pi;
        ``shape`` (mode, ball), max-normalised (for lines of up to ``MAX_SHAPE_BALLS``);
        ``mass`` (ball); ``static_compression``, ``static_force``, ``linear_stiffness``
        (contact); ``dispersion`` (q, branch), ``band_bottom`` and ``band_top``
        (branch) for a periodic line. Attributes: ``units``, ``n``, ``strikers_left_out``,
        ``period``, ``loaded_contacts``, ``zero_modes``, ``shape_normalisation``.

    Raises
    ------
    ChainrunError
        One line: a line that is not at rest in a static state, too long, or not of the
        ``period`` given.
    """
    import xarray as xr

    size = line.n - strikers(line)
    if size > MAX_BALLS:
        raise ChainrunError(f"chain.n: a line of {size} balls at rest is too long for its "
                            f"spectrum (at most {MAX_BALLS})")
    state = static_state(line, units)
    shapes = state.mass.size <= MAX_SHAPE_BALLS
    omega, shape = normal_modes(state.mass, state.springs, shapes=shapes)
    modes = np.arange(1, omega.size + 1)

    def var(dims, values, quantity, long_name):
        return (dims, values, {"long_name": long_name, "units": _units_of(quantity, units)})

    data = {
        "omega": var("mode", omega, "angular_frequency",
                     "angular frequency of the normal mode, ascending"),
        "frequency": var("mode", omega / (2.0 * math.pi), "frequency",
                         "frequency of the normal mode, omega / (2 pi)"),
        "mass": var("ball", state.mass, "mass", "mass of the ball"),
        "static_compression": var("contact", state.compression, "position",
                                  "compression of the contact at rest (< 0: a gap)"),
        "static_force": var("contact", state.force, "force", "force of the contact at rest"),
        "linear_stiffness": var("contact", state.stiffness, "linear_stiffness",
                                "linear stiffness alpha kappa delta0^(alpha - 1)"),
    }
    if shape is not None:
        data["shape"] = (("mode", "ball"), shape,
                         {"long_name": "displacement of each ball in the mode: largest "
                                       "magnitude 1, the first ball moving forward",
                          "units": "1"})
    coords = {"mode": ("mode", modes, {"long_name": "mode number, by ascending frequency"}),
              "ball": ("ball", state.balls, {"long_name": "ball number (from 1)"}),
              "contact": ("contact", state.contacts,
                          {"long_name": "contact j joins balls j and j+1; 0 is the left "
                                        "wall's, N the right wall's"})}
    cell = find_period(state.mass, state.springs[1:-1], period)
    if cell and not np.all(state.springs[1:cell + 1] > 0.0):
        # a cell that a contact without stiffness cuts: the infinite line falls apart
        if period is not None:
            raise ChainrunError(f"period: a contact of the {cell}-ball cell has no linear "
                                "stiffness (no load), so the infinite line falls apart "
                                "and has no dispersion relation")
        cell = 0
    if cell:
        cell_mass, cell_springs = state.mass[:cell], state.springs[1:cell + 1]
        q = np.linspace(0.0, math.pi, Q_POINTS)
        bottom, top = band_edges(cell_mass, cell_springs)
        coords["q"] = ("q", q, {"long_name": "wavenumber: phase from one cell to the next",
                                "units": "rad"})
        coords["branch"] = ("branch", np.arange(1, cell + 1),
                            {"long_name": "branch of the dispersion relation, from below"})
        data["dispersion"] = var(("q", "branch"), dispersion(cell_mass, cell_springs, q),
                                 "angular_frequency",
                                 "angular frequency omega(q) of the infinite periodic line")
        data["band_bottom"] = var("branch", bottom, "angular_frequency",
                                  "lowest angular frequency of the branch (its band's edge)")
        data["band_top"] = var("branch", top, "angular_frequency",
                               "highest angular frequency of the branch (its band's edge)")
    attrs = {
        "units": "SI" if units == "si" else PAPER,
        "n": line.n,
        "strikers_left_out": state.left_out,
        "period": cell,
        "loaded_contacts": int(np.count_nonzero(state.force)),
        "zero_modes": int(np.count_nonzero(omega == 0.0)),
        "shape_normalisation": ("max: largest magnitude 1, the first ball moving forward"
                                if shapes else
                                f"none: no shapes for more than {MAX_SHAPE_BALLS} balls"),
    }
    for table in (data, coords):
        for name, (dims, values, meta) in table.items():
            if name in _LABELS:
                table[name] = (dims, values, {**meta, "long_name": _LABELS[name],
                                              "description": meta["long_name"]})
    return xr.Dataset(data, coords=coords, attrs=attrs)


def run_spectrum(spec, *, period: int | None = None):
    """``line_spectrum`` of a run of an experiment (``chainrun.config.RunSpec``), with
    where it came from: ``experiment``, ``run_id``, ``config_hash`` and ``config`` (the
    experiment file's text) as attributes."""
    ds = line_spectrum(spec.line, spec.units, period=period)
    ds.attrs.update(experiment=spec.experiment, run_id=spec.run_id,
                    config_hash=spec.config_hash, config=spec.source_text)
    return ds
