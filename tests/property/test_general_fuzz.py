"""Fuzzing the general model: whole random lines, run and checked against an oracle.

Hypothesis draws experiment files of any line the model describes (``general_lines``):
1 to 12 balls; masses, stiffnesses and exponents (1 to 3) per contact; gaps and
overlaps; strikers of any mass and speed, head-on, or none (a line at rest); walls on
either side, elastic or damped; constant forces and a precompression, against a wall
or between two (with ``solver.t_end``); every damping law, given as a damping or as a
restitution; in SI, materials and diameters. Each file is read as ``chainrun
simulate`` reads it (``parse_experiment``), and its line run as a run runs it
(``simulate`` with the file's settings), with snapshots.

Every drawn file is valid, and every run must reach its terminal state or its
``t_end`` within ``TIME_BOUND`` seconds, or stop with a named outcome and a one-line
message; nothing else may escape (``test_every_line_runs``). On every line that ends
well, independently of the solver's own diagnostics:

* momentum: ``sum m v`` at the end is the initial one plus the external forces'
  impulse ``sum f t`` and the walls' impulses;
* energy: kinetic + contact + dissipated, less the forces' work, is the initial
  energy (``reference.line_energy``);
* at a terminal state nothing approaches: velocities non-decreasing along the line,
  and away from each wall (to the velocity floor).

The oracle (``test_lines_agree_with_the_reference``): the tests' independent scipy
solver (``reference.reference_line``) runs the same line. chainrun's final velocities
and snapshots must agree with it to ``TOL["reference"]`` wherever the line is well
conditioned: where the reference's own answers at two tolerances (its default,
1e-13, and 1e-12) agree to ``TOL["conditioning"]``. The second answer is computed
only where the first disagrees with chainrun (a line on which the two solvers agree
needs no excuse); the lines whose answer is steered by rounding (a near three-body
collision turns 1e-13 into 1e-9) are counted, as are those the reference cannot run
(it gives up after 20,000 events or on a step it cannot take).

Some lines also go through ``chainrun simulate`` (``test_lines_through_the_command``):
exit status 0, no traceback, and the run file holds the library's run bit for bit.

The default is a few hundred lines for ``make test``, the same ones on every run (the
suite's hypothesis profile, ``conftest.py``). A long run draws new ones::

    CHAINRUN_FUZZ_EXAMPLES=10000 .venv/bin/python -m pytest -n 2 \
        tests/property/test_general_fuzz.py

gives each of the three tests that many lines; the number tried and compared is printed
at the end (``fuzz: N cases tried``), and the lines that failed are printed in full.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from chainrun.config import parse_experiment
from chainrun.materials import MATERIALS
from chainrun.solver import Outcome, simulate, velocity_floor
from chainrun.solver.restitution import LAWS
from reference import line_energy, reference_line

LONG = int(os.environ.get("CHAINRUN_FUZZ_EXAMPLES", "0") or 0)

#: Seconds a run of one drawn line may take (they take milliseconds).
TIME_BOUND = 20.0

#: One table of tolerances, relative to the line's scales (``Line.scales()``: its
#: velocity, length, energy and momentum are of order 1 there).
TOL = {
    # chainrun against the reference, velocities (and positions: relative to the
    # length the line travels, L (1 + t/T)); the reference is trusted to 1e-10 on such
    # lines, chainrun at its default rtol 1e-12 to ~1e-10, collisions amplify both
    "reference": 1e-7,
    # the reference at rtol 1e-13 and 1e-12: where it differs from itself by more, the
    # answer is steered by rounding and is not compared
    "conditioning": 1e-9,
    "momentum": 1e-11,
    "energy": 1e-9,
}


class Deadline(Exception):
    """A run took longer than ``TIME_BOUND``."""


# --- drawing lines ---------------------------------------------------------------------

def _log_uniform(low: float, high: float):
    return st.floats(math.log10(low), math.log10(high)).map(lambda e: float(10.0 ** e))


def _per(draw, size: int, values, scalar_too: bool = True):
    """One value for all (sometimes) or a list of ``size`` of ``values``."""
    if scalar_too and draw(st.booleans()):
        return draw(values)
    return draw(st.lists(values, min_size=size, max_size=size))


def _forces(scale: float):
    """0, or a force of either sign from 1e-6 of ``scale`` to ``scale``. A smaller one
    (a subnormal, say) moves a line by less than its rounding over the times drawn
    here, and sets its scales alone on a line at rest; such forces have tests of their
    own in test_general_model.py (``test_forces_as_small_as_a_float_can_be``,
    ``test_a_line_at_rest_under_a_force_below_its_rounding``,
    ``test_a_ball_pressed_on_a_linear_wall_by_a_force_below_its_rounding``)."""
    return st.just(0.0) | st.builds(lambda f, sign: sign * f, st.floats(1e-6 * scale, scale),
                                    st.sampled_from([1.0, -1.0]))


ALPHAS = st.sampled_from([1.0, 1.5, 2.0, 2.5, 3.0]) | st.floats(1.0, 3.0)


def _dissipation(draw, si: bool, per_contact: int | None):
    """A contact's (or a wall's, ``per_contact`` None) dissipation keys, or {}."""
    kind = draw(st.sampled_from(["elastic", "elastic", "damping", "law", "restitution"]))
    one = (lambda values: draw(values)) if per_contact is None else \
        (lambda values: _per(draw, per_contact, values))
    if kind == "elastic":
        return {}
    if kind == "restitution":
        law = draw(st.sampled_from(LAWS))
        keys = {"restitution": one(st.floats(0.2, 1.0)), "damping_law": law}
        if law != "tsuji":  # e holds at one impact speed
            keys["restitution_speed"] = draw(_log_uniform(0.05, 5.0) if si
                                             else _log_uniform(0.1, 3.0))
        return keys
    if si:  # eta in SI units is the line's own business: give it as a restitution
        return {"restitution": one(st.floats(0.5, 1.0)), "damping_law": "tsuji"}
    damping = one(st.just(0.0) | _log_uniform(1e-3, 3.0))
    if kind == "law":
        return {"damping": damping, "damping_law": draw(st.sampled_from(LAWS))}
    return {"damping": damping, "damping_exponent": draw(st.sampled_from([0.0, 0.25, 0.5])
                                                         | st.floats(0.0, 1.0))}


@st.composite
def general_lines(draw):
    """An experiment file's tables (a dict, valid) of a random general line, and
    ``horizon``: the span of its snapshot times in units of its time scale.

    ``solver.t_end`` and the snapshot times are set later, in units of the line's own
    time scale (``with_times``), where the line needs or draws them.
    """
    si = draw(st.integers(0, 3)) == 0
    n = draw(st.integers(1, 12))
    nc = n - 1
    chain: dict = {"n": n}
    doc: dict = {"name": "fuzz", "chain": chain}
    if si:
        doc["units"] = draw(st.sampled_from(["si", "SI"]))
        chain["diameter"] = _per(draw, n, st.floats(0.002, 0.05))
        if draw(st.integers(0, 3)) == 0:
            chain["young"] = _per(draw, n, _log_uniform(1e9, 6e11))
            chain["poisson"] = _per(draw, n, st.floats(0.0, 0.45))
            chain["density"] = _per(draw, n, _log_uniform(1000.0, 16000.0))
        else:
            chain["material"] = _per(draw, n, st.sampled_from(sorted(MATERIALS)))
        speeds = _log_uniform(0.01, 5.0)
    else:
        if draw(st.booleans()):
            chain["mass"] = _per(draw, n, _log_uniform(0.1, 10.0))
        if nc and draw(st.booleans()):
            chain["stiffness"] = _per(draw, nc, _log_uniform(0.1, 10.0))
        if nc or draw(st.booleans()):
            chain["alpha"] = _per(draw, max(nc, 1), ALPHAS, scalar_too=True) if nc \
                else draw(ALPHAS)
        speeds = _log_uniform(0.05, 10.0)
    if nc and draw(st.integers(0, 2)) == 0:
        chain["gap"] = draw(st.lists(st.just(0.0) | st.floats(0.01, 0.5)
                                     | st.floats(-0.05, -0.001), min_size=nc, max_size=nc))
        if si:
            chain["gap"] = [g * 1e-4 for g in chain["gap"]]  # 0.1 mm .. 50 um
    how = draw(st.sampled_from(["strikers", "strikers", "head-on", "velocities"]))
    if how == "strikers":  # k = 0: a line at rest (moved by its overlaps or forces)
        chain["k"] = draw(st.integers(0, n))
        speed = draw(speeds) * draw(st.sampled_from([1.0, 1.0, 1.0, -1.0]))
        if chain["k"] and (speed != 1.0 or draw(st.booleans())):
            chain["speed"] = speed
    elif how == "head-on":
        v = [0.0] * n
        v[0] = draw(speeds)
        if n > 1:
            v[-1] = -draw(speeds)
        chain["velocity"] = v
    else:
        chain["velocity"] = draw(st.lists(st.just(0.0) | speeds | speeds.map(lambda s: -s),
                                          min_size=n, max_size=n))
    if nc:
        chain.update(_dissipation(draw, si, nc))
    walls = {}
    for side in ("left", "right"):
        if draw(st.integers(0, 3)) == 0:
            wall: dict = {}
            if si:
                if draw(st.booleans()):
                    wall["material"] = draw(st.sampled_from(sorted(MATERIALS)))
            else:
                if draw(st.booleans()):
                    wall["stiffness"] = draw(_log_uniform(0.1, 10.0))
                if draw(st.booleans()) or (n == 1 and "alpha" not in chain):
                    wall["alpha"] = draw(ALPHAS)
            if draw(st.booleans()):
                wall["gap"] = draw(st.floats(0.0, 0.3)) * (1e-4 if si else 1.0)
            wall.update(_dissipation(draw, si, None))
            walls[side] = wall
    if walls:
        doc["walls"] = walls
    load = draw(st.sampled_from(["none", "none", "none", "force", "precompression"]))
    if load == "force":
        scale = 0.05 if si else 0.5
        chain["force"] = _per(draw, n, _forces(scale))
    elif load == "precompression" and "right" in walls and how == "strikers" \
            and chain["k"] < n:
        # against the right wall, the balls after the strikers at rest; between two
        # walls, every ball at rest and the left wall placed by the load
        if "left" in walls:
            chain["k"] = 0
            chain.pop("speed", None)
            walls["left"].pop("gap", None)
        chain["precompression"] = draw(st.floats(0.01, 1.0) if not si else
                                       _log_uniform(0.01, 10.0))
    return doc


def with_times(doc: dict, times, t_end):
    """``doc`` with its snapshot times and ``solver.t_end`` (where the line needs one,
    or ``t_end`` is drawn), given in units of the line's time scale, read as a file:
    its run's spec (``RunSpec``: the line, times, t_end, rtol)."""
    probe = {**doc, "solver": {"t_end": 1.0}}  # the line does not depend on them
    (spec,) = parse_experiment(_toml(probe), "toml", source="fuzz").runs()
    line = spec.line
    unit = line.scales().time
    if t_end is None and not line.has_terminal_state:
        t_end = 30.0
    times = sorted(t * unit for t in times if t_end is None or t <= t_end)
    doc = {**doc, "output": {"times": times}}
    if t_end is not None:
        doc["solver"] = {"t_end": t_end * unit}
    (spec,) = parse_experiment(_toml(doc), "toml", source="fuzz").runs()
    return spec


def _toml(doc: dict) -> str:
    """TOML text of ``doc`` (two levels of tables; values: numbers, strings, lists)."""
    def value(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(float(v)) if isinstance(v, float) else repr(v)

    lines = [f"{k} = {value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    for table, body in doc.items():
        if not isinstance(body, dict):
            continue
        if any(isinstance(v, dict) for v in body.values()):
            for sub, keys in body.items():
                lines.append(f"[{table}.{sub}]")
                lines += [f"{k} = {value(v)}" for k, v in keys.items()]
        else:
            lines.append(f"[{table}]")
            lines += [f"{k} = {value(v)}" for k, v in body.items()]
    return "\n".join(lines) + "\n"


#: Snapshot times and a drawn stop time, in units of the line's time scale.
SNAPSHOTS = st.lists(st.floats(0.0, 40.0), max_size=6)
T_END = st.none() | st.floats(0.5, 60.0)


# --- running and checking ----------------------------------------------------------------

def run(spec, slowest: list):
    """``simulate`` as a run of ``spec`` calls it, stopped after ``TIME_BOUND`` s;
    ``slowest[0]`` keeps the longest time a run took."""
    start = time.perf_counter()

    def hook(t):
        if time.perf_counter() > start + TIME_BOUND:
            raise Deadline(f"still running at t = {t:.6g} after {TIME_BOUND} s")

    sol = simulate(spec.line, spec.times, t_end=spec.t_end, rtol=spec.rtol,
                   max_events=spec.max_events, on_progress=hook)
    slowest[0] = max(slowest[0], time.perf_counter() - start)
    return sol


def check_run(line, sol, t_end) -> None:
    """What every run must satisfy: a named outcome, a one-line message; when it ended
    well, the balance of momentum and energy and (terminal) nothing approaching."""
    assert isinstance(sol.message, str) and sol.message.strip()
    assert len(sol.message.splitlines()) == 1, sol.message
    if not sol.outcome.ok:
        return
    sc = line.scales()
    v0, x0 = line.velocity, line.position
    v1, x1 = sol.final_velocity, sol.final_position
    assert np.all(np.isfinite(v1)) and np.all(np.isfinite(x1))
    if t_end is not None and not sol.terminal:
        assert sol.end_time == pytest.approx(t_end, rel=1e-12)
    # momentum: the forces' and the walls' impulses
    m = line.mass
    p0 = float(m @ v0) + float(np.sum(line.force)) * sol.end_time + float(np.sum(sol.wall_impulse))
    assert abs(float(m @ v1) - p0) <= TOL["momentum"] * sc.mass * sc.velocity * max(
        1.0, sol.end_time / sc.time), "momentum"
    # energy: kinetic + contact + dissipated - the forces' work
    e0, e1 = line_energy(line, x0, v0), line_energy(line, x1, v1)
    k0 = 0.5 * float(m @ (v0 * v0))
    # (the forces' potential -F.x is summed from terms |F x|, which its rounding is of)
    scale = max(k0, abs(e0 + float(line.force @ x0) - k0),
                abs(float(line.force @ (x1 - x0))),
                float(np.abs(line.force) @ (np.abs(x0) + np.abs(x1))), 1e-300)
    assert abs(e1 + sol.dissipated_energy - e0) <= TOL["energy"] * scale, (
        f"energy: {abs(e1 + sol.dissipated_energy - e0) / scale:.2e} of {scale:.3g}")
    if sol.terminal:
        floor = 2.0 * velocity_floor(sol.diagnostics.rtol) * sc.velocity
        assert np.all(np.diff(v1) >= -floor), "balls still approaching at the end"
        if line.right is not None:
            assert v1[-1] <= floor
        if line.left is not None:
            assert v1[0] >= -floor


def compare(line, sol, spec, counts: dict) -> str | None:
    """chainrun's final velocities and snapshots against the reference's; why they
    differ where the line is well conditioned (None if they agree, or it is not)."""
    kw = dict(t_max=spec.t_end, times=spec.times, max_events=20_000)
    try:
        ref = reference_line(line, **kw)
    except RuntimeError:
        counts["reference failed"] += 1
        return None
    if spec.t_end is None and not ref.terminal:
        counts["reference failed"] += 1
        return None
    sc = line.scales()
    # the reference declares no terminal state on a line with forces or between two
    # walls (chainrun does, where nothing moves at all: a line at rest between walls)
    if line.has_terminal_state and bool(ref.terminal) != bool(sol.terminal):
        return f"terminal: chainrun {sol.terminal}, reference {ref.terminal}"
    error = _difference(sol, ref, spec.times, sc)
    if error <= TOL["reference"]:
        counts["agreed"] += 1
        return None
    # they differ: is the answer itself steered by rounding? (the reference at 1e-12)
    coarse = reference_line(line, rtol=1e-12, **kw)
    own = _difference(coarse, ref, spec.times, sc)
    if own > TOL["conditioning"]:
        counts["steered by rounding"] += 1
        return None
    return (f"differs from the reference by {error:.2e} (relative to the line's scales), "
            f"which differs from itself at rtol 1e-12 by {own:.1e}")


def _difference(a, b, times, sc) -> float:
    """The largest difference of final velocities and snapshots of two runs, relative
    to the line's velocity scale (positions: to L (1 + t/T))."""
    dv = np.max(np.abs(a.final_velocity - b.final_velocity)) / sc.velocity
    if len(times):
        t = np.asarray(times)[:, None]
        dv = max(dv, np.max(np.abs(a.velocities - b.velocities)) / sc.velocity)
        dx = np.abs(a.positions - b.positions) / (sc.length * (1.0 + t / sc.time))
        dv = max(dv, float(np.max(dx)))
    return float(dv)


def _fuzz_settings(fast: int):
    return settings(max_examples=LONG or fast, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def _finish(record_property, tried: int, counts: dict, failures: list,
            slowest: float | None = None) -> None:
    record_property("fuzz_cases", tried)
    record_property("fuzz_detail", ", ".join(f"{n} {what}" for what, n in counts.items())
                    + ("" if slowest is None else f"; the slowest run took {slowest:.2f} s"))
    if failures:
        shown = "\n".join(f"- {why}\n  {doc!r}"
                           for doc, why in failures[:None if LONG else 20])  # a long run: all
        pytest.fail(f"{len(failures)} of {tried} lines failed:\n{shown}", pytrace=False)


@pytest.fixture(scope="module", autouse=True)
def _kernels():
    from chainrun.solver import load_kernels

    load_kernels()


def test_every_line_runs(record_property):
    """Every drawn line runs to its end, or stops with a named outcome, in time; every
    run that ends well balances momentum and energy (``check_run``)."""
    tried, failures, slowest = [0], [], [0.0]
    counts = {"terminal": 0, "stopped at t_end": 0, "failed with a message": 0}

    @_fuzz_settings(300)
    @given(doc=general_lines(), times=SNAPSHOTS, t_end=T_END)
    def one(doc, times, t_end):
        tried[0] += 1
        try:
            spec = with_times(doc, times, t_end)
            sol = run(spec, slowest)
            check_run(spec.line, sol, spec.t_end)
        except Exception as exc:
            failures.append((doc, f"{type(exc).__name__}: {exc}"))
            return
        counts[{Outcome.TERMINAL: "terminal", Outcome.STOP_TIME: "stopped at t_end"}.get(
            sol.outcome, "failed with a message")] += 1
        if not sol.outcome.ok:
            failures.append((doc, f"{sol.outcome.value}: {sol.message}"))

    one()
    _finish(record_property, tried[0], counts, failures, slowest[0])


def test_lines_agree_with_the_reference(record_property):
    """Every well-conditioned line ends as the independent reference solver says, to
    ``TOL["reference"]`` (``compare``)."""
    tried, failures, slowest = [0], [], [0.0]
    counts = {"agreed": 0, "steered by rounding": 0, "reference failed": 0,
              "not compared (too long for the quick run)": 0}

    @_fuzz_settings(40)
    @given(doc=general_lines(), times=SNAPSHOTS, t_end=T_END)
    def one(doc, times, t_end):
        tried[0] += 1
        try:
            spec = with_times(doc, times, t_end)
            line = spec.line
            sol = run(spec, slowest)
            if not sol.outcome.ok:
                raise AssertionError(f"{sol.outcome.value}: {sol.message}")
            if not LONG and sol.event_time.size > 40:
                counts["not compared (too long for the quick run)"] += 1
                return
            why = compare(line, sol, spec, counts)
        except Exception as exc:
            why = f"{type(exc).__name__}: {exc}"
        if why:
            failures.append((doc, why))

    one()
    _finish(record_property, tried[0], counts, failures, slowest[0])


def test_lines_through_the_command(record_property, tmp_path_factory):
    """The same files through ``chainrun simulate``: exit 0, no traceback, and the run
    file holds the library's run, bit for bit."""
    from click.testing import CliRunner

    from chainrun.cli import main
    from chainrun.store import read_run

    tried, failures = [0], []
    counts = {"ran": 0}

    @_fuzz_settings(30)
    @given(doc=general_lines(), times=SNAPSHOTS, t_end=T_END)
    def one(doc, times, t_end):
        tried[0] += 1
        try:
            spec = with_times(doc, times, t_end)
            folder = tmp_path_factory.mktemp("line")
            config = folder / "line.toml"
            config.write_text(spec.source_text)
            result = CliRunner().invoke(main, ["simulate", str(config), "-o",
                                               str(folder / "out")])
            output = result.stdout + result.stderr
            assert "Traceback" not in output, output
            assert result.exit_code == 0, output
            counts["ran"] += 1
            stored = read_run(folder / "out" / "run.h5")
            sol = run(spec, [0.0])
            assert np.array_equal(stored.final_velocity, sol.final_velocity)
            assert np.array_equal(stored.final_position, sol.final_position)
            assert stored.outcome == sol.outcome.value
        except Exception as exc:
            failures.append((doc, f"{type(exc).__name__}: {exc}"))

    one()
    _finish(record_property, tried[0], counts, failures)
