"""Building a ``Line`` from plain values: real spheres to Hertz constants, restitutions to
damping, precompression to a static state.

This module owns the physics of turning a described line into the ``Line`` the solver
integrates. Its inputs are checked numbers and arrays (``chainrun.config`` reads and
checks the experiment file, expands every per-ball and per-contact key, and calls
``build_line``); it never sees the file's models. No kernel imports it: it stays out
of the kernels' cache key (``chainrun.solver._jit``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from chainrun.solver import physics
from chainrun.solver import restitution as collision
from chainrun.solver.drive import Drive
from chainrun.solver.model import Line, Wall, precompress, weigh


@dataclass(frozen=True)
class Spheres:
    """Real spheres, one value per ball (SI): ``mass = rho pi d^3 / 6`` and Hertz
    contacts (alpha = 3/2) between neighbours.

    Attributes
    ----------
    diameter, young, poisson, density : ndarray, shape (N,)
    material : ndarray of str, shape (N,), or str
        The preset each ball is of (``chainrun.materials``), ``""`` for constants
        given explicitly; recorded with the line, not read by the solver.
    """

    diameter: np.ndarray
    young: np.ndarray
    poisson: np.ndarray
    density: np.ndarray
    material: np.ndarray | str = ""


@dataclass(frozen=True)
class Dissipation:
    """How contacts dissipate: a ``damping`` eta with its ``exponent`` beta (or the
    exponent of ``law``), or a ``restitution`` e with its ``law`` (and the impact
    ``speed`` e holds at, where it depends on the speed). Arrays have one value per
    contact (one for a wall); all None: elastic."""

    damping: np.ndarray | None = None
    exponent: np.ndarray | float | None = None
    restitution: np.ndarray | None = None
    law: str | None = None
    speed: float | None = None


@dataclass(frozen=True)
class WallSpec:
    """A wall to build: ``stiffness`` and ``alpha`` given, or (``stiffness`` None) a
    Hertz contact with the end sphere, the wall of ``young`` and ``poisson`` (None: of
    the end ball's material). ``alpha`` None takes the exponent of the contact next to
    the wall."""

    gap: float = 0.0
    stiffness: float | None = None
    alpha: float | None = None
    young: float | None = None
    poisson: float | None = None
    dissipation: Dissipation = Dissipation()
    motion: Drive | None = None


class BuildError(ValueError):
    """Problems building a line: ``(key, reason)`` pairs, the key relative to the line
    (``"restitution_speed"``, ``"right.restitution"``; ``""`` for the line itself)."""

    def __init__(self, problems: list[tuple[str, str]]):
        super().__init__("; ".join(f"{k}: {r}" if k else r for k, r in problems))
        self.problems = problems


def build_line(n: int, velocity: np.ndarray, *, mass=None, stiffness=None, alpha=None,
               gap=None, force=None, spheres: Spheres | None = None,
               dissipation: Dissipation = Dissipation(), left: WallSpec | None = None,
               right: WallSpec | None = None, drives=(),
               precompression: float | None = None, gravity: float | None = None) -> Line:
    """The ``Line`` of ``n`` balls these values describe.

    Parameters
    ----------
    n : int
    velocity : ndarray, shape (N,)
    mass, force : float or ndarray, shape (N,), optional
    stiffness, alpha, gap : float or ndarray, shape (N-1,), optional
        Left out: ``Line.make``'s defaults. With ``spheres``, mass, stiffness and alpha
        come from the spheres instead.
    spheres : Spheres, optional
    dissipation : Dissipation
        The contacts' between balls (a restitution is converted to eta with the
        reduced mass of each contact, ``m_j m_(j+1) / (m_j + m_(j+1))``; a wall's with
        the end ball's mass).
    left, right : WallSpec, optional
    drives : sequence of (int, Drive)
        Forces in time, on balls numbered from 0.
    precompression : float, optional
        The load the resting balls start at equilibrium under
        (``chainrun.solver.model.precompress``).
    gravity : float, optional
        The acceleration of the balls' weights, towards ball N; on a right wall the
        resting balls start at equilibrium under them (``chainrun.solver.model.weigh``).

    Raises
    ------
    BuildError
        Every problem found.
    """
    kw = {}
    if spheres is not None:
        radius = spheres.diameter / 2.0
        kw.update(diameter=spheres.diameter, material=spheres.material,
                  mass=physics.sphere_mass(spheres.density, spheres.diameter),
                  stiffness=physics.hertz_stiffness(
                      spheres.young[:-1], spheres.poisson[:-1], radius[:-1],
                      spheres.young[1:], spheres.poisson[1:], radius[1:]),
                  alpha=1.5)
    else:
        kw.update({key: value for key, value in (("mass", mass), ("stiffness", stiffness),
                                                 ("alpha", alpha)) if value is not None})
    if gap is not None:
        kw["gap"] = gap
    if force is not None:
        kw["force"] = force
    walls = {}
    for side, spec, end in (("left", left, 0), ("right", right, n - 1)):
        if spec is None:
            continue
        if spec.stiffness is None:  # Hertz: a flat body, R* the end ball's radius
            s = spheres
            young = s.young[end] if spec.young is None else spec.young
            poisson = s.poisson[end] if spec.poisson is None else spec.poisson
            walls[side] = Wall(float(physics.hertz_stiffness(
                s.young[end], s.poisson[end], s.diameter[end] / 2.0, young, poisson)),
                1.5, spec.gap, motion=spec.motion)
            continue
        wall_alpha = spec.alpha
        if wall_alpha is None:  # the law of the contact next to it
            wall_alpha = float(np.asarray(kw["alpha"]).reshape(-1)[0 if side == "left" else -1])
        walls[side] = Wall(spec.stiffness, wall_alpha, spec.gap, motion=spec.motion)
    try:
        line = Line.make(n, velocity=velocity, drives=tuple(drives), **walls, **kw)
    except ValueError as exc:  # not expected: every value was checked by the caller
        raise BuildError([("", str(exc))]) from None
    line = _with_dissipation(line, dissipation, left, right)
    if precompression:
        try:
            line = precompress(line, precompression)
        except ValueError as exc:
            raise BuildError([("precompression", str(exc))]) from None
    if gravity:
        try:
            line = weigh(line, gravity)
        except ValueError as exc:
            raise BuildError([("gravity", str(exc))]) from None
    return line


def _damping_of(prefix: str, spec: Dissipation, kappa: np.ndarray, alpha: np.ndarray,
                mu: np.ndarray, problems: list[tuple[str, str]]):
    """(eta, beta) of contacts of stiffness ``kappa``, exponent ``alpha`` and reduced
    mass ``mu`` (arrays alike), or None for elastic contacts or a problem (added to
    ``problems``); beta None: ``spec.exponent`` as given."""
    law = spec.law
    if spec.restitution is not None:
        beta = np.array([collision.law_exponent(law, a) for a in alpha.reshape(-1)])
        needs = (spec.restitution < 1.0) & (beta != (alpha - 1.0) / 2.0)
        if spec.speed is None and np.any(needs):
            i = int(np.flatnonzero(needs)[0])
            # (contacts numbered as the run file numbers them: contact j joins balls
            # j and j + 1, counted from 1)
            where = f"contact {i + 1}, balls {i + 1}-{i + 2}, " if not prefix else ""
            problems.append((f"{prefix}restitution_speed",
                             f"required: the restitution of the {law} law depends on the "
                             f"impact speed ({where}alpha = {_number(float(alpha[i]))}); give "
                             "the speed it holds at"))
            return None
        try:
            eta = collision.damping_for_restitution(spec.restitution, law, kappa, alpha, mu,
                                                    spec.speed)
        except (ValueError, RuntimeError) as exc:  # not expected: inputs were checked
            problems.append((f"{prefix}restitution", str(exc)))
            return None
        return np.asarray(eta, dtype=float), beta
    if spec.damping is None:
        return None
    if spec.exponent is not None:
        return spec.damping, None
    if law is not None:
        return spec.damping, np.array([collision.law_exponent(law, a)
                                       for a in alpha.reshape(-1)])
    return spec.damping, np.zeros_like(spec.damping)


def _number(x: float) -> str:
    """``2`` for 2.0, else the float's repr."""
    return str(int(x)) if x.is_integer() and abs(x) < 1e15 else repr(x)


def _with_dissipation(line: Line, chain: Dissipation, left: WallSpec | None,
                      right: WallSpec | None) -> Line:
    """``line`` with the damping of its contacts and walls."""
    problems: list[tuple[str, str]] = []
    changes = {}
    m = line.mass
    mu = m[:-1] * m[1:] / (m[:-1] + m[1:])
    got = _damping_of("", chain, np.asarray(line.stiffness), np.asarray(line.alpha), mu,
                      problems)
    if got is not None:
        changes["damping"] = got[0]
        changes["damping_exponent"] = chain.exponent if got[1] is None else got[1]
    for side, spec, end in (("left", left, 0), ("right", right, line.n - 1)):
        wall = getattr(line, side)
        if spec is None or wall is None:
            continue
        got = _damping_of(f"{side}.", spec.dissipation, np.array([wall.stiffness]),
                          np.array([wall.alpha]), np.array([m[end]]), problems)
        if got is not None:
            beta = spec.dissipation.exponent if got[1] is None else float(got[1][0])
            changes[side] = replace(wall, damping=float(got[0][0]), damping_exponent=beta)
    if problems:
        raise BuildError(problems)
    return replace(line, **changes) if changes else line
