"""The line the solver integrates: balls, contacts, walls and external forces, in any units.

Balls i = 1..N have masses ``m_i``, displacements ``x_i(t)`` from their reference
positions (``x_i(0)`` is ``position``, 0 unless the line starts precompressed),
velocities ``v_i(0)`` and constant external forces ``f_i``. Contact j joins balls j
and j + 1; its compression is ``delta_j = x_j - x_{j+1} - g_j`` (``g_j > 0`` a gap,
``< 0`` an initial overlap) and its force

    F_j = max(0, kappa_j delta_j^alpha_j + eta_j delta_j^beta_j d(delta_j)/dt)

while ``delta_j > 0`` never pulls: an elastic part and a damping part (``eta_j`` the
damping, ``beta_j`` its exponent; ``eta_j = 0``, the default, is elastic). A wall is a contact with a body of infinite mass at rest: on the right
``delta_R = x_N - g_R``, on the left ``delta_L = -x_1 - g_L``.

    m_i x_i'' = F_{i-1} - F_i + f_i + d_i(t)

A driven line moves under prescribed functions of time (``chainrun.solver.drive``): a
wall whose displacement from its place follows ``Wall.motion`` w(t) (then
``delta_L = w_L(t) - x_1 - g_L``, ``delta_R = x_N - w_R(t) - g_R``), and forces
``d_i(t)`` on chosen balls (``Line.drives``). The drives do work on the line; it has
no terminal state.

Any consistent units will do (SI, or the paper's, where every coefficient is 1): the
driver solves in units of the line's own scales (``Scales``), so that speeds, masses
and stiffnesses are of order 1 there whatever units they were given in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from chainrun.solver.drive import Drive


#: log(eps) of a float: a length below ``eps L`` is below the rounding of L
_LOG_EPS = math.log(np.finfo(float).eps)


def _alike(a: np.ndarray) -> bool:
    """Whether every entry of ``a`` is the same (or there is none)."""
    return a.size == 0 or bool(a[0] == a[-1] and np.all(a == a[0]))


@dataclass(frozen=True)
class Wall:
    """A flat wall of infinite mass, touching the end ball across ``gap``: at rest, or,
    with a ``motion`` w(t), displaced by w(t) from its place (w(0) = 0)."""

    stiffness: float
    alpha: float = 1.5
    gap: float = 0.0
    damping: float = 0.0
    damping_exponent: float = 0.0
    motion: Drive | None = None

    def __post_init__(self):
        if self.motion is not None:
            if not isinstance(self.motion, Drive):
                raise ValueError(f"wall motion must be a Drive, got {self.motion!r}")
            if self.motion(0.0) != 0.0:
                raise ValueError("a wall's motion starts at its place: w(0) must be 0, "
                                 f"got {float(self.motion(0.0))!r}")
        for name in ("damping", "damping_exponent"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"wall {name} must be a finite number >= 0, got {value!r}")
        for name, value, low in (("stiffness", self.stiffness, 0.0),
                                 ("alpha", self.alpha, 1.0)):
            if not (math.isfinite(value) and (value > low if name == "stiffness"
                                              else value >= low)):
                raise ValueError(f"wall {name} must be a finite number "
                                 f"{'>' if name == 'stiffness' else '>='} {low:g}, "
                                 f"got {value!r}")
        if not math.isfinite(self.gap):
            raise ValueError(f"wall gap must be finite, got {self.gap!r}")


@dataclass(frozen=True)
class Scales:
    """The units the driver solves in: a mass, a length and a time (and from them a
    velocity and a force). For the paper's line in its units, all are 1."""

    mass: float
    length: float
    time: float

    @property
    def velocity(self) -> float:
        return self.length / self.time

    @property
    def force(self) -> float:
        return self.mass * self.length / (self.time * self.time)

    @property
    def energy(self) -> float:
        return self.force * self.length


def _per(name: str, value, size: int) -> np.ndarray:
    """``value`` (a scalar or a sequence of ``size``) as a float array of ``size``."""
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:  # one value for all: a read-only view, no memory per ball
        return np.broadcast_to(a, (size,))
    a = a.reshape(-1)
    if a.size != size:
        raise ValueError(f"{name} must be a number or a list of {size} numbers, "
                         f"got a list of {a.size}")
    return a.copy()


def _names(value, size: int) -> np.ndarray:
    """``value`` (a name or a sequence of ``size`` names) as a str array of ``size``."""
    a = np.asarray(value, dtype=str)
    if a.ndim == 0:
        return np.broadcast_to(a, (size,))
    if a.shape != (size,):
        raise ValueError(f"material must be a name or a list of {size} names, "
                         f"got a list of {a.size}")
    return a.copy()


def _check(name: str, a: np.ndarray, low: float | None = None, strict: bool = True):
    bad = ~np.isfinite(a)
    if low is not None:
        bad |= (a <= low) if strict else (a < low)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        what = "finite" if low is None else f"finite and {'>' if strict else '>='} {low:g}"
        raise ValueError(f"{name}[{i}] must be {what}, got {a[i]!r}")


@dataclass(frozen=True, eq=False)
class Line:
    """A line of N balls (see the module's docstring); build it with ``Line.make``.

    Arrays are per ball (``mass``, ``velocity``, ``force``, ``position``, shape (N,))
    or per contact (``stiffness``, ``alpha``, ``gap``, ``damping``,
    ``damping_exponent``, shape (N-1,)). A line of real spheres also records what they
    are, per ball: ``diameter`` and ``material`` (a preset's name, ``""`` for constants
    given explicitly); the solver does not read them, the run file keeps them.
    ``drives`` are forces prescribed in time, ``(ball, Drive)`` pairs (ball numbered
    from 0; several on one ball add up), besides the constant ``force``.
    """

    mass: np.ndarray
    stiffness: np.ndarray
    alpha: np.ndarray
    gap: np.ndarray
    velocity: np.ndarray
    force: np.ndarray
    position: np.ndarray
    left: Wall | None = None
    right: Wall | None = None
    damping: np.ndarray | None = None
    damping_exponent: np.ndarray | None = None
    diameter: np.ndarray | None = None
    material: np.ndarray | None = None
    drives: tuple = ()

    def __post_init__(self):
        n = self.mass.shape[0]
        if n < 1:
            raise ValueError("a line needs at least one ball")
        drives = tuple(self.drives)
        for ball, drive in drives:
            if isinstance(ball, bool) or int(ball) != ball or not 0 <= ball < n:
                raise ValueError(f"a drive's ball must be within 0..{n - 1}, got {ball!r}")
            if not isinstance(drive, Drive):
                raise ValueError(f"a ball's drive must be a Drive, got {drive!r}")
        object.__setattr__(self, "drives", tuple((int(b), d) for b, d in drives))
        for name in ("mass", "velocity", "force", "position"):
            a = getattr(self, name)
            if a.shape != (n,):
                raise ValueError(f"{name} must have one value per ball ({n})")
        for name in ("damping", "damping_exponent"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.broadcast_to(0.0, (n - 1,)))
        for name in ("stiffness", "alpha", "gap", "damping", "damping_exponent"):
            a = getattr(self, name)
            if a.shape != (n - 1,):
                raise ValueError(f"{name} must have one value per contact ({n - 1})")
        _check("mass", self.mass, 0.0)
        _check("stiffness", self.stiffness, 0.0)
        _check("alpha", self.alpha, 1.0, strict=False)
        _check("damping", self.damping, 0.0, strict=False)
        _check("damping_exponent", self.damping_exponent, 0.0, strict=False)
        for name in ("gap", "velocity", "force", "position"):
            _check(name, getattr(self, name))
        for name in ("diameter", "material"):
            a = getattr(self, name)
            if a is not None and a.shape != (n,):
                raise ValueError(f"{name} must have one value per ball ({n})")
        if self.diameter is not None:
            _check("diameter", self.diameter, 0.0)
        for name in ("mass", "stiffness", "alpha", "gap", "velocity", "force", "position",
                     "damping", "damping_exponent"):
            getattr(self, name).setflags(write=False)

    @classmethod
    def make(cls, n: int, *, mass=1.0, stiffness=1.0, alpha=1.5, gap=0.0,
             velocity=None, k: int | None = None, speed: float = 1.0, force=0.0,
             position=0.0, damping=0.0, damping_exponent=0.0,
             left: Wall | None = None, right: Wall | None = None,
             diameter=None, material=None, drives=()) -> Line:
        """A line from scalars (every ball or contact alike) or sequences.

        The initial velocities are ``velocity`` (one per ball), or the first ``k``
        balls at ``speed`` and the rest at rest (k = 1 by default).
        """
        if isinstance(n, bool) or int(n) != n or n < 1:
            raise ValueError(f"n must be an integer >= 1, got {n!r}")
        n = int(n)
        if velocity is None:
            k = 1 if k is None else k
            if isinstance(k, bool) or int(k) != k or not 0 <= k <= n:
                raise ValueError(f"k must be an integer with 0 <= k <= n ({n}), got {k!r}")
            v = np.zeros(n)
            v[:int(k)] = speed
        elif k is not None:
            raise ValueError("give the initial velocities or k, not both")
        else:
            v = _per("velocity", velocity, n)
        return cls(
            mass=_per("mass", mass, n),
            stiffness=_per("stiffness", stiffness, n - 1),
            alpha=_per("alpha", alpha, n - 1),
            gap=_per("gap", gap, n - 1),
            velocity=v,
            force=_per("force", force, n),
            position=_per("position", position, n),
            damping=_per("damping", damping, n - 1),
            damping_exponent=_per("damping_exponent", damping_exponent, n - 1),
            left=left, right=right,
            diameter=None if diameter is None else _per("diameter", diameter, n),
            material=None if material is None else _names(material, n),
            drives=drives,
        )

    @classmethod
    def paper(cls, n: int, k: int, alpha: float) -> Line:
        """The paper's line: unit masses and stiffnesses, the first k balls at 1.

        n >= 1 balls, 0 <= k <= n strikers (0: the line at rest; ``make`` checks both),
        one exponent alpha >= 1 (1 linear, 1.5 Hertz).
        """
        if not (math.isfinite(alpha) and alpha >= 1.0):
            raise ValueError(f"alpha must be a finite number >= 1, got {alpha!r}")
        return cls.make(n, k=k, alpha=float(alpha))

    @property
    def n(self) -> int:
        return int(self.mass.shape[0])

    @property
    def walls(self) -> tuple[Wall | None, Wall | None]:
        return self.left, self.right

    def terminal_obstacles(self) -> tuple[str, ...]:
        """Why no terminal state can exist, one reason each (none: it can): an external
        force keeps doing work, a drive does, or walls hold the line at both ends. A
        run of such a line needs a stop time."""
        reasons = []
        if np.any(self.force != 0.0):
            reasons.append("an external force keeps doing work")
        if self.is_driven:
            reasons.append("a drive keeps doing work")
        if self.left is not None and self.right is not None:
            reasons.append("walls hold it at both ends")
        return tuple(reasons)

    @property
    def has_terminal_state(self) -> bool:
        """Whether a terminal state can exist (``terminal_obstacles``)."""
        return not self.terminal_obstacles()

    @property
    def is_driven(self) -> bool:
        """Whether a wall moves or a ball is driven (``drives``)."""
        return bool(self.drives) or any(w is not None and w.motion is not None
                                        for w in (self.left, self.right))

    def wall_displacement(self, t) -> tuple[np.ndarray, np.ndarray]:
        """(w_L(t), w_R(t)): each wall's displacement from its place at times ``t``
        (0 for a wall at rest, or none); each of the shape of ``t``."""
        t = np.asarray(t, dtype=float)
        return tuple(np.zeros(t.shape) if w is None or w.motion is None
                     else np.asarray(w.motion(t)) for w in (self.left, self.right))

    @property
    def is_paper(self) -> bool:
        """Unit masses and stiffnesses, no gap, force or wall, one exponent, balls at
        rest or at velocity 1: the paper's line."""
        return bool(
            np.all(self.mass == 1.0) and np.all(self.stiffness == 1.0)
            and np.all(self.alpha == self.alpha[:1]) and not np.any(self.gap)
            and not np.any(self.force) and not np.any(self.position)
            and not self.is_damped and not self.drives
            and np.all((self.velocity == 0.0) | (self.velocity == 1.0))
            and self.left is None and self.right is None)

    @property
    def is_damped(self) -> bool:
        """Whether any contact, or a wall, has damping."""
        return bool(np.any(self.damping != 0.0)) or any(
            w is not None and w.damping != 0.0 for w in (self.left, self.right))

    def damping_params(self) -> tuple[np.ndarray, np.ndarray]:
        """(damping, damping_exponent) of every contact, the walls' included, in the
        order of ``contact_params``."""
        etas, betas = [self.damping], [self.damping_exponent]
        if self.left is not None:
            etas.insert(0, [self.left.damping])
            betas.insert(0, [self.left.damping_exponent])
        if self.right is not None:
            etas.append([self.right.damping])
            betas.append([self.right.damping_exponent])
        return (np.concatenate(etas).astype(float), np.concatenate(betas).astype(float))

    def contact_params(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(stiffness, alpha, gap) of every contact, the walls' included: the left
        wall's first, the right wall's last."""
        if self.left is None and self.right is None:
            return self.stiffness, self.alpha, self.gap
        ks, als, gs = [self.stiffness], [self.alpha], [self.gap]
        if self.left is not None:
            ks.insert(0, [self.left.stiffness])
            als.insert(0, [self.left.alpha])
            gs.insert(0, [self.left.gap])
        if self.right is not None:
            ks.append([self.right.stiffness])
            als.append([self.right.alpha])
            gs.append([self.right.gap])
        return (np.concatenate(ks).astype(float), np.concatenate(als).astype(float),
                np.concatenate(gs).astype(float))

    def scales(self, params=None) -> Scales:
        """Units in which this line's typical mass, stiffness and speed are 1.

        Mass M: the median mass; stiffness K and exponent a: the median contact's
        (walls included; ``params``: ``contact_params()``, if at hand); velocity V: the largest initial speed, or, for a line at
        rest, a driven wall's typical speed (``Drive.speed``), or else the speed a
        typical force (external, a drive's, or of the largest overlap) gives over its
        static compression. Then the time ``T = (M V^(1-a) / K)^(1/(a+1))``
        and length ``V T`` make the force law ``K x^a`` balance ``M x''``: the paper's
        scales (its section 2), which are all 1 for its own line.

        For a line at rest, the static compression is the median contact's,
        ``L = (F/K)^(1/a)``. Where the exponents differ, another contact j can take a
        compression ``L_j = (F/K_j)^(1/a_j)`` that is a vanishing fraction of it: far
        from the crossing of two force laws, the ratio goes as a power of F (a linear
        wall and a contact of exponent 2.5 under F = 4e-154: L_j / L = 1e-92). In
        units of L that contact has a stiffness (L / L_j)^(a_j) and a time scale
        sqrt(L_j / L) of the unit: it would never be resolved, and its stiffness
        overflows the kernels' arithmetic. So where the smallest L_j is below the
        rounding of L (``L_j < eps L``), that contact sets the scales (K_j, a_j,
        L_j): the one the force actually moves, and every contact then has a
        stiffness of at most 1. Elsewhere, the median contact's scales stand.

        A moving line has the same defect in time. At the speed V, contact j stops a
        ball over its own time ``T_j = (M V^(1-a_j) / K_j)^(1/(a_j+1))`` and length
        ``V T_j``; with mixed exponents these too part as a power of V (a linear wall
        and a contact of exponent 2.5 at V = 1e-100: T_j / T = 1e-43). In units of T
        that contact has a stiffness (T / T_j)^(a_j+1), and a collision far shorter
        than the smallest step the integrator takes (8 eps of the unit): the run ends
        at t = 0, the step too small or the state non-finite. So where the smallest
        T_j is below the rounding of T (``T_j < eps T``, the same as ``V T_j < eps
        V T``), that contact sets the scales (K_j, a_j): the fastest, in whose units
        every other contact i has a stiffness (T_j / T_i)^(a_i+1) of at most 1. That
        makes the units finite and the start resolved; it cannot resolve both ends of
        a line whose contact times span beyond the kernels' reach (slow collisions, of
        1e16 units and more, end non-finite too).
        """
        kappa, alpha, gap = self.contact_params() if params is None else params
        m = self.mass
        mass = float(m[0]) if _alike(m) else float(np.median(m))
        if kappa.size == 0:  # one ball, no wall: nothing to balance
            v = float(np.max(np.abs(self.velocity)))
            return Scales(mass, v if v > 0 else 1.0, 1.0)
        if _alike(kappa) and _alike(alpha):
            k0, a0 = float(kappa[0]), float(alpha[0])
        else:
            i = int(np.argsort(kappa, kind="stable")[kappa.size // 2])
            k0, a0 = float(kappa[i]), float(alpha[i])
        speed = float(np.max(np.abs(self.velocity)))
        if speed == 0.0:  # a line at rest moves with its walls' motion
            speed = max((w.motion.speed for w in self.walls
                         if w is not None and w.motion is not None), default=0.0)
        if speed == 0.0:
            # a line at rest moves only under its forces or overlaps: their static
            # compression L = (F/K)^(1/a) and the time sqrt(M L / F) give a speed
            f = max([float(np.max(np.abs(self.force)))]
                    + [d.size for _, d in self.drives])
            overlap = float(max(np.max(-gap, initial=0.0),
                                np.max(np.abs(np.diff(self.position)), initial=0.0)))
            if overlap > 0.0:
                f = max(f, k0 * overlap ** a0)
            if f == 0.0:
                return Scales(mass, 1.0, 1.0)
            # in logarithms: a force as small as a float can be (a subnormal) still
            # gives a positive length and speed, where (F/K)^(1/a) would underflow to 0
            log_length = (math.log(f) - math.log(k0)) / a0
            if not (_alike(kappa) and _alike(alpha)):
                # each contact's own static compression under F, in logarithms: where
                # one is below the rounding of the length above, that contact is the
                # one F moves, and it is the length (``scales``' docstring)
                own = (math.log(f) - np.log(kappa)) / alpha
                j = int(np.argmin(own))
                if own[j] < log_length + _LOG_EPS:
                    k0, a0 = float(kappa[j]), float(alpha[j])
                    log_length = (math.log(f) - math.log(k0)) / a0
            log_speed = 0.5 * (log_length + math.log(f) - math.log(mass))
            log_time = (math.log(mass) + (1.0 - a0) * log_speed - math.log(k0)) / (a0 + 1.0)
            return Scales(mass, math.exp(log_speed + log_time), math.exp(log_time))
        if not (_alike(kappa) and _alike(alpha)):
            # each contact's own time at this speed, in logarithms: where one is below
            # the rounding of the median's, that contact sets the scales (``scales``'
            # docstring); the time itself is computed as before, to the bit
            log_m, log_v = math.log(mass), math.log(speed)
            own = (log_m + (1.0 - alpha) * log_v - np.log(kappa)) / (alpha + 1.0)
            log_time = (log_m + (1.0 - a0) * log_v - math.log(k0)) / (a0 + 1.0)
            j = int(np.argmin(own))
            if own[j] < log_time + _LOG_EPS:
                k0, a0 = float(kappa[j]), float(alpha[j])
        time = (mass * speed ** (1.0 - a0) / k0) ** (1.0 / (a0 + 1.0))
        return Scales(mass, speed * time, time)


def strikers(line: Line) -> int:
    """K: the number of leading balls with a non-zero initial velocity (they strike)."""
    moving = line.velocity != 0.0
    return line.n if moving.all() else int(np.argmin(moving))


def _resting(line: Line, k: int, loads: np.ndarray, wall_load: float) -> np.ndarray:
    """The displacements of balls k..N-1 (0-based) at rest on the right wall, contact j
    (balls j and j+1, j >= k) carrying ``loads[j - k]`` and the wall ``wall_load``, by
    the force law exactly: x_N = g_R + (W/k_R)^(1/a_R), x_j = x_{j+1} + g_j +
    (F_j/k_j)^(1/a_j), summed from the wall back (the order of a loop from j = N-2 down
    to k); balls before k at 0."""
    wall = line.right
    x = np.zeros(line.n)
    x[-1] = wall.gap + (wall_load / wall.stiffness) ** (1.0 / wall.alpha)
    step = line.gap[k:] + (loads / line.stiffness[k:]) ** (1.0 / line.alpha[k:])
    x[k:-1] = np.cumsum(np.concatenate(([x[-1]], step[::-1])))[:0:-1]
    return x


def precompress(line: Line, load: float) -> Line:
    """``line`` at rest in its static state under the load ``load``, pushed at the right wall.

    Against one wall (a right wall, no left one), the strikers (balls 1..K,
    ``strikers``) keep their velocities; balls K+1..N start at the static equilibrium
    under a constant external force ``load`` on ball K+1, pointing at the right wall
    (+x), which keeps acting during the run. Every contact from K+1 to the wall then
    carries ``load``, so the force law gives the positions exactly, from the wall back:

        x_N = g_R + (F0/k_R)^(1/a_R),   x_j = x_{j+1} + g_j + (F0/k_j)^(1/a_j)

    for j = N-1 down to K+1. The strikers are moved by x_{K+1}, so that they meet ball
    K+1 as they would without the load. The result has a force that keeps doing work:
    it has no terminal state.

    Between two walls, no external force acts: the left wall (an actuator) is placed
    where every contact, both walls' included, carries ``load`` at rest. The balls take
    the same positions (j = N-1 down to 1) and the left wall the gap
    ``g_L = -x_1 - (F0/k_L)^(1/a_L)``; every ball must be at rest (no strikers).

    The line must have a right wall, no external force of its own, a ball after the
    strikers, and those balls at rest; ``load`` > 0.

    Returns
    -------
    Line
        A new line, with ``position`` and ``force`` (one wall) or the left wall's
        ``gap`` (two walls) set.
    """
    load = float(load)
    if not (math.isfinite(load) and load > 0.0):
        raise ValueError(f"the load must be a finite number > 0, got {load!r}")
    if line.right is None:
        raise ValueError("precompression needs a right wall to push against")
    if np.any(line.force != 0.0):
        raise ValueError("precompression sets the external forces; the line has its own")
    between = line.left is not None
    k = strikers(line)
    if between and k:
        raise ValueError("precompression between two walls holds every ball at rest in "
                         "its static state: the line must start at rest (k = 0); ball 1 moves")
    if k >= line.n:
        raise ValueError("precompression needs a ball at rest after the strikers")
    moving = np.flatnonzero(line.velocity[k:])
    if moving.size:
        raise ValueError(f"precompression needs the balls after the strikers at rest; "
                         f"ball {k + int(moving[0]) + 1} moves")
    x = _resting(line, k, np.full(line.n - 1 - k, load), load)
    if between:
        left = line.left
        gap = -x[0] - (load / left.stiffness) ** (1.0 / left.alpha)
        return replace(line, position=x, left=replace(left, gap=float(gap)))
    x[:k] = line.position[:k] + x[k]
    force = np.zeros(line.n)
    force[k] = load
    return replace(line, force=force, position=x)


def weigh(line: Line, gravity: float) -> Line:
    """``line`` under its weight: a force ``m_n g`` on every ball, along the line towards
    ball N (+x), which keeps acting during the run; with a right wall (the floor), the
    balls after the strikers start at rest in their static state on it.

    Ball N rests on the floor and every ball on the one below it: contact j (balls j
    and j+1, j >= K+1) carries the weight of balls K+1..j above it, and the floor that
    of them all, W = g sum m. The force law gives the positions exactly, from the floor
    up (as ``precompress`` does for a uniform load):

        x_N = g_R + (W/k_R)^(1/a_R),   x_j = x_{j+1} + g_j + (W_j/k_j)^(1/a_j)

    The strikers (balls 1..K, ``strikers``) keep their velocities and are moved by
    x_{K+1}, so that they meet ball K+1 as they would without the load (they fall as
    they come: their weight acts on them too). Without a right wall, or without a ball
    at rest after the strikers, the balls only get their weights: the line falls.

    The line must have no external force of its own; ``gravity`` > 0 (an acceleration,
    in the line's units: m/s^2 for a line in SI).
    """
    g = float(gravity)
    if not (math.isfinite(g) and g > 0.0):
        raise ValueError(f"gravity must be a finite number > 0, got {gravity!r}")
    if np.any(line.force != 0.0):
        raise ValueError("gravity sets the external forces (the balls' weights); the line "
                         "has its own")
    weight = g * np.asarray(line.mass, dtype=float)
    k = strikers(line)
    if line.right is None or k >= line.n or np.any(line.velocity[k:] != 0.0):
        return replace(line, force=weight)
    # contact j (0-based, balls j and j+1) carries balls k..j; the floor all of them
    above = np.cumsum(weight[k:])
    x = _resting(line, k, above[:-1], above[-1])
    x[:k] = line.position[:k] + x[k]
    return replace(line, force=weight, position=x)
