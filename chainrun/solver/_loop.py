"""The step loop: ``advance``, which runs the solver and evaluates its state.

The kernels own the numerics and nothing else: they never see files or Python
objects, and report through integer status codes (``_state.ST_*``) that ``_driver``
maps to named outcomes. ``advance`` is the one entry point that Python calls (cached,
see ``_jit``); everything else is a ``kernel`` linked into it. One entry point is one
compiled library to load at start-up: a snapshot or a sample of a few balls
(``_output._snapshot``, ``_sample``) is a task ``advance`` runs when ``ints[I_TASK]``
asks.

One pass of the loop does one of these: packs the compact arrays again after a change
of structure (``_clusters``), takes a snapshot due inside the last step, applies the
event or releases that the last step ended on (``_settle``), takes a collision due now
off the heap (``_heap``), jumps over free flight to the next predicted collision, or
takes one accepted step that ends on the earliest event found in it (``_stepping``). A
predicted collision that nothing else can reach while it lasts is taken whole (in
closed form, or a damped pair's own relative motion), and its end waits in the heap
(``_binary``, ``_pairs``, ``_pair_damped``): it costs no steps and does not hold back
the clusters' step size.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._binary import _seal, _sealed_end
from chainrun.solver._clusters import _rebuild, _unseal_at_end
from chainrun.solver._heap import _heap_pop, _heap_valid_top
from chainrun.solver._jit import entry, kernel
from chainrun.solver._output import _sample, _snapshot
from chainrun.solver._settle import _post_step
from chainrun.solver._state import (
    AGAIN, COUNTED, EPS, EV_CLOSE, F_HLAST, F_T, F_TEND, F_TOUT, F_TPREV, F_TSAME, F_TTASK,
    GO_ON, I_DIRTY, I_EVJ, I_EVK, I_EVTOTAL, I_FORCED, I_HAVEOUT, I_JUMP, I_M, I_MAXEV,
    I_NCL, I_NEED, I_NEV, I_NSAME, I_NSEAL, I_PAIRS, I_POST, I_TASK, ST_DEFECT,
    ST_EVENT_LIMIT, ST_FLUSH, ST_GROW, ST_OUTPUT, ST_STOP_TIME, ST_TERMINAL, ST_YIELD,
    TASK_RUN, TASK_SNAPSHOT, YIELD_STEPS,
)
from chainrun.solver._stepping import _step_to_event


@entry
def advance(S):
    """Run until something needs the driver; return a status code (ST_*).

    The driver sets ``fs[F_TOUT]`` and ``ints[I_HAVEOUT] = 1`` to ask for the next
    snapshot (2 for a sample of a few balls, which it then asks for as a task),
    empties the event log on ST_FLUSH, grows the compact arrays on ST_GROW (to
    ``ints[I_NEED]``) and calls again; ST_DEFECT reports contact states that do not
    settle. With ``ints[I_TASK]`` set, the call evaluates the state at ``fs[F_TTASK]``
    instead (TASK_SNAPSHOT: every ball into ox, ov; TASK_SAMPLE: the balls of probe)
    and returns ST_OUTPUT.

    Each pass: what the last step left (``_after_step``), a collision due now
    (``_collide``), the stop time, free flight to the next collision (``_fly``), or
    one step of the clusters (``_step_to_event``).
    """
    task = S.ints[I_TASK]
    if task != TASK_RUN:
        S.ints[I_TASK] = TASK_RUN
        if task == TASK_SNAPSHOT:
            _snapshot(S, S.fs[F_TTASK])
        else:
            _sample(S, S.fs[F_TTASK])
        return ST_OUTPUT
    nsteps = 0
    while True:
        st = _after_step(S)
        if st == AGAIN:
            continue
        if st != GO_ON:
            return st
        t = S.fs[F_T]
        tend = S.fs[F_TEND]
        tcol = _next_collision(S, t)
        if tcol <= t:
            st = _collide(S, t)
            if st == COUNTED:
                nsteps += 1
                if nsteps > YIELD_STEPS:
                    return ST_YIELD
            elif st != AGAIN:
                return st
            continue
        if t >= tend:
            _unseal_at_end(S)
            return ST_STOP_TIME
        if S.ints[I_NCL] == 0:
            if tcol == np.inf and S.ints[I_FORCED] == 0:
                return ST_TERMINAL  # (under external forces, free flight to tend)
            _fly(S, t, min(tcol, tend))
            continue
        nsteps += 1
        if nsteps > YIELD_STEPS:
            return ST_YIELD
        st = _step_to_event(S, t, min(tcol, tend))
        if st != AGAIN:
            return st


@kernel(inline="always")
def _after_step(S):
    """What the last step (or jump, or collision) left: the compact arrays packed again
    after a change of structure, a snapshot due inside the step (before its event
    reshapes the clusters), its event applied (``_post_step``); the event limit.

    Returns a status for the driver, AGAIN after applying the step's event, or GO_ON.
    """
    while S.ints[I_DIRTY] == 1:  # (a rebuild can take a sealed pair in: again)
        need = _rebuild(S)
        if need > 0:
            S.ints[I_NEED] = need
            return ST_GROW
    # (I_HAVEOUT 2: a sample of a few balls, which the driver takes with _sample)
    if S.ints[I_HAVEOUT] != 0 and S.fs[F_TOUT] <= S.fs[F_T]:
        if S.ints[I_HAVEOUT] == 1:
            _snapshot(S, S.fs[F_TOUT])
        S.ints[I_HAVEOUT] = 0
        return ST_OUTPUT
    if S.ints[I_POST] == 1:
        if S.ev_t.shape[0] - S.ints[I_NEV] < S.ints[I_M] + 5:
            return ST_FLUSH
        S.ints[I_POST] = 0
        if not _post_step(S):
            return ST_DEFECT
        return AGAIN
    if S.ints[I_MAXEV] >= 0 and S.ints[I_EVTOTAL] >= S.ints[I_MAXEV]:
        _unseal_at_end(S)
        return ST_EVENT_LIMIT
    return GO_ON


@kernel(inline="always")
def _next_collision(S, t):
    """The time of the next predicted collision of free balls (or a sealed one's end),
    inf if none; t itself if it is within the resolution of t (as _due takes it): the
    mirror image of a collision at this instant, its time rounded otherwise, is at this
    instant; a step that short moves no ball, and a contact closed now would neither
    press nor part in it."""
    if not _heap_valid_top(S):
        return np.inf
    tcol = S.hp_t[0]
    if tcol <= t + 4.0 * EPS * abs(t):
        return t
    return tcol


@kernel(inline="always")
def _collide(S, t):
    """Take the collision due at t off the heap: a sealed collision ends, or one begins
    (``_binary``), and COUNTED is returned; else the contact closes after this pass
    (AGAIN). Collisions at one instant close each contact at most a few times; more
    means states flipping back and forth, a defect reported (as by _settle) rather than
    run forever."""
    if S.ev_t.shape[0] - S.ints[I_NEV] < 2:
        return ST_FLUSH
    if t == S.fs[F_TSAME]:
        S.ints[I_NSAME] += 1
        if S.ints[I_NSAME] > 4 * S.cst.shape[0] + 64:
            return ST_DEFECT
    else:
        S.fs[F_TSAME] = t
        S.ints[I_NSAME] = 0
    j = S.hp_j[0]
    _heap_pop(S)
    nc = S.cst.shape[0]
    if j >= nc or (S.ints[I_PAIRS] == 1 and _seal(S, j)):
        if j >= nc:
            _sealed_end(S, j - nc)
        else:
            S.ints[I_NSEAL] += 1
        return COUNTED
    S.ints[I_EVJ] = j
    S.ints[I_EVK] = EV_CLOSE
    S.ints[I_POST] = 1
    return AGAIN


@kernel(inline="always")
def _fly(S, t, tn):
    """No cluster: every ball flies freely to tn, the next collision or the stop time."""
    S.fs[F_TPREV] = t
    S.fs[F_HLAST] = tn - t
    S.fs[F_T] = tn
    S.ints[I_JUMP] = 1
