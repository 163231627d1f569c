"""A meeting of two free balls, taken whole where it is isolated (see ``_pairs``).

``_seal`` decides at the meeting whether the collision can be applied in closed form:
a line without external forces (``ints[I_PAIRS]``), two free balls in
touch through an open contact, and each neighbour free, not itself in a sealed
collision, behind an open contact, and clear of the pair's centre of mass's line
until the contact ends. It then logs the close, and the heap holds the contact's end,
where ``_part`` logs the open and sets the balls off on their exact outgoing lines (a
damped contact's unload comes first: ``_sealed_end`` logs it).
A neighbour whose motion changes before then is checked again (``_heap``), and a
contact it could reach is integrated from that instant (``_clusters._unseal``).
"""

from __future__ import annotations

from chainrun.solver._clusters import _touch_ball, _unseal
from chainrun.solver._events import _log, _rounding
from chainrun.solver._heap import _heap_push, _schedule_pair
from chainrun.solver._jit import kernel
from chainrun.solver._pairs import (
    _clear_of, _closed_form, _damped_seal, _first_end, _fractions, _sealed_contact, _sealed_lost,
    _unload_ahead,
)
from chainrun.solver._state import (
    B_IM, C_DISS, C_EPS, EV_CLOSE, EV_OPEN, EV_UNLOAD, F_DISS, F_JL, F_JR, F_T, I_LWALL,
    I_RWALL, I_SEALED, OPEN, SEALED, SL_E, SL_PH, SL_T0, SL_TAU, SL_V, SL_W, SL_X,
)


@kernel(inline="always")
def _free_neighbour(S, j, a):
    """Whether ball a, next to the pair of contact j, is free, not in a sealed
    collision, and behind an open contact."""
    between = j - 1 if a < j else j + 1
    return S.bmap[a] < 0 and S.cst[between] == OPEN and _sealed_contact(S, a) < 0


@kernel
def _seal(S, j):
    """Take the meeting of free balls j, j + 1 now whole, if it is isolated; return
    whether it was."""
    if S.cst[j] != OPEN or S.bmap[j] >= 0 or S.bmap[j + 1] >= 0:
        return False
    if _sealed_contact(S, j) >= 0 or _sealed_contact(S, j + 1) >= 0:
        return False
    # the neighbours' states first: a damped contact's outcome costs an integration
    last = S.bx.shape[0] - 1
    if j >= 1 and not _free_neighbour(S, j, j - 1):
        return False
    if j + 2 <= last and not _free_neighbour(S, j, j + 2):
        return False
    t = S.fs[F_T]
    if not _closed_form(S, j, t):
        return False
    tend = S.sl[SL_T0, j] + S.sl[SL_TAU, j]
    if j >= 1 and not _clear_of(S, j, j - 1, t, tend):
        return False
    if j + 2 <= last and not _clear_of(S, j, j + 2, t, tend):
        return False
    S.cst[j] = SEALED
    S.ints[I_SEALED] += 1
    _touch_ball(S, j)
    _touch_ball(S, j + 1)
    _heap_push(S, _first_end(S, j), j + S.cst.shape[0])
    _log(S, t, j, EV_CLOSE)
    return True


@kernel(inline="always")
def _sealed_end(S, j):
    """The heap calls on sealed contact j now: at a damped contact's unload (logged;
    the balls part with the force held at 0, and the heap calls again at the
    opening), or at its end (_part)."""
    if _unload_ahead(S, j):
        S.sl[SL_PH, j] = 1.0
        _log(S, S.fs[F_T], j, EV_UNLOAD)
        _heap_push(S, S.sl[SL_T0, j] + S.sl[SL_TAU, j], j + S.cst.shape[0])
        return
    _part(S, j)


@kernel
def _part(S, j):
    """End sealed contact j now: its balls leave on their outgoing lines (with the
    compression back at 0), and their neighbours are scheduled."""
    t = S.fs[F_T]
    s = t - S.sl[SL_T0, j]
    w = S.sl[SL_W, j]
    v = S.sl[SL_V, j]
    e = 1.0
    if _damped_seal(S, j):
        e = S.sl[SL_E, j]
        lost = _sealed_lost(S, j, t)
        S.cp[C_DISS, j] += lost
        S.fs[F_DISS] += lost
    fl, fr = _fractions(S, j)
    x = S.sl[SL_X, j] + v * s
    vl = v - fl * (e * w)
    vr = v + fr * (e * w)
    for b, vb in ((j, vl), (j + 1, vr)):
        S.bx[b] = x
        S.bv[b] = vb
        S.bt[b] = t
        S.sep_t[b] = t
        S.sep_v[b] = vb
    # a wall's impulse: the momentum it gave the ball, (1 + e) mu w
    imp = (1.0 + e) * w / (S.bp[B_IM, j] + S.bp[B_IM, j + 1])
    if j == 0 and S.ints[I_LWALL] == 1:
        S.fs[F_JL] += imp
    if j + 1 == S.bx.shape[0] - 1 and S.ints[I_RWALL] == 1:
        S.fs[F_JR] += imp
    S.cst[j] = OPEN
    S.ints[I_SEALED] -= 1
    S.lvl[j] = max(S.cp[C_EPS, j], 4.0 * _rounding(2.0 * abs(x)))
    _touch_ball(S, j)
    _touch_ball(S, j + 1)
    _log(S, t, j, EV_OPEN)
    # (a neighbour is never in a sealed collision itself, see _seal; were it, one it
    # could reach would be integrated from now)
    for q in (j - 1, j + 1):
        js = _schedule_pair(S, q)
        if js >= 0:
            _unseal(S, js)
