"""The line a run's chain and walls describe: their keys checked against each other,
their values expanded into arrays (every value checked, by index), and the ``Line``
built from them by ``chainrun.solver.build``.

``line_of`` is the one way from the file's models to a ``Line``; ``line_problems``
reports what is wrong with one sweep combination's line, and ``needs_t_end`` whether it
needs a stop time.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from chainrun import generators
from chainrun.config.problems import Problem, key_path
from chainrun.config.schema import CHECK_MAX_N, RULES, SI_KEYS, Chain, Walls, rule_reason
from chainrun.errors import show_value, suggest
from chainrun.generators import Values, ValuesError
from chainrun.materials import MATERIALS
from chainrun.solver import Line
from chainrun.solver.build import BuildError, Dissipation, Spheres, WallSpec, build_line
from chainrun.solver.model import strikers


class LineError(Exception):
    """Problems building a line, as ``key: reason`` problems."""

    def __init__(self, problems: list[Problem]):
        super().__init__("; ".join(p.line() for p in problems))
        self.problems = problems


#: Keys whose single number is handed to the line as it is (``Line.make`` spreads it
#: over every ball or contact without an array of its own).
_AS_NUMBER = ("mass", "stiffness", "alpha", "gap", "force")


def _expanded(chain: Chain, key: str, size: int, problems: list[Problem],
              prefix: str = "chain") -> Any:
    """The values of ``chain.<key>`` expanded to ``size`` and checked (None if absent
    or wrong; the problem is added to ``problems``). A single number of a key of
    ``_AS_NUMBER`` stays a number: it was checked as the file was read."""
    value = getattr(chain, key)
    if value is None:
        return None
    if key in _AS_NUMBER and isinstance(value, float):
        return value
    values = value if isinstance(value, Values) else Values(scalar=value)
    try:
        a = generators.expand(values, size)
    except ValuesError as exc:
        problems.append(Problem(key_path((prefix, key) + exc.sub), exc.reason))
        return None
    if key == "material":
        unknown = [i for i, name in enumerate(a) if name not in MATERIALS]
        if unknown:
            i = unknown[0]
            problems.append(Problem(f"{prefix}.{key}[{i}]", f"unknown material "
                                    f"{show_value(a[i])}{suggest(str(a[i]), MATERIALS)} "
                                    f"(known: {', '.join(MATERIALS)})"))
            return None
        return a
    bad = ~np.isfinite(a)
    low, strict, high, _ = RULES[key]
    with np.errstate(invalid="ignore"):
        if low is not None:
            bad |= (a <= low) if strict else (a < low)
        if high is not None:
            bad |= (a >= high) if key == "poisson" else (a > high)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        x = float(a[i])
        reason = "must be finite" if not math.isfinite(x) else rule_reason(key, x)
        problems.append(Problem(f"{prefix}.{key}[{i}]", f"{reason}, got {show_value(x)}"))
        return None
    return a


def _velocities(chain: Chain, problems: list[Problem]) -> np.ndarray | None:
    if chain.velocity is not None:
        return _expanded(chain, "velocity", chain.n, problems)
    v = np.zeros(chain.n)
    v[:chain.k] = 1.0 if chain.speed is None else chain.speed
    return v


def _dissipation(settings: Any, damping, restitution, exponent) -> Dissipation:
    return Dissipation(damping=damping, exponent=exponent, restitution=restitution,
                       law=settings.damping_law, speed=settings.restitution_speed)


def _key(key: str) -> str:
    """A key of ``chainrun.solver.build`` (relative to the line) as the file's."""
    if key.startswith(("left.", "right.")):
        return "walls." + key
    return f"chain.{key}" if key else "chain"


def line_of(chain: Chain, walls: Walls, units: str) -> Line:
    """The ``Line`` an experiment's chain and walls describe, in its ``units``.

    In SI, balls given by ``diameter`` and a ``material`` (a preset of
    ``chainrun.materials`` or ``young``, ``poisson`` and ``density``) are real spheres
    (``chainrun.solver.build.Spheres``); a wall of a ``material`` is a flat body of it,
    and a wall with neither stiffness nor material is of the end ball's material. With
    ``precompression`` the resting balls start at equilibrium under that load: pushed
    by a constant force against the right wall, or, between two walls, held by them,
    the left wall placed where every contact carries the load. With ``gravity`` every
    ball weighs m g towards ball N, and on a right wall (the floor) the resting balls
    start at equilibrium under their weights (``chainrun.solver.model.weigh``).

    Raises
    ------
    LineError
        Every problem found, each naming its key (and index).
    """
    problems: list[Problem] = []
    n = chain.n
    real = [key for key in SI_KEYS if getattr(chain, key) is not None]
    wall_real = [side for side in ("left", "right")
                 if getattr(walls, side) is not None and getattr(walls, side).material]
    if units != "si":
        problems += [Problem(f"chain.{key}", 'needs units = "si" (real spheres)')
                     for key in real]
        problems += [Problem(f"walls.{side}.material", 'needs units = "si" (real spheres)')
                     for side in wall_real]
        if problems:
            raise LineError(problems)
    spheres = None
    kw: dict[str, Any] = {}
    if real:
        explicit = [key for key in ("young", "poisson", "density")
                    if getattr(chain, key) is not None]
        if chain.material is not None and explicit:
            problems += [Problem(f"chain.{key}", "give chain.material or explicit constants, "
                                 "not both") for key in explicit]
        elif chain.material is None and len(explicit) < 3:
            problems += [Problem(f"chain.{key}", "required with explicit constants "
                                 "(or give chain.material)")
                         for key in ("young", "poisson", "density") if key not in explicit]
        if chain.diameter is None:
            problems.append(Problem("chain.diameter", "required with a material (m)"))
        for key in ("mass", "stiffness", "alpha"):
            if getattr(chain, key) is not None:
                problems.append(Problem(f"chain.{key}", "set by the material and diameter "
                                        "(Hertz, alpha = 3/2); give one or the other"))
        if problems:
            raise LineError(problems)
        diameter = _expanded(chain, "diameter", n, problems)
        names = None
        if chain.material is not None:
            names = _expanded(chain, "material", n, problems)
            if names is not None:
                young = np.array([MATERIALS[m].young for m in names])
                poisson = np.array([MATERIALS[m].poisson for m in names])
                density = np.array([MATERIALS[m].density for m in names])
        else:
            young = _expanded(chain, "young", n, problems)
            poisson = _expanded(chain, "poisson", n, problems)
            density = _expanded(chain, "density", n, problems)
        if problems:
            raise LineError(problems)
        spheres = Spheres(diameter, young, poisson, density, "" if names is None else names)
    else:
        for key in ("mass", "stiffness", "alpha"):
            size = n if RULES[key][3] == "ball" else n - 1
            kw[key] = _expanded(chain, key, size, problems)
    kw["gap"] = _expanded(chain, "gap", n - 1, problems)
    force = kw["force"] = _expanded(chain, "force", n, problems)
    velocity = _velocities(chain, problems)

    built: dict[str, WallSpec] = {}
    for side in ("left", "right"):
        spec = getattr(walls, side)
        if spec is None:
            continue
        if spec.material is not None and spheres is None:
            problems.append(Problem(f"walls.{side}.material", "needs the balls' materials "
                                    "(chain.material and chain.diameter)"))
            continue
        if spec.material is not None or (spec.stiffness is None and spheres is not None):
            if spec.stiffness is None and spec.alpha is not None and spec.material is None:
                problems.append(Problem(f"walls.{side}.alpha", "a wall of the end ball's "
                                        "material is Hertz (3/2); give its stiffness too"))
                continue
            wall = MATERIALS[spec.material] if spec.material else None
            built[side] = WallSpec(spec.gap, young=wall.young if wall else None,
                                   poisson=wall.poisson if wall else None)
            continue
        if spec.stiffness is None and units == "si":
            problems.append(Problem(f"walls.{side}.stiffness", "required in SI (N/m^alpha), "
                                    "or give the wall a material"))
            continue
        alpha = spec.alpha
        if alpha is None and n == 1 and not real:
            # one ball: no contact next to it, but the chain's alpha
            if not isinstance(chain.alpha, float):
                problems.append(Problem(f"walls.{side}.alpha", "required: a line of one "
                                        "ball has no contact whose exponent the wall could "
                                        "take (or give chain.alpha)"))
                continue
            alpha = chain.alpha
        built[side] = WallSpec(spec.gap, 1.0 if spec.stiffness is None else spec.stiffness,
                               alpha)
    if chain.drive is not None and n == 1 and walls.left is None and walls.right is None:
        problems.append(Problem("chain.drive", "a lone ball without walls touches nothing: "
                                "its drive alone moves it, with nothing to solve"))
    drives = []
    for spec in chain.drive or ():
        if spec.ball > n:
            where = ("chain.drive.ball" if spec.index is None
                     else f"chain.drive[{spec.index}].ball")
            problems.append(Problem(where, f"ball {spec.ball} is beyond chain.n ({n})"))
        drives.append((spec.ball - 1, spec.drive))
    if problems:
        raise LineError(problems)

    size = n - 1
    damping = _expanded(chain, "damping", size, problems)
    restitution = _expanded(chain, "restitution", size, problems)
    exponent = _expanded(chain, "damping_exponent", size, problems)
    if problems:
        raise LineError(problems)
    for side, spec in built.items():
        settings = getattr(walls, side)
        built[side] = WallSpec(
            spec.gap, spec.stiffness, spec.alpha, spec.young, spec.poisson,
            _dissipation(settings,
                         None if settings.damping is None else np.array([settings.damping]),
                         None if settings.restitution is None
                         else np.array([settings.restitution]),
                         settings.damping_exponent),
            None if settings.motion is None else settings.motion.drive)
    conflict = None  # keys that precompression and gravity set themselves
    if chain.gravity and (chain.precompression or (force is not None and np.any(force != 0.0))):
        conflict = Problem("chain.gravity", "sets the external forces itself (the balls' "
                           "weights); leave chain.force and chain.precompression out")
    elif chain.precompression:
        if force is not None and np.any(force != 0.0):
            conflict = Problem("chain.precompression", "sets the external force itself; "
                               "leave chain.force out")
        elif walls.left is not None and walls.right is not None and walls.left.gap != 0.0:
            conflict = Problem("walls.left.gap", "set by chain.precompression between two "
                               "walls (the left wall is placed where every contact carries "
                               "the load); leave it out")
    try:
        line = build_line(n, velocity, spheres=spheres,
                          dissipation=_dissipation(chain, damping, restitution, exponent),
                          left=built.get("left"), right=built.get("right"), drives=drives,
                          precompression=None if conflict else chain.precompression,
                          gravity=None if conflict else chain.gravity, **kw)
    except BuildError as exc:
        raise LineError([Problem(_key(key), reason) for key, reason in exc.problems]) from None
    if conflict:  # after the line's own problems, as its precompression would be
        raise LineError([conflict])
    return line


def needs_t_end(chain: Chain, walls: Walls, t_end: float | None,
                line: Line | None = None) -> list[Problem]:
    """The problem of a line with no terminal state run without a stop time.

    Whether it has one is ``Line.has_terminal_state`` of its ``line`` when it is built;
    a line not built (too long to build as the file is read, or one whose values are
    wrong) is judged from its keys. The reasons are named by the keys that cause them.
    """
    if t_end is not None:
        return []
    reasons = []
    if chain.gravity:
        reasons.append("chain.gravity keeps pulling")
    elif chain.precompression and walls.left is None:
        reasons.append("chain.precompression keeps pushing")
    elif isinstance(chain.force, float) and chain.force != 0.0:
        reasons.append("chain.force keeps doing work")
    elif isinstance(chain.force, Values) and chain.force.items is not None and any(
            chain.force.items):
        reasons.append("chain.force keeps doing work")
    if walls.left is not None and walls.right is not None:
        reasons.append("the line is held between two walls")
    for side in ("left", "right"):
        wall = getattr(walls, side)
        if wall is not None and wall.motion is not None:
            reasons.append(f"walls.{side}.motion drives it")
    if chain.drive is not None:
        reasons.append("chain.drive drives it")
    if line is not None:
        if line.has_terminal_state:
            return []
        if not reasons:  # a generated force, seen only once expanded
            reasons.append("chain.force keeps doing work")
    if not reasons:
        return []
    return [Problem("solver.t_end", f"required: {' and '.join(reasons)}, so the run "
                    "has no terminal state", frozenset({"chain.force",
                                                        "chain.precompression",
                                                        "chain.gravity"}))]


def is_paper(chain: Chain, walls: Walls, units: str) -> bool:
    """Whether a run's line is the paper's: only n, k and a scalar alpha, in its units."""
    return chain.is_paper and walls == Walls() and units == "paper"


def line_problems(chain: Chain, walls: Walls, units: str, t_end: float | None,
                  to_run: bool = True) -> tuple[list[Problem], Line | None]:
    """The problems of the line one combination describes (values out of range, by
    index; keys that conflict; a stop time it needs), and the line, built unless it is
    the paper's or longer than ``CHECK_MAX_N`` (None then, or when it has problems)."""
    if not to_run:
        t_end = math.inf  # analysed at rest, never run: no stop time is needed
    problems: list[Problem] = []
    line = None
    if not is_paper(chain, walls, units) and chain.n <= CHECK_MAX_N:
        try:
            line = line_of(chain, walls, units)
        except LineError as exc:
            problems = exc.problems
    return needs_t_end(chain, walls, t_end, line) + problems, line


def k_and_alpha(chain: Chain, walls: Walls, line: Line | None) -> tuple[int, float]:
    """K, the leading balls that move (``strikers`` of the ``line``, when it is built),
    and the contacts' exponent if it is one number (NaN if it varies, or if there is
    no contact): what summaries and the index show of a run."""
    if line is not None:
        k = strikers(line)
    elif chain.velocity is None:
        k = chain.k
    elif isinstance(chain.velocity, float):
        k = chain.n if chain.velocity != 0.0 else 0
    else:  # a line too long to build as the file is read: known when it runs
        k = 0
    a = chain.alpha
    if a is None and chain.n == 1 and all(getattr(chain, key) is None for key in SI_KEYS):
        # one ball: its walls' exponents alone (each given, see line_of)
        given = {w.alpha for w in (walls.left, walls.right) if w is not None}
        alpha = given.pop() if len(given) == 1 and None not in given else math.nan
    elif a is None:
        alpha = 1.5  # Hertz, from the material
    elif isinstance(a, float):
        alpha = a
    elif a.items is not None:
        alpha = a.items[0] if len(set(a.items)) == 1 else math.nan
    else:
        table = json.loads(a.table)
        alpha = table["value"] if set(table) == {"value"} else math.nan
    return int(k), float(alpha)
