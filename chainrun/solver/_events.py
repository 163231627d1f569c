"""Event location: the first contact in the last step to open, close, engage or release,
or, on a damped line, whose force is held at 0 or rises from it (unload, reload).

Events are located on the dense output by sampling each candidate contact at several
points of the step (an opening can re-close within one step) and bracketing the first
crossing (``_contact_event``, ``_crossing``); the step loop then redoes the step from
its start to end exactly at the root, refined by Newton on the step itself, so no
accepted step ever crosses a non-smooth point. On a series step a contact is a
candidate only if its level lies within the Bernstein bounds of its compression's
series over the step (``_compression``, ``_generated._series_bounds``). ``_log``
writes the events into the state's event log.

References
----------
E. Hairer, S. P. Norsett, G. Wanner, Solving Ordinary Differential Equations I,
Sec. II.6 (dense output and event location).
"""

from __future__ import annotations

from chainrun.solver._compression import (
    _bernstein_range, _contact_series, _curvature_bound, _sample_series, _series_at,
    _stays_open,
)
from chainrun.solver._forces import _load, _power, _window_beta
from chainrun.solver._generated import _series_bounds
from chainrun.solver._jit import kernel
from chainrun.solver._state import (
    ACTIVE, C_ALPHA, C_BETA, C_DORM, C_EPS, C_ETA, C_HELD, C_KAPPA, C_LOC, DORMANT, EPS,
    EV_CLOSE, EV_ENGAGE, EV_OPEN, EV_RELEASE, EV_RELOAD, EV_UNLOAD, FRESH, F_FLOOR,
    F_HLAST, F_TDEF, F_TPREV, HI_ROW, I_DAMPED, I_DEFJ, I_EVTOTAL, I_M, I_MODE, I_NCL,
    I_NEV, I_TAY, LO_ROW, MODE_HERTZ, MODE_LINEAR, MODE_MIXED, N_SAMPLES, N_SERIES_SAMPLES,
    OPEN, PT, W_ALPHA, W_BETA, W_ETA, W_HELD, _tw,
)
from chainrun.solver._steppers import _ball_at, _ball_end, _dense_at, _poly


@kernel(inline="always")
def _log(S, t, j, kind):
    n = S.ints[I_NEV]
    S.ev_t[n] = t
    S.ev_j[n] = j
    S.ev_k[n] = kind
    S.ints[I_NEV] = n + 1
    S.ints[I_EVTOTAL] += 1


@kernel
def _contact_at(S, j, th):
    """(compression, its rate, |x_l| + |x_r|) of contact j at t_prev + th * h_last."""
    xl, vl = _ball_at(S, j, th)
    xr, vr = _ball_at(S, j + 1, th)
    return xl - xr, vl - vr, abs(xl) + abs(xr)


@kernel(inline="always")
def _contact_end(S, j, th):
    """_contact_at at th = 0 or 1, where no interpolant is needed (inlined)."""
    xl, vl = _ball_end(S, j, th)
    xr, vr = _ball_end(S, j + 1, th)
    return xl - xr, vl - vr, abs(xl) + abs(xr)


@kernel
def _crossing(S, j, ta, tb, ca, cb_, level, load=False):
    """Root of c_j(theta) = level in [ta, tb] (bracketed), by safeguarded regula falsi;
    with ``load``, of contact j's damped load instead (ca, cb_ its values, level 0)."""
    fa = ca - level
    fb = cb_ - level
    side = 0
    for _ in range(100):
        if tb - ta <= 4.0 * EPS * max(1.0, tb):
            break
        tm = tb - fb * (tb - ta) / (fb - fa) if fb != fa else 0.5 * (ta + tb)
        if not (tm > ta and tm < tb):
            tm = 0.5 * (ta + tb)
        fm = (_load_at(S, j, tm)[0] if load else _contact_at(S, j, tm)[0]) - level
        if fm == 0.0:
            return tm
        if (fm > 0.0) == (fa > 0.0):
            ta = tm
            fa = fm
            if side == -1:
                fb *= 0.5
            side = -1
        else:
            tb = tm
            fb = fm
            if side == 1:
                fa *= 0.5
            side = 1
    # the side past the level, so the event is not missed by a hair
    return tb


@kernel(inline="always")
def _contact_load(S, j, c, w):
    """Contact j's damped force before it is held at 0 (_forces._load)."""
    cp = S.cp
    return _load(cp[C_KAPPA, j], cp[C_ALPHA, j], cp[C_ETA, j], cp[C_BETA, j], c, w)


@kernel
def _load_at(S, j, th):
    """(_contact_load, compression) of contact j at t_prev + th * h_last."""
    if th <= 0.0 or th >= 1.0:
        c, w, _s = _contact_end(S, j, th)
    else:
        c, w, _s = _contact_at(S, j, th)
    return _contact_load(S, j, c, w), c


@kernel(inline="always")
def _load_inside(S, j, p, th):
    """_load_at for a contact inside a cluster of a DOP853 step (its left ball at p in
    the window, its interpolant built), read from the interpolant without a call per
    sample: the same operations as _load_at's."""
    if th <= 0.0 or th >= 1.0:
        c, w, _s = _contact_end(S, j, th)
    else:
        c = _poly(S.FX, S.X0[p], p, th) - _poly(S.FX, S.X0[p + 1], p + 1, th)
        w = _poly(S.FV, S.V0[p], p, th) - _poly(S.FV, S.V0[p + 1], p + 1, th)
    return _contact_load(S, j, c, w), c


@kernel
def _load_rate(S, j, c, w, a):
    """(load, its rate, its rounding) of damped contact j at compression c, rate w and
    relative acceleration a: what a step's ends say of the load (_find_event), and
    Newton's residual where a step lands on an unload or a reload (_stepping)."""
    cp = S.cp
    g, dg, scale = _load_and_rate(cp[C_KAPPA, j], cp[C_ALPHA, j], cp[C_ETA, j],
                                  cp[C_BETA, j], c, w, a, True)
    return g, dg, 16.0 * EPS * scale


@kernel(inline="always")
def _load_and_rate(kappa, al, eta, beta, c, w, a, exact_at_zero):
    """(load, its rate, their scale) of a damped contact (stiffness kappa, exponent al,
    damping eta |c|^beta) at compression c, rate w and relative acceleration a.
    |c|^(beta-1) is taken as |c|^beta / |c|: at c = 0 that is NaN, where pow gives the
    infinity the rate has there; ``exact_at_zero`` takes pow's there."""
    g = _load(kappa, al, eta, beta, c, w)
    ac = abs(c)
    fa = _power(ac, al - 1.0)
    dg = kappa * al * fa * w
    if beta == 0.0:
        dg += eta * a
        damp = eta * w
    else:
        fb = _power(ac, beta)
        fbm = ac ** (beta - 1.0) if exact_at_zero and not ac > 0.0 else fb / ac
        dg += eta * (beta * fbm * w * w + fb * a)
        damp = eta * fb * w
    return g, dg, kappa * ac * fa + abs(damp)


@kernel
def _kinks_possible(S, h):
    """Flag (``jbuf[p]`` 1, else 0) each damped lane of the window whose load may have
    crossed 0 in the last step, of length h: all but those whose load at both ends is
    on the side the contact is on (bearing: above 0; held at 0: below) by four times
    what a parabola through its ends' rates could dip (h |g'_1 - g'_0| / 8).

    One pass over the lanes, with the law and the damping's exponent fixed where the
    window's lanes share them (as ``_forces._damped_forces``), so that it vectorises;
    each lane's load and rate are those ``_load_rate`` gives, to the bit (where the
    rate is not a number, at c = 0, neither test passes and the lane is flagged, as
    with pow's infinity).
    """
    nc = S.ints[I_M] - 1
    mode = S.ints[I_MODE]
    beta = _window_beta(S.WP[W_ETA], S.WP[W_BETA], nc)
    if mode == MODE_HERTZ and beta == 0.25:
        _kink_lanes(S, h, nc, 1.5, 0.25)
    elif mode == MODE_HERTZ and beta == 0.5:
        _kink_lanes(S, h, nc, 1.5, 0.5)
    elif mode == MODE_LINEAR and beta == 0.0:
        _kink_lanes(S, h, nc, 1.0, 0.0)
    else:
        _kink_lanes(S, h, nc, -1.0, -1.0)


@kernel(inline="always")
def _kink_lanes(S, h, nc, alpha, beta):
    """``_kinks_possible``'s pass, with the exponents ``alpha`` and ``beta`` (-1: each
    lane's own)."""
    X0, V0, A0, X, V, A = S.X0, S.V0, S.A0, S.X, S.V, S.A
    KAPPA, AL, ETA, BETA, HELD = S.TR, S.WP[W_ALPHA], S.WP[W_ETA], S.WP[W_BETA], S.WP[W_HELD]
    flag = S.jbuf
    for p in range(nc):
        kappa = KAPPA[p]
        eta = ETA[p]
        al = AL[p] if alpha < 0.0 else alpha
        be = BETA[p] if beta < 0.0 else beta
        g0, d0, _s0 = _load_and_rate(kappa, al, eta, be, X0[p] - X0[p + 1],
                                     V0[p] - V0[p + 1], A0[p] - A0[p + 1], False)
        g1, d1, _s1 = _load_and_rate(kappa, al, eta, be, X[p] - X[p + 1],
                                     V[p] - V[p + 1], A[p] - A[p + 1], False)
        margin = 0.5 * h * abs(d1 - d0)
        held = HELD[p] != 0.0
        quiet = (held & (g0 < -margin) & (g1 < -margin)) | \
            (~held & (g0 > margin) & (g1 > margin))
        flag[p] = 1 if (eta != 0.0) & ~quiet else 0


@kernel
def _unload_event(S, j, hcap):
    """The first kink of damped contact j's force in the last step before ``hcap``.

    Its load g = kappa f(c) + eta |c|^beta w (its force before it is held at 0) is
    sampled on the dense output: a contact bearing its load unloads where g falls
    below 0 (the collision ends, before the compression has gone), one held at 0
    reloads where g rises above 0 while still compressed. C_HELD says which it is, so
    a step that starts on the kink, within rounding of it on either side, finds no
    second one there. Returns (theta, kind), theta = 2 when there is none.
    """
    held = S.cp[C_HELD, j] != 0.0
    # both balls are in the window (the contact is inside a cluster), and a damped
    # line's steps are DOP853's: their interpolants, built here
    p = S.bmap[j]
    _dense_at(S, p)
    _dense_at(S, p + 1)
    ta = 0.0
    ga = _load_at(S, j, 0.0)[0]
    for i in range(1, N_SAMPLES + 1):
        tb = min(i / N_SAMPLES, hcap)
        gb, cb_ = _load_inside(S, j, p, tb)
        # (a load reaching exactly 0 is an unload: the compression's own opening at the
        # cap, where it is exactly 0, may come just after the unload)
        if not held and ga > 0.0 and gb <= 0.0:
            return _crossing(S, j, ta, tb, ga, gb, 0.0, True), EV_UNLOAD
        if held and ga <= 0.0 and gb > 0.0 and cb_ > 0.0:
            return _crossing(S, j, ta, tb, ga, gb, 0.0, True), EV_RELOAD
        ta = tb
        ga = gb
        if tb >= hcap:
            break
    return 2.0, 0


@kernel(inline="always")
def _rounding(scale):
    return 16.0 * EPS * max(1.0, scale)


@kernel(inline="always")
def _may_cross(c0, c1, reach, level):
    return not (min(c0, c1) - reach > level or max(c0, c1) + reach < level)


@kernel
def _contact_event(S, j, hcap):
    """Earliest event of contact j in the last step before ``hcap``.

    Returns (theta, kind, level), theta = 2 when there is none. The kind says what
    crossing was found; the caller sets the contact's new state from it.
    """
    st = S.cst[j]
    tay = S.ints[I_TAY] == 1
    if st == FRESH and not tay:
        # never pressed beyond eps_rel: its force is below the floor, so it is checked
        # at the step's end (_release_quiet), like a dormant contact
        return 2.0, 0, 0.0
    c0, w0, s0 = _contact_end(S, j, 0.0)
    c1, w1, s1 = _contact_end(S, j, 1.0)
    h = S.fs[F_HLAST]
    if st == FRESH:
        # a series step is long enough for a fresh contact to be pressed beyond
        # eps_rel and to open again inside it: that opening is located
        lev1 = S.cp[C_EPS, j]
        lev2 = lev1
    elif st == ACTIVE:
        lev1 = 0.0
        lev2 = 0.0
    elif st == DORMANT:
        # a dormant contact pressed slowly engages at the step's end (_post_step): its
        # force below FORCE_LOCATE is far under rounding; only a fast press is located
        if c1 < S.cp[C_LOC, j]:
            return 2.0, 0, 0.0
        lev1 = S.cp[C_DORM, j]
        lev2 = -S.cp[C_EPS, j]
    else:
        lev1 = 0.0
        lev2 = S.lvl[j]
    if tay:
        # the series of c over the step lies within the hull of its Bernstein
        # coefficients: a level outside it is not reached (a lane inside a cluster has
        # them from the scan, _series_bounds)
        _contact_series(S, j)
        pa = S.bmap[j]
        if pa >= 0 and S.bmap[j + 1] == pa + 1 and S.TR[pa] != 0.0:
            blo = S.TW[_tw(pa, LO_ROW)]
            bhi = S.TW[_tw(pa, HI_ROW)]
        else:
            blo, bhi = _bernstein_range(S.TD, h, S.TS[0])
        if not (blo <= lev1 <= bhi or blo <= lev2 <= bhi):
            return 2.0, 0, 0.0
    else:
        # how far c can stray from its end values inside the step: h^2/8 max|c''|,
        # with c'' taken at both ends and a safety factor of 2
        reach = 0.25 * h * h * _curvature_bound(S, j)
        if not (_may_cross(c0, c1, reach, lev1) or _may_cross(c0, c1, reach, lev2)):
            return 2.0, 0, 0.0
    floor = S.fs[F_FLOOR]
    # a series step is several DOP853 steps long: sample it as finely, on the series
    # of c itself (TD)
    ns = N_SERIES_SAMPLES if tay else N_SAMPLES
    if tay:
        _sample_series(S, ns, h)
        # each crossing below needs a sample on the level's far side: when none is,
        # the scan would find nothing (its common outcome), so skip it
        smin = min(c0, c1)
        smax = max(c0, c1)
        for i in range(ns):
            smin = min(smin, S.TS[1, i])
            smax = max(smax, S.TS[1, i])
        if st == ACTIVE:
            clear = smin > lev1
        elif st == FRESH:
            clear = smin > 0.0
        elif st == DORMANT:
            clear = smax < lev1 and smin > lev2
        else:
            clear = smax < 0.0 and smax < lev2
        if clear:
            return 2.0, 0, 0.0
    pressed = c0 > lev1  # (a fresh contact's press beyond eps_rel)
    ta = 0.0
    ca = c0
    for i in range(1, ns + 1):
        tb = i / ns
        if tb >= hcap:
            tb = hcap
        if tb >= 1.0:
            cb_ = c1
        elif tay:
            cb_ = S.TS[1, i - 1] if tb == i / ns else _series_at(S.TD, tb * h)
        else:
            cb_ = _contact_at(S, j, tb)[0]
        if st == ACTIVE:
            if ca > lev1 and cb_ <= lev1:
                return _crossing(S, j, ta, tb, ca, cb_, lev1), EV_OPEN, lev1
        elif st == FRESH:
            if pressed and ca > 0.0 and cb_ <= 0.0:
                return _crossing(S, j, ta, tb, ca, cb_, 0.0), EV_OPEN, 0.0
            pressed = pressed or cb_ > lev1
        elif st == DORMANT:
            if ca < lev1 and cb_ >= lev1:
                return _crossing(S, j, ta, tb, ca, cb_, lev1), EV_ENGAGE, lev1
            if ca > lev2 and cb_ <= lev2:
                return _crossing(S, j, ta, tb, ca, cb_, lev2), EV_RELEASE, lev2
        else:
            if ca < 0.0 and cb_ >= 0.0:
                tr = _crossing(S, j, ta, tb, ca, cb_, 0.0)
                if _contact_at(S, j, tr)[1] >= floor:
                    return tr, EV_CLOSE, 0.0
            if ca < lev2 and cb_ >= lev2:
                return _crossing(S, j, ta, tb, ca, cb_, lev2), EV_ENGAGE, lev2
        ta = tb
        ca = cb_
        if tb >= hcap:
            break
    return 2.0, 0, 0.0


@kernel(inline="always")
def _stays_positive(c0, c1, w0, w1, g0, g1, h):
    """Whether c > 0 throughout a step where c'' keeps one sign (both ends agree within 10x).

    Concave: the minimum is at an end. Convex: c lies above both end tangents, whose
    upper envelope has its minimum at their intersection.
    """
    if c0 <= 0.0 or c1 <= 0.0:
        return False
    if g0 < 0.0 and g1 < 0.0 and 10.0 * g0 <= g1 and 10.0 * g1 <= g0:
        return True
    if g0 > 0.0 and g1 > 0.0 and 10.0 * g0 >= g1 and 10.0 * g1 >= g0:
        if w0 >= 0.0 or w1 <= 0.0:
            return True  # monotone over the step: the smaller end is the minimum
        # tangents c0 + w0 h s and c1 - w1 h (1 - s) meet at s*
        sst = (c1 - w1 * h - c0) / (h * (w0 - w1))
        return c0 + w0 * h * sst > 0.0
    return False


@kernel
def _parts_after(S, j, th):
    """Whether held contact j, whose compression crosses 0 at th of the last step,
    stays open to the step's end: below 0 at each of the scan's samples after th (the
    resolution at which the scan finds crossings) and at the end beyond its rounding.
    Its balls then part, without a force between them, through the rest of the step."""
    c1, _w1, s1 = _contact_end(S, j, 1.0)
    if not c1 < -_rounding(s1):
        return False
    for i in range(1, N_SAMPLES):
        tb = i / N_SAMPLES
        if tb > th and not _contact_at(S, j, tb)[0] < 0.0:
            return False
    return True


@kernel(inline="always")
def _find_event(S):
    """Scan the contacts touching clusters for the earliest event of the last step.

    A held contact's opening (its force already 0, and 0 after it) does not end the
    step where the rest of its cluster goes on: the earliest that stays open to the
    step's end waits in I_DEFJ (its time in F_TDEF) for ``_settle._post_step``, unless
    the step ends before it."""
    best = 2.0
    bj = -1
    bk = 0
    blev = 0.0
    dth = 2.0  # the held contact whose opening waits, and when
    dj = -1
    ncont = S.cst.shape[0]
    h = S.fs[F_HLAST]
    q = 0.25 * h * h
    tay = S.ints[I_TAY] == 1
    W = S.TW
    if tay:
        _series_bounds(W, S.ints[I_M] - 1, h)
    EPSREL = S.cp[C_EPS]
    X, X0, A, A0 = S.X, S.X0, S.A, S.A0
    for c in range(S.ints[I_NCL]):
        lo = S.clo[c]
        o = S.coff[c] - lo
        for j in range(max(lo - 1, 0), min(S.chi[c], ncont - 1) + 1):
            # a boundary shared by two clusters is seen twice: skip the second
            if j == lo - 1 and c > 0 and S.chi[c - 1] == j:
                continue
            st = S.cst[j]
            if j >= lo and j < S.chi[c]:
                # a contact inside the cluster, active or fresh (never pressed beyond
                # eps_rel): can it open in this step?
                p = o + j
                if tay:
                    if W[_tw(p, LO_ROW)] > 0.0 or (st == FRESH and W[_tw(p, HI_ROW)] < EPSREL[j]):
                        continue
                elif st == FRESH:
                    continue  # checked at the step's end (_release_quiet)
                else:
                    c0 = X0[p] - X0[p + 1]
                    c1 = X[p] - X[p + 1]
                    g0 = A0[p] - A0[p + 1]
                    g1 = A[p] - A[p + 1]
                    if min(c0, c1) > q * max(abs(g0), abs(g1)):
                        continue
                    if _stays_positive(c0, c1, S.V0[p] - S.V0[p + 1],
                                       S.V[p] - S.V[p + 1], g0, g1, h):
                        continue
            else:
                # quick rejections at a cluster's edge; the general path repeats them
                cq0 = _contact_end(S, j, 0.0)[0]
                cq1 = _contact_end(S, j, 1.0)[0]
                if st == DORMANT:
                    if cq1 < S.cp[C_LOC, j]:
                        continue
                elif st == OPEN:
                    if tay:
                        _contact_series(S, j)
                        if _stays_open(S.TD, h, S.lvl[j], S.fs[F_FLOOR], S.TS[1], S.TS[0]):
                            continue
                    elif max(cq0, cq1) + q * _curvature_bound(S, j) < 0.0:
                        continue  # stays open: below both of its levels (0 and lvl > 0)
            th, kind, lev = _contact_event(S, j, best)
            cj = j
            # (an undamped line's cp has no row C_HELD; in a cluster of two balls the
            # opening may be the run's last event, the terminal state's instant)
            if th < best and kind == EV_OPEN and S.ints[I_DAMPED] == 1 and \
                    S.cp[C_HELD, j] != 0.0 and S.chi[c] - lo >= 2 and \
                    _parts_after(S, j, th):
                # (one waits: of two, the later ends the step)
                if th < dth:
                    th, dth = dth, th
                    cj, dj = dj, j
                if cj < 0:
                    continue
            if th < best:
                best = th
                bj = cj
                bk = kind
                blev = lev
    if S.ints[I_DAMPED] == 1:
        # the kinks of the damped forces inside the clusters, sampled where one may be
        # (_kinks_possible): the damped lanes are the clusters' inner contacts, in order
        _kinks_possible(S, h)
        for p in range(S.ints[I_M] - 1):
            if S.jbuf[p] != 0:
                th, kind = _unload_event(S, S.cb[p], best)
                if th < best:
                    best = th
                    bj = S.cb[p]
                    bk = kind
                    blev = 0.0
    if dth < best:
        S.ints[I_DEFJ] = dj
        S.fs[F_TDEF] = S.fs[F_TPREV] + dth * h
    else:
        S.ints[I_DEFJ] = -1
    return best, bj, bk, blev


@kernel(inline="always")
def _grazes(S, h):
    """Whether a contact of the window passes a minimum of its compression inside the
    series step [0, h] (its rate below 0 at the start, above 0 at the end) and comes
    below half its start (above 0) there (``_series_bounds``' lower bound, after ``_find_event``).

    Near such a graze c(t)^alpha has branch points close to the real axis, at the
    complex times where c vanishes; they bound the series' radius of convergence, and
    from a start far from them the last terms do not show it yet, so the truncation
    estimate passes a step that crosses them. A linear contact has none.
    """
    mode = S.ints[I_MODE]
    if mode == MODE_LINEAR:
        return False
    W, MK = S.TW, S.TR
    for p in range(S.ints[I_M] - 1):
        if MK[p] == 0.0 or (mode == MODE_MIXED and S.WP[W_ALPHA, p] == 1.0):
            continue
        c0 = W[_tw(p, 0)]
        # (a compression within rounding of 0 or below, a contact just closed, has no
        # start to fall below half of)
        if not (c0 > 0.0 and W[_tw(p, LO_ROW)] < 0.5 * c0 and W[_tw(p, 1)] < 0.0):
            continue
        rate = PT * W[_tw(p, PT)]
        for k in range(PT - 1, 0, -1):
            rate = rate * h + k * W[_tw(p, k)]
        if rate > 0.0:
            return True
    return False
