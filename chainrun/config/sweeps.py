"""Sweeps: the keys a ``[sweep]`` table may vary (generator fields such as
``chain.mass.seed`` and replicas included), each combination's data, its run id, and
the hash of its resolved configuration that makes a sweep resumable.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import Any

from pydantic_core import PydanticCustomError

from chainrun.check import check_rtol
from chainrun.config.drives import SINE_KEYS, DriveSpec
from chainrun.config.problems import Issue, check_int, key_text, suggest
from chainrun.config.schema import (RULES, SCALAR_CHECKS, Chain, Output,
                                    SolverSettings, WallSettings)
from chainrun.errors import show_value
from chainrun.generators import Values
from chainrun.solver import DEFAULT_RTOL

#: Keys a ``[sweep]`` table may vary, and the type of their values.
SWEEPABLE_KEYS: dict[str, type] = {
    "chain.n": int,
    "chain.k": int,
    "chain.alpha": float,
    "chain.mass": float,
    "chain.stiffness": float,
    "chain.gap": float,
    "chain.force": float,
    "chain.speed": float,
    "chain.precompression": float,
    "chain.gravity": float,
    "chain.diameter": float,
    "chain.damping": float,
    "chain.damping_exponent": float,
    "chain.restitution": float,
    "chain.restitution_speed": float,
    "walls.left.stiffness": float,
    "walls.left.alpha": float,
    "walls.left.gap": float,
    "walls.left.damping": float,
    "walls.left.damping_exponent": float,
    "walls.left.restitution": float,
    "walls.left.restitution_speed": float,
    "walls.right.stiffness": float,
    "walls.right.alpha": float,
    "walls.right.gap": float,
    "walls.right.damping": float,
    "walls.right.damping_exponent": float,
    "walls.right.restitution": float,
    "walls.right.restitution_speed": float,
    **{f"walls.{side}.motion.{key}": float for side in ("left", "right") for key in SINE_KEYS},
    "solver.rtol": float,
    "solver.t_end": float,
    "solver.max_events": int,
}

#: Most runs a sweep may have.
MAX_RUNS = 10_000
#: Most snapshots (runs times snapshot times) an experiment may ask for in all.
MAX_SNAPSHOTS = 10_000_000

#: A generator table's numeric keys that a sweep may vary, ``"chain.<key>.<field>"``
#: (``"chain.mass.seed" = [1, 2, 3]``), and their type.
GENERATOR_FIELDS: dict[str, type] = {
    "seed": int, "low": float, "high": float, "median": float, "sigma": float,
    "taper": float, "start": float, "value": float,
}
#: The ``[sweep]`` key that asks for that many runs of the line, each drawing its
#: random values with the file's seeds plus the run's replica number (0, 1, ...).
REPLICAS = "replicas"
#: Most replicas a sweep may ask for (each is a run).
MAX_REPLICAS = 10_000


def _generator_key(key: str) -> tuple[str, str] | None:
    """``("mass", "seed")`` for ``"chain.mass.seed"``: a generator's field of a per-ball
    or per-contact key of the chain; None for any other key."""
    parts = key.split(".")
    if (len(parts) == 3 and parts[0] == "chain" and parts[1] in RULES
            and parts[2] in GENERATOR_FIELDS):
        return parts[1], parts[2]
    return None


def sweep_type(key: str) -> type | None:
    """The type of a sweep key's values, or None for a key that cannot be swept."""
    if key in SWEEPABLE_KEYS:
        return SWEEPABLE_KEYS[key]
    generator = _generator_key(key)
    return None if generator is None else GENERATOR_FIELDS[generator[1]]


#: The tables of an experiment and their models: a key of one of them that cannot be
#: swept is said to be one, not an unknown key.
_TABLES = {"chain": Chain, "walls.left": WallSettings, "walls.right": WallSettings,
           "output": Output, "solver": SolverSettings}


def _not_sweepable(key: str) -> str:
    """Why ``key`` cannot be swept: a key of the experiment that is not among the
    sweepable ones (with those of its table), or no key at all (with the closest)."""
    table, _, name = key.rpartition(".")
    model = _TABLES.get(table)
    if model is not None and name in model.model_fields:
        same = [k for k in SWEEPABLE_KEYS if k.rpartition(".")[0] == table]
        return (f"'{key}' cannot be swept" + (f" (of {table}, these can: {', '.join(same)})"
                                               if same else ""))
    return f"unknown key '{key}'{suggest(key, [*SWEEPABLE_KEYS, REPLICAS])}"


def _flatten_sweep(table: Mapping[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """``{"chain": {"k": [...]}}`` (TOML's unquoted ``chain.k = [...]``) as ``chain.k``.

    At most three levels are unfolded (sweepable keys have two or three parts, as
    ``walls.right.gap`` or ``chain.mass.seed``), so a deep or cyclic table (YAML
    aliases) is reported as an unknown key rather than recursed into.
    """
    items: list[tuple[str, Any]] = []
    for key, value in table.items():
        dotted = f"{prefix}{key_text(key)}"
        if (isinstance(value, Mapping) and prefix.count(".") < 2
                and (not prefix or dotted in ("walls.left", "walls.right")
                     or (prefix == "chain." and dotted.removeprefix("chain.") in RULES))):
            items.extend(_flatten_sweep(value, dotted + "."))
        else:
            items.append((dotted, value))
    return items


def check_sweep(value: Any) -> tuple[dict[str, tuple[Any, ...]], set[str], list[Issue]]:
    """The valid entries of a sweep table, every sweepable key it names, and its issues."""
    if value is None:
        return {}, set(), []
    if not isinstance(value, Mapping):
        return {}, set(), [Issue(f"expected a table, got {show_value(value)}")]
    valid: dict[str, tuple[Any, ...]] = {}
    named: set[str] = set()
    issues: list[Issue] = []
    for key, values in _flatten_sweep(value):
        if key == REPLICAS:
            try:
                count = check_int(values)
            except PydanticCustomError:
                count = 0
            if not 1 <= count <= MAX_REPLICAS:
                issues.append(Issue(f"expected a number of runs from 1 to {MAX_REPLICAS}, "
                                    f"got {show_value(values)}", (key,)))
            else:
                named.add("replica")
                valid["replica"] = tuple(range(count))
            continue
        if sweep_type(key) is None:
            issues.append(Issue(_not_sweepable(key)))
            continue
        sub = (key,)
        if key in named:  # "chain.k" and chain = {k = ...} in one table
            issues.append(Issue("given twice", sub))
            valid.pop(key, None)
            continue
        named.add(key)
        if not isinstance(values, (list, tuple)):
            issues.append(Issue(f"expected a list of values, got {show_value(values)}", sub))
            continue
        if not values:
            issues.append(Issue("must list at least one value", sub))
            continue
        check = SCALAR_CHECKS[sweep_type(key)]
        clean: list[Any] = []
        ok = True
        for position, item in enumerate(values):
            try:
                x = check(item)
            except PydanticCustomError as exc:
                ok = False
                issues.extend(
                    i._replace(reason=f"{i.reason} at position {position}", sub=sub)
                    for i in exc.context["issues"]
                )
                continue
            if x in clean:
                ok = False
                issues.append(Issue(f"duplicate value {x!r} at position {position}", sub))
            clean.append(x)
        if ok:
            valid[key] = tuple(clean)
    seeds = [key for key in valid if key.endswith(".seed")]
    if "replica" in valid and seeds:
        issues.append(Issue(f"give replicas or a sweep of seeds ({seeds[0]}), not both",
                            (REPLICAS,)))
        valid.pop("replica")
    return valid, named, issues


def _short(key: str) -> str:
    """A swept key as a run id names it: ``k`` for ``chain.k``, ``right_gap`` for
    ``walls.right.gap``, ``mass_seed`` for ``chain.mass.seed``."""
    if key.startswith("walls.") or _generator_key(key):
        return "_".join(key.split(".")[1:])
    return key.split(".")[-1]


def run_label(overrides: Mapping[str, Any], sep: str = ", ") -> str:
    """``"n=100, k=3"``: the short name of each swept key with its value."""
    return sep.join(f"{_short(key)}={value}" for key, value in overrides.items())


#: Longest run id, well inside a file name's 255 bytes with its suffixes.
MAX_RUN_ID = 200


def make_run_id(overrides: Mapping[str, Any]) -> str:
    """The run's name and file name: ``"n=100_k=3"``, or ``"run"`` without a sweep.

    An id longer than MAX_RUN_ID (a sweep over many keys) keeps the pairs that fit and
    ends with ``hash=`` and 16 hex digits of the whole id, which keeps it unique.
    """
    full = run_label(overrides, "_") or "run"
    if len(full) <= MAX_RUN_ID:
        return full
    tail = "hash=" + hashlib.sha256(full.encode()).hexdigest()[:16]
    kept = ""
    for key, value in overrides.items():
        pair = f"{_short(key)}={value}"
        if len(kept) + len(pair) + 1 + len(tail) + 1 > MAX_RUN_ID:
            break
        kept += pair + "_"
    return kept + tail


def _plain_table(value: Any) -> Any:
    """A generator table as a plain dict (a checked one, ``Values``, is JSON text), and
    a checked drive as the table or list the file holds."""
    if isinstance(value, Values) and value.table is not None:
        return json.loads(value.table)
    if isinstance(value, DriveSpec):
        return value.to_json()
    return value


def _replica(chain: Any, number: int) -> Any:
    """The chain's tables with each random generator's seed moved on by ``number``: the
    ``number``-th replica's line (the 0th is the file's own)."""
    if not isinstance(chain, Mapping):
        return chain
    out = dict(chain)
    for key, value in chain.items():
        table = _plain_table(value)
        if (isinstance(table, Mapping) and "random" in table
                and isinstance(table.get("seed"), int) and not isinstance(table["seed"], bool)):
            out[key] = {**table, "seed": table["seed"] + number}
    return out


def _random_keys(chain: Any) -> list[str]:
    """The chain's keys whose values are drawn at random (a generator table's)."""
    if not isinstance(chain, Mapping):
        return []
    return [key for key, value in chain.items()
            if isinstance(_plain_table(value), Mapping) and "random" in _plain_table(value)]


def set_key(data: dict[str, Any], dotted: str, value: Any) -> None:
    """Set ``data["chain"]["k"]`` for ``"chain.k"`` (``data["walls"]["right"]["gap"]``
    for ``"walls.right.gap"``, and the field of a generator table for
    ``"chain.mass.seed"``), creating missing tables; ``"replica"`` moves the seeds of
    the chain's random generators on by ``value``."""
    if dotted == "replica":
        data["chain"] = _replica(data.get("chain"), value)
        return
    head, _, rest = dotted.partition(".")
    if data.get(head) is None:
        data[head] = {}
    current = _plain_table(data[head])
    if not isinstance(current, Mapping):
        return
    inner = dict(current)
    if "." in rest:
        set_key(inner, rest, value)
    else:
        inner[rest] = value
    data[head] = inner


def checked_config(config: dict[str, Any]) -> dict[str, Any]:
    """A run's resolved ``config`` with ``solver.rtol`` at its check's tolerance
    (``chainrun.check.check_rtol``): the configuration of its check run."""
    solver = config.get("solver") or {}
    rtol = check_rtol(solver.get("rtol", DEFAULT_RTOL))
    return {**config, "solver": {**solver, "rtol": rtol}}


def config_hash(config: dict[str, Any]) -> str:
    """sha256 (hex) of a run's resolved ``config``, as ``RunSpec.config_hash``."""
    return hashlib.sha256(json.dumps(config, sort_keys=True, separators=(",", ":"))
                          .encode()).hexdigest()


def canonical_json(config: dict[str, Any], times_json: str) -> str:
    """``json.dumps(config, sort_keys=True, separators=(",", ":"))``, with the (long) list
    ``config["output"]["times"]`` given already serialised as ``times_json``.

    A quote inside a JSON string is always escaped, and no other table has a key
    ``times``, so ``"times":[]`` can only occur as the real key.
    """
    stub = {**config, "output": {**config["output"], "times": []}}
    text = json.dumps(stub, sort_keys=True, separators=(",", ":"))
    marker = '"times":[]'
    assert text.count(marker) == 1
    return text.replace(marker, f'"times":{times_json}')


def generator_sweep_issues(valid: dict[str, tuple], chain: Any,
                           walls: Any = None) -> list[Issue]:
    """Sweeps of a generator's field, or replicas, on a chain without such a table, and
    of a wall motion's key where the motion is not one sine (the entries are dropped
    from ``valid``)."""
    issues = []
    for key in list(valid):
        generator = _generator_key(key)
        if generator is not None and isinstance(chain, Mapping) and not isinstance(
                chain.get(generator[0]), Mapping):
            issues.append(Issue(f"chain.{generator[0]} is not a generator table "
                                f"(e.g. {{random = \"uniform\", ..., seed = 1}}): "
                                f"there is no {generator[1]} to sweep", (key,)))
            valid.pop(key)
    for key in list(valid):
        parts = key.split(".")
        if len(parts) == 4 and parts[2] == "motion" and isinstance(walls, Mapping):
            wall = walls.get(parts[1])
            motion = _plain_table(wall.get("motion")) if isinstance(wall, Mapping) else None
            if not (isinstance(motion, Mapping) and "file" not in motion):
                issues.append(Issue(f"walls.{parts[1]}.motion is not one sine table "
                                    f"{{amplitude, frequency, ramp}}: there is no "
                                    f"{parts[3]} to sweep", (key,)))
                valid.pop(key)
    if "replica" in valid and isinstance(chain, Mapping) and not _random_keys(chain):
        issues.append(Issue("the chain draws no random values (a table with random = "
                            "...): its replicas would be one run", (REPLICAS,)))
        valid.pop("replica")
    return issues
