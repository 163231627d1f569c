"""numba kernels of the event-driven solver: stepping, event location, cluster bookkeeping.

The kernels own the numerics and nothing else: they never see files or Python objects,
and report through integer status codes that ``_driver`` maps to named outcomes.

State model
-----------
A ball is either *free* (no active contact; it moves as ``x + v (t - tref)``) or a
member of a *cluster*, a maximal run of balls joined by active contacts. Only cluster
balls are integrated: their state is packed, cluster after cluster, into compact
arrays and advanced together. Between events the active set is fixed, so the
right-hand side is smooth: an active contact carries ``f(c) = c |c|^(alpha-1)``, which
is the force for ``c > 0`` and its odd continuation beyond (for alpha = 1 exactly
linear), so a step that ends on an opening sees no kink. Each step is taken by the
Taylor series of the motion to order PT (``_taylor``), whose steps are several times
longer than those of a Runge-Kutta pair at the same tolerance and which is its own
dense output; where the series does not exist or reaches less far (a contact closed
just now, at compression exactly 0, is a branch point of c^alpha), and on windows of
many clusters (SERIES_CLUSTERS), by the explicit Runge-Kutta pair DOP853 (order 8,
dense output of order 7).

Contact states (``cst``)::

    DORMANT  touching at zero compression since t = 0, never pressed; engages when
             its force would reach ``FORCE_DORMANT`` (not logged: it was closed already)
    FRESH    active, not yet compressed beyond the floor's compression ``eps_rel``;
             openings fire only below minus the rounding level of its positions
    ACTIVE   active ("seasoned"); opens exactly where the compression crosses 0
    OPEN     inactive; closes where the gap reaches 0 with approach speed >= floor,
             or engages where the compression exceeds ``lvl[j]`` (a slow press)

Events are located on the dense output by sampling each candidate contact at several
points of the step (an opening can re-close within one step) and bracketing the first
crossing; the step is then redone from its start to end exactly at the root, refined
by Newton on the step itself, so no accepted step ever crosses a non-smooth point.
On a series step a contact is a candidate only if its level lies within the Bernstein
bounds of its compression's series over the step.
Free pairs approaching at >= floor are predicted analytically in a binary heap.

References
----------
E. Hairer, S. P. Norsett, G. Wanner, Solving Ordinary Differential Equations I,
Sec. II.4-II.6 (DOP853, dense output, event location).
A. Jorba, M. Zou, A software package for the numerical integration of ODEs by means
of high-order Taylor methods, Experimental Mathematics 14 (2005) (Taylor series by
recurrences, step size from the last terms).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from chainrun.solver._jit import entry, kernel

# ---- DOP853 (its tableau is written into the stage code by _codegen) -----------------
_NS = 12  # stages of the step proper; row 12 holds f at the step's end (FSAL)
_NSE = 16  # with the three extra stages of the dense output
# ---- Taylor series (see _taylor) -------------------------------------------------------
PT = 24  # order of the series of x(t)
# the series' steps keep their truncation estimate within this fraction of the
# tolerance: an estimate from the last terms is not a bound, and DOP853's, which the
# tolerance was set against, is pessimistic (its steps are far more accurate than it says)
TAYLOR_TOL = 0.1
# the series is tried only on windows of at most this many clusters: a step of many
# clusters (a line broken by many impacting balls) ends at the next event of any of
# them, sooner than either method's step, and the series then costs more than DOP853
SERIES_CLUSTERS = 8
# Bernstein coefficients on [0, 1] of a polynomial of degree DB from its power
# coefficients, b_i = sum_k C(i, k) / C(DB, k) a_k, stored transposed (_BERN[k, i]);
# the terms of a series beyond DB are bounded by the sum of their magnitudes. At the
# front of a Hertz wave a compression grows a thousandfold over a step, and those terms
# are large: at degree 10 the scan flagged 1.7 lanes per step that never reach 0, each
# then sampled in vain (_contact_event); at degree 16, 0.5
DB = 16
# the weights j / k of the force series' recurrence, and 1 / ((k + 1)(k + 2)), the step
# from the forces' order k to the positions' order k + 2 (see _series_orders)
J_OVER_K = np.array([[j / k if k else 0.0 for j in range(PT)] for k in range(PT)])
SERIES_SCALE = np.array([1.0 / ((k + 1) * (k + 2)) for k in range(PT)])
_BERN = np.array([[math.comb(i, k) / math.comb(DB, k) if k <= i else 0.0
                   for i in range(DB + 1)] for k in range(DB + 1)])

# ---- status codes returned by ``advance`` ---------------------------------------------
ST_TERMINAL = 0
ST_STOP_TIME = 1
ST_OUTPUT = 2
ST_YIELD = 3
ST_GROW = 4
ST_FLUSH = 5
ST_EVENT_LIMIT = 6
ST_NON_FINITE = 7
ST_STEP_UNDERFLOW = 8

# ---- contact states -------------------------------------------------------------------
DORMANT = 3
FRESH = 1
ACTIVE = 2
OPEN = 0

# ---- event kinds (same values as chainrun.solver.EventKind) ---------------------------
EV_RELEASE = -2
EV_OPEN = -1
EV_CLOSE = 1
EV_ENGAGE = 2

#: a dormant contact engages where its force c^alpha would reach this (fs[F_LDORM] =
#: FORCE_DORMANT^(1/alpha), 1e-24 for alpha = 1, 1e-16 for Hertz): far below rounding of
#: order-1 velocities, it keeps subnormals out of the front, and the balls ahead of a
#: wave, which it never moves, out of the window
FORCE_DORMANT = 1e-24
#: a dormant contact pressed at the end of a step less than FORCE_LOCATE^(1/alpha)
#: (fs[F_LLOCATE], 1e-18 for alpha = 1, 1e-12 for Hertz) engages there without being
#: located: the force it missed, over a fraction of the step, is below FORCE_LOCATE
FORCE_LOCATE = 1e-18
EPS = 2.220446049250313e-16
N_SAMPLES = 8  # subintervals sampled per step for each candidate contact
N_SERIES_SAMPLES = 4 * N_SAMPLES  # on a series step, several DOP853 steps long
# the series' work tiles TW (see _tw): lanes in tiles of SERIES_TILE, each tile holding
# TILE_ROWS rows: the compressions' series c_k (rows k <= PT), the forces' f_k (rows
# PT + 1 + k), 1 / c_0 (row 2 PT), and the bounds of the compression over a series step
# (rows LO_ROW, HI_ROW, _series_bounds); TR holds each contact lane's mask (1 inside a
# cluster, _rebuild)
SERIES_TILE = 16
LO_ROW = 2 * PT + 1
HI_ROW = 2 * PT + 2
TILE_ROWS = 2 * PT + 3
TILE_STRIDE = TILE_ROWS * SERIES_TILE
#: the step after an event, as a fraction of the step that crossed it (measured on
#: linear lines: 1 rejects 40% of the steps at N = 10^5, 0.8 about 14%)
AFTER_EVENT = 0.8
YIELD_STEPS = 20000

# ---- scalar slots ---------------------------------------------------------------------
# float scalars
F_T, F_H, F_TPREV, F_HLAST, F_TOUT, F_TEND, F_TOL, F_FLOOR, F_EPSREL, F_ALPHA, \
    F_EPROJ, F_TSAME, F_QX1, F_QX2, F_QV1, F_QV2, F_LDORM, F_LLOCATE, F_NFLOAT = range(19)
# int scalars
I_NCL, I_M, I_NHEAP, I_NEV, I_STEPS, I_REJ, I_EVTOTAL, I_DIRTY, I_DENSE, I_NFREED, \
    I_MODE, I_MAXWIN, I_POST, I_EVJ, I_EVK, I_NEED, I_HAVEOUT, I_MAXEV, I_JUMP, \
    I_NSAME, I_DSTAMP, I_TAY, I_NINT = range(23)

State = namedtuple(
    "State",
    [
        # balls, shape (N,)
        "bx", "bv", "bt", "sep_t", "sep_v", "bmap",
        # contacts, shape (N-1,) (at least 1)
        "cst", "lvl", "stamp",
        # clusters: ball range, offset in the compact arrays, energy since the last change
        "clo", "chi", "coff", "cen",
        # compact (integrated) balls: state, step start, dense-stage positions (XS),
        # contact forces (FS), stage accelerations (KV), interpolant rows (FX, FV) and
        # the stamp of the step they were built for (DM, see _dense_at); the Taylor
        # series of the positions (TX), order-major (see _taylor), with the work tiles
        # of the compressions' and forces' series (TW, see _tw) and lane mask (TR),
        # and of one contact's compression (TD, shape (PT + 1,)) with its samples (TS)
        "cb", "X", "V", "A", "X0", "V0", "A0", "XS", "FS", "KV", "FX", "FV", "DM",
        "TX", "TW", "TR", "TD", "TS",
        # heap of free-pair collisions
        "hp_t", "hp_j", "hp_s",
        # event log buffer
        "ev_t", "ev_j", "ev_k",
        # snapshot buffer
        "ox", "ov",
        # scratch lists of ball / contact indices, shape (N,)
        "freed", "jbuf",
        # scalars
        "fs", "ints",
    ],
)


# =========================================================================================
# forces
# =========================================================================================
@kernel(inline="always")
def _force(c, mode, alpha):
    if mode == 0:
        return c
    elif mode == 1:
        return c * np.sqrt(abs(c))
    else:
        if c == 0.0:
            return 0.0
        return c * abs(c) ** (alpha - 1.0)


@kernel
def _forces(X, F, MK, o, e, mode, alpha):
    """Forces of the contact lanes o..e-1 at positions X into F[o:e], masked by MK.

    One loop per law, each with its law fixed, so that the loop vectorises. A lane
    from a cluster's last ball to the next cluster's first carries none (MK = 0, see
    _rebuild).
    """
    if mode == 0:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], 0, alpha) * MK[p]
    elif mode == 1:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], 1, alpha) * MK[p]
    else:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], mode, alpha) * MK[p]


@kernel
def _accelerations(X, F, MK, out, m, mode, alpha):
    """Accelerations of the m compact balls at positions X into out (forces into F).

    One pass over the window's m - 1 contact lanes, clusters and all, gaps masked: the
    loops are as long as the window, and vectorise, where loops per cluster are as
    short as the clusters (a line broken by many impacting balls has hundreds of them).
    """
    nc = m - 1
    _forces(X, F, MK, 0, nc, mode, alpha)
    out[0] = -F[0]
    for p in range(1, nc):
        out[p] = F[p - 1] - F[p]
    out[nc] = F[nc - 1]


@kernel
def _rhs(S, Xs, out):
    """Accelerations of the compact balls at positions ``Xs`` into ``out``."""
    _accelerations(Xs, S.FS, S.TR, out, S.ints[I_M], S.ints[I_MODE], S.fs[F_ALPHA])


# =========================================================================================
# one DOP853 step for x'' = a(x), y = (x, v), f = (v, a)
# =========================================================================================
# ---- BEGIN GENERATED STAGES (python -m chainrun.solver._codegen) ----
@kernel
def _stages(S, h):
    """The 12 stages of a DOP853 step from (X0, V0, A0): new (X, V), stages in KV.

    DOP853 applied to y = (x, v), y' = (v, a(x)), written in Nystrom form: the
    stage velocities are eliminated, KV[s] holds the stage accelerations and
    KV[12] those at the step's end.
    """
    m = S.ints[I_M]
    mode = S.ints[I_MODE]
    alpha = S.fs[F_ALPHA]
    F, MK = S.FS, S.TR
    KV, X0, V0, A0, X, V = S.KV, S.X0, S.V0, S.A0, S.X, S.V
    for p in range(m):
        KV[0, p] = A0[p]
    for p in range(m):
        X[p] = X0[p] + h * (0.05260015195876773 * V0[p])
    _accelerations(X, F, MK, KV[1], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.0789002279381516 * V0[p] + h * (0.003112622984346139 * KV[0, p]))
    _accelerations(X, F, MK, KV[2], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.1183503419072274 * V0[p] + h * (0.0017508504286947032 * KV[0, p] + 0.00525255128608411 * KV[1, p]))
    _accelerations(X, F, MK, KV[3], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.2816496580927726 * V0[p] + h * (0.009915816237971964 * KV[0, p] + -0.05234336665618132 * KV[1, p] + 0.0820908153700972 * KV[2, p]))
    _accelerations(X, F, MK, KV[4], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.3333333333333333 * V0[p] + h * (0.03533793130488635 * KV[0, p] + -0.09581915952175495 * KV[2, p] + 0.11603678377242414 * KV[3, p]))
    _accelerations(X, F, MK, KV[5], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.25 * V0[p] + h * (0.018920483189113914 * KV[0, p] + -0.03815245266364541 * KV[2, p] + 0.05268745617004205 * KV[3, p] + -0.00220548669551055 * KV[4, p]))
    _accelerations(X, F, MK, KV[6], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.3076923076923077 * V0[p] + h * (0.03067021189623757 * KV[0, p] + -0.07975482628537983 * KV[2, p] + 0.0979912056772412 * KV[3, p] + -0.0014238754814449106 * KV[4, p] + -0.00014543770014516837 * KV[5, p]))
    _accelerations(X, F, MK, KV[7], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.6512820512820513 * V0[p] + h * (-0.15229089727622033 * KV[0, p] + 0.46966087733519885 * KV[2, p] + -0.06814140470279369 * KV[3, p] + 0.01071185753171531 * KV[4, p] + 0.31196985474604216 * KV[5, p] + -0.35982613247286355 * KV[6, p]))
    _accelerations(X, F, MK, KV[8], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.6 * V0[p] + h * (-0.11020716722377502 * KV[0, p] + 0.30128953154727944 * KV[2, p] + 0.07865735349516391 * KV[3, p] + 0.030838873981239242 * KV[4, p] + -0.31960414755130306 * KV[5, p] + -0.6851760518136165 * KV[6, p] + 0.8842016075650119 * KV[7, p]))
    _accelerations(X, F, MK, KV[9], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (0.8571428571428571 * V0[p] + h * (0.3721894995071433 * KV[0, p] + -0.5050736261155677 * KV[2, p] + -0.4614987464855827 * KV[3, p] + -0.06518509348541897 * KV[4, p] + 4.098038403866562 * KV[5, p] + 3.8922102844072377 * KV[6, p] + -7.025278165955339 * KV[7, p] + 0.06194438303648047 * KV[8, p]))
    _accelerations(X, F, MK, KV[10], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (1.0 * V0[p] + h * (-0.7650750098382327 * KV[0, p] + 0.8347994820739504 * KV[2, p] + 1.7559441441931152 * KV[3, p] + 0.23253698859550578 * KV[4, p] + 11.903719357881853 * KV[5, p] + -1.9034949405460306 * KV[6, p] + -10.951226401858388 * KV[7, p] + 1.3530625395360725 * KV[8, p] + -1.9602661600378632 * KV[9, p]))
    _accelerations(X, F, MK, KV[11], m, mode, alpha)
    for p in range(m):
        X[p] = X0[p] + h * (V0[p] + h * (0.05429373411656877 * KV[0, p] + 2.96687526183494 * KV[5, p] + 1.4186384244858756 * KV[6, p] + -4.016218126161175 * KV[7, p] + 0.10850859975965002 * KV[8, p] + -0.06086437986500647 * KV[9, p] + 0.028766485829147193 * KV[10, p]))
        V[p] = V0[p] + h * (0.054293734116568765 * KV[0, p] + 4.450312892752409 * KV[5, p] + 1.8915178993145003 * KV[6, p] + -5.801203960010585 * KV[7, p] + 0.3111643669578199 * KV[8, p] + -0.1521609496625161 * KV[9, p] + 0.20136540080403034 * KV[10, p] + 0.04471061572777259 * KV[11, p])
    _accelerations(X, F, MK, KV[12], m, mode, alpha)


@kernel
def _error_norm(S, h):
    """DOP853's error estimate of the last step, max over balls, scaled by the tolerance.

    Per component e = |h| e5^2 / (sqrt(d) sc), d = e5^2 + e3^2 / 100; the largest
    e^2 = h^2 e5^4 / (d sc^2) is kept as a fraction, so the loop takes no square
    root or division per ball. An infinite or NaN fraction is kept: it fails the
    step.
    """
    m = S.ints[I_M]
    KV, X0, V0, X, V = S.KV, S.X0, S.V0, S.X, S.V
    tol = S.fs[F_TOL]
    num = 0.0
    den = 1.0
    for p in range(m):
        e5 = h * (-0.18865188001798794 * KV[0, p] + 0.9962151331241323 * KV[3, p] + 0.23599761577747433 * KV[4, p] + -2.8546306823509116 * KV[5, p] + -4.082808827933706 * KV[6, p] + 6.038341535948958 * KV[7, p] + 0.39584534789657555 * KV[8, p] + -0.5259249995299615 * KV[9, p] + -0.014383242914573597 * KV[10, p])
        e3 = h * (-0.45385457342917346 * KV[0, p] + 2.6987585022618616 * KV[3, p] + 0.6812767760191378 * KV[4, p] + -16.885342816594818 * KV[5, p] + -13.987876814514605 * KV[6, p] + 27.96175549233409 * KV[7, p] + 0.3042333850581198 * KV[8, p] + -0.3335239499192926 * KV[9, p] + 0.014573998784681819 * KV[10, p])
        sc = tol + 64.0 * EPS * max(abs(X0[p]), abs(X[p]))
        n = e5 * e5 * e5 * e5
        d = (e5 * e5 + 0.01 * e3 * e3) * sc * sc
        if num < np.inf and not n * den <= num * d:
            num = n
            den = d
        e5 = 1.0 * (0.01312004499419488 * KV[0, p] + -1.2251564463762044 * KV[5, p] + -0.4957589496572502 * KV[6, p] + 1.6643771824549864 * KV[7, p] + -0.35032884874997366 * KV[8, p] + 0.3341791187130175 * KV[9, p] + 0.08192320648511571 * KV[10, p] + -0.022355307863886294 * KV[11, p])
        e3 = 1.0 * (-0.18980075407240762 * KV[0, p] + 4.450312892752409 * KV[5, p] + 1.8915178993145003 * KV[6, p] + -5.801203960010585 * KV[7, p] + -0.4226823213237919 * KV[8, p] + -0.1521609496625161 * KV[9, p] + 0.20136540080403034 * KV[10, p] + 0.02265179219836082 * KV[11, p])
        sc = tol + 64.0 * EPS * max(abs(V0[p]), abs(V[p]))
        n = e5 * e5 * e5 * e5
        d = (e5 * e5 + 0.01 * e3 * e3) * sc * sc
        if num < np.inf and not n * den <= num * d:
            num = n
            den = d
    return abs(h) * np.sqrt(num / den)


@kernel
def _dense_stages(S):
    """The three extra stages of the dense output (positions staged in XS)."""
    m = S.ints[I_M]
    mode = S.ints[I_MODE]
    alpha = S.fs[F_ALPHA]
    F, MK = S.FS, S.TR
    h = S.fs[F_HLAST]
    KV, X0, V0, Xs = S.KV, S.X0, S.V0, S.XS
    for p in range(m):
        Xs[p] = X0[p] + h * (0.1 * V0[p] + h * (0.005054351963776213 * KV[0, p] + -0.41267006753617264 * KV[5, p] + -0.11888400830261192 * KV[6, p] + 0.5112504000718059 * KV[7, p] + -0.05239733207549385 * KV[8, p] + 0.06981946420649211 * KV[9, p] + 0.003198200361512927 * KV[10, p] + -0.0003710086893090569 * KV[11, p]))
    _accelerations(Xs, F, MK, KV[13], m, mode, alpha)
    for p in range(m):
        Xs[p] = X0[p] + h * (0.2 * V0[p] + h * (0.009887781381457055 * KV[0, p] + -0.00760250313479944 * KV[5, p] + 0.047423345887574166 * KV[6, p] + -0.0363790659291871 * KV[7, p] + -0.021320408140087014 * KV[8, p] + 0.026772748548590852 * KV[9, p] + 0.0013364963323445063 * KV[10, p] + 0.001054215711719072 * KV[11, p] + -0.0011726106576121006 * KV[12, p]))
    _accelerations(Xs, F, MK, KV[14], m, mode, alpha)
    for p in range(m):
        Xs[p] = X0[p] + h * (0.7777777777777778 * V0[p] + h * (0.35886633997225575 * KV[0, p] + 9.38025080291835 * KV[5, p] + 7.477758624830405 * KV[6, p] + -15.729096304440624 * KV[7, p] + -0.3664913832247408 * KV[8, p] + 0.4520427193280568 * KV[9, p] + 0.024882489771726926 * KV[10, p] + 0.018743046880517162 * KV[11, p] + -0.02134289656466091 * KV[12, p] + -1.2931443036688188 * KV[13, p]))
    _accelerations(Xs, F, MK, KV[15], m, mode, alpha)


@kernel
def _dense_ball(S, p):
    """The three extra stages of the dense output at compact ball p alone.

    Each stage's accelerations at a ball need its positions one ball further each
    way, so the last stage at p needs the first on p - 3 .. p + 3. Every band is
    cut at the ends of p's cluster, where its forces stop.
    """
    mode = S.ints[I_MODE]
    alpha = S.fs[F_ALPHA]
    h = S.fs[F_HLAST]
    KV, X0, V0, Xs, F, MK = S.KV, S.X0, S.V0, S.XS, S.FS, S.TR
    c = _find_cluster(S, S.cb[p])
    o = S.coff[c]
    e = o + S.chi[c] - S.clo[c]
    lo = max(o, p - 3)
    hi = min(e, p + 3)
    for q in range(lo, hi + 1):
        Xs[q] = X0[q] + h * (0.1 * V0[q] + h * (0.005054351963776213 * KV[0, q] + -0.41267006753617264 * KV[5, q] + -0.11888400830261192 * KV[6, q] + 0.5112504000718059 * KV[7, q] + -0.05239733207549385 * KV[8, q] + 0.06981946420649211 * KV[9, q] + 0.003198200361512927 * KV[10, q] + -0.0003710086893090569 * KV[11, q]))
    _forces(Xs, F, MK, lo, hi, mode, alpha)
    for q in range(lo if lo == o else lo + 1, (hi if hi == e else hi - 1) + 1):
        KV[13, q] = (F[q - 1] if q > o else 0.0) - (F[q] if q < e else 0.0)
    lo = max(o, p - 2)
    hi = min(e, p + 2)
    for q in range(lo, hi + 1):
        Xs[q] = X0[q] + h * (0.2 * V0[q] + h * (0.009887781381457055 * KV[0, q] + -0.00760250313479944 * KV[5, q] + 0.047423345887574166 * KV[6, q] + -0.0363790659291871 * KV[7, q] + -0.021320408140087014 * KV[8, q] + 0.026772748548590852 * KV[9, q] + 0.0013364963323445063 * KV[10, q] + 0.001054215711719072 * KV[11, q] + -0.0011726106576121006 * KV[12, q]))
    _forces(Xs, F, MK, lo, hi, mode, alpha)
    for q in range(lo if lo == o else lo + 1, (hi if hi == e else hi - 1) + 1):
        KV[14, q] = (F[q - 1] if q > o else 0.0) - (F[q] if q < e else 0.0)
    lo = max(o, p - 1)
    hi = min(e, p + 1)
    for q in range(lo, hi + 1):
        Xs[q] = X0[q] + h * (0.7777777777777778 * V0[q] + h * (0.35886633997225575 * KV[0, q] + 9.38025080291835 * KV[5, q] + 7.477758624830405 * KV[6, q] + -15.729096304440624 * KV[7, q] + -0.3664913832247408 * KV[8, q] + 0.4520427193280568 * KV[9, q] + 0.024882489771726926 * KV[10, q] + 0.018743046880517162 * KV[11, q] + -0.02134289656466091 * KV[12, q] + -1.2931443036688188 * KV[13, q]))
    _forces(Xs, F, MK, lo, hi, mode, alpha)
    for q in range(lo if lo == o else lo + 1, (hi if hi == e else hi - 1) + 1):
        KV[15, q] = (F[q - 1] if q > o else 0.0) - (F[q] if q < e else 0.0)


@kernel(inline="always")
def _dense_rows(S, p):
    """Rows 3..6 of ball p's interpolant: h * D @ K for positions and velocities."""
    h = S.fs[F_HLAST]
    KV, FX, FV = S.KV, S.FX, S.FV
    FX[3, p] = h * h * (2.861169879683012 * KV[0, p] + 30.512155838528837 * KV[5, p] + -24.61264508865549 * KV[6, p] + -35.419609174711354 * KV[7, p] + -3.8634586281384 * KV[8, p] + 3.7761446592257824 * KV[9, p] + 0.5382666867527854 * KV[10, p] + 0.12984961919289312 * KV[11, p] + -0.14125972611089993 * KV[12, p] + -14.374598829726839 * KV[13, p] + 40.593984763959675 * KV[14, p])
    FV[3, p] = h * (-8.428938276109013 * KV[0, p] + 0.5667149535193777 * KV[5, p] + -3.0689499459498917 * KV[6, p] + 2.38466765651207 * KV[7, p] + 2.117034582445028 * KV[8, p] + -0.871391583777973 * KV[9, p] + 2.2404374302607883 * KV[10, p] + 0.6315787787694688 * KV[11, p] + -0.08899033645133331 * KV[12, p] + 18.148505520854727 * KV[13, p] + -9.194632392478356 * KV[14, p] + -4.436036387594894 * KV[15, p])
    FX[4, p] = h * h * (-17.921210306702967 * KV[0, p] + -124.22607870722848 * KV[5, p] + 273.1379593828121 * KV[6, p] + 96.31318087284055 * KV[7, p] + 27.68487015330039 * KV[8, p] + -29.055636475084697 * KV[9, p] + -3.0977069495595084 * KV[10, p] + 0.4625952063992359 * KV[11, p] + 0.21147048462990323 * KV[12, p] + 104.24898538523482 * KV[13, p] + -327.75842904664137 * KV[14, p])
    FV[4, p] = h * (10.427508642579134 * KV[0, p] + 242.28349177525817 * KV[5, p] + 165.20045171727028 * KV[6, p] + -374.5467547226902 * KV[7, p] + -22.113666853125306 * KV[8, p] + 7.733432668472264 * KV[9, p] + -30.674084731089398 * KV[10, p] + -9.332130526430229 * KV[11, p] + 15.697238121770845 * KV[12, p] + -31.139403219565178 * KV[13, p] + -9.35292435884448 * KV[14, p] + 35.81684148639408 * KV[15, p])
    FX[5, p] = h * h * (-8.999411590110816 * KV[0, p] + -250.14465065648486 * KV[5, p] + -7.345168174338197 * KV[6, p] + 324.41205855963244 * KV[7, p] + 1.3538496519789456 * KV[8, p] + 3.8566662410202324 * KV[9, p] + -0.5618712467427652 * KV[10, p] + -0.5475191693050367 * KV[11, p] + 0.45402652434053137 * KV[12, p] + 47.262978033508965 * KV[13, p] + -109.74095817349945 * KV[14, p])
    FV[5, p] = h * (19.985053242002433 * KV[0, p] + -387.0373087493518 * KV[5, p] + -189.17813819516758 * KV[6, p] + 527.8081592054236 * KV[7, p] + -11.57390253995963 * KV[8, p] + 6.8812326946963 * KV[9, p] + -1.0006050966910838 * KV[10, p] + 0.7777137798053443 * KV[11, p] + -2.778205752353508 * KV[12, p] + -60.19669523126412 * KV[13, p] + 84.32040550667716 * KV[14, p] + 11.99229113618279 * KV[15, p])
    FX[6, p] = h * h * (75.66260800528795 * KV[0, p] + 904.8218815202384 * KV[5, p] + -991.2456491432963 * KV[6, p] + -911.6644928639355 * KV[7, p] + -83.3439947560784 * KV[8, p] + 73.06569397631901 * KV[9, p] + 11.227103851084005 * KV[10, p] + -1.2324213700720026 * KV[11, p] + -0.5764911999188783 * KV[12, p] + -446.85829878732994 * KV[13, p] + 1370.1440607677018 * KV[14, p])
    FV[6, p] = h * (-25.69393346270375 * KV[0, p] + -154.18974869023643 * KV[5, p] + -231.5293791760455 * KV[6, p] + 357.6391179106141 * KV[7, p] + 93.40532418362432 * KV[8, p] + -37.45832313645163 * KV[9, p] + 104.0996495089623 * KV[10, p] + 29.8402934266605 * KV[11, p] + -43.53345659001114 * KV[12, p] + 96.32455395918828 * KV[13, p] + -39.17726167561544 * KV[14, p] + -149.72683625798564 * KV[15, p])


@kernel(fastmath={"contract"})
def _series_orders(TX, W, nc, m, alpha):
    """Orders 1 and up of the force series of every contact lane (see _taylor)."""
    a1 = alpha + 1.0
    nt = (nc + SERIES_TILE - 1) // SERIES_TILE
    f0 = 25  # row of f_0
    for k in range(1, 23):
        for p in range(nc):
            W[_tw(p, k)] = TX[k, p] - TX[k, p + 1]
        for t in range(nt):
            o = t * TILE_STRIDE
            c = o + k * SERIES_TILE
            f = o + f0 * SERIES_TILE
            e0 = alpha * W[c + 0] * W[f + 0]
            e1 = alpha * W[c + 1] * W[f + 1]
            e2 = alpha * W[c + 2] * W[f + 2]
            e3 = alpha * W[c + 3] * W[f + 3]
            e4 = alpha * W[c + 4] * W[f + 4]
            e5 = alpha * W[c + 5] * W[f + 5]
            e6 = alpha * W[c + 6] * W[f + 6]
            e7 = alpha * W[c + 7] * W[f + 7]
            e8 = alpha * W[c + 8] * W[f + 8]
            e9 = alpha * W[c + 9] * W[f + 9]
            e10 = alpha * W[c + 10] * W[f + 10]
            e11 = alpha * W[c + 11] * W[f + 11]
            e12 = alpha * W[c + 12] * W[f + 12]
            e13 = alpha * W[c + 13] * W[f + 13]
            e14 = alpha * W[c + 14] * W[f + 14]
            e15 = alpha * W[c + 15] * W[f + 15]
            d0 = 0.0
            d1 = 0.0
            d2 = 0.0
            d3 = 0.0
            d4 = 0.0
            d5 = 0.0
            d6 = 0.0
            d7 = 0.0
            d8 = 0.0
            d9 = 0.0
            d10 = 0.0
            d11 = 0.0
            d12 = 0.0
            d13 = 0.0
            d14 = 0.0
            d15 = 0.0
            for j in range(1, k, 2):
                w = a1 * J_OVER_K[k, j] - 1.0
                c = o + j * SERIES_TILE
                f = o + (f0 + k - j) * SERIES_TILE
                d0 += w * W[c + 0] * W[f + 0]
                d1 += w * W[c + 1] * W[f + 1]
                d2 += w * W[c + 2] * W[f + 2]
                d3 += w * W[c + 3] * W[f + 3]
                d4 += w * W[c + 4] * W[f + 4]
                d5 += w * W[c + 5] * W[f + 5]
                d6 += w * W[c + 6] * W[f + 6]
                d7 += w * W[c + 7] * W[f + 7]
                d8 += w * W[c + 8] * W[f + 8]
                d9 += w * W[c + 9] * W[f + 9]
                d10 += w * W[c + 10] * W[f + 10]
                d11 += w * W[c + 11] * W[f + 11]
                d12 += w * W[c + 12] * W[f + 12]
                d13 += w * W[c + 13] * W[f + 13]
                d14 += w * W[c + 14] * W[f + 14]
                d15 += w * W[c + 15] * W[f + 15]
            for j in range(2, k, 2):
                w = a1 * J_OVER_K[k, j] - 1.0
                c = o + j * SERIES_TILE
                f = o + (f0 + k - j) * SERIES_TILE
                e0 += w * W[c + 0] * W[f + 0]
                e1 += w * W[c + 1] * W[f + 1]
                e2 += w * W[c + 2] * W[f + 2]
                e3 += w * W[c + 3] * W[f + 3]
                e4 += w * W[c + 4] * W[f + 4]
                e5 += w * W[c + 5] * W[f + 5]
                e6 += w * W[c + 6] * W[f + 6]
                e7 += w * W[c + 7] * W[f + 7]
                e8 += w * W[c + 8] * W[f + 8]
                e9 += w * W[c + 9] * W[f + 9]
                e10 += w * W[c + 10] * W[f + 10]
                e11 += w * W[c + 11] * W[f + 11]
                e12 += w * W[c + 12] * W[f + 12]
                e13 += w * W[c + 13] * W[f + 13]
                e14 += w * W[c + 14] * W[f + 14]
                e15 += w * W[c + 15] * W[f + 15]
            c = o + (f0 + k) * SERIES_TILE
            f = o + 48 * SERIES_TILE
            W[c + 0] = (e0 + d0) * W[f + 0]
            W[c + 1] = (e1 + d1) * W[f + 1]
            W[c + 2] = (e2 + d2) * W[f + 2]
            W[c + 3] = (e3 + d3) * W[f + 3]
            W[c + 4] = (e4 + d4) * W[f + 4]
            W[c + 5] = (e5 + d5) * W[f + 5]
            W[c + 6] = (e6 + d6) * W[f + 6]
            W[c + 7] = (e7 + d7) * W[f + 7]
            W[c + 8] = (e8 + d8) * W[f + 8]
            W[c + 9] = (e9 + d9) * W[f + 9]
            W[c + 10] = (e10 + d10) * W[f + 10]
            W[c + 11] = (e11 + d11) * W[f + 11]
            W[c + 12] = (e12 + d12) * W[f + 12]
            W[c + 13] = (e13 + d13) * W[f + 13]
            W[c + 14] = (e14 + d14) * W[f + 14]
            W[c + 15] = (e15 + d15) * W[f + 15]
        s = SERIES_SCALE[k]
        for p in range(m):
            fl = W[_tw(p - 1, f0 + k)] if p > 0 else 0.0
            fr = W[_tw(p, f0 + k)] if p < nc else 0.0
            TX[k + 2, p] = (fl - fr) * s
    # the compressions' last two orders, for the bounds (_series_bounds)
    for p in range(nc):
        W[_tw(p, 23)] = TX[23, p] - TX[23, p + 1]
        W[_tw(p, 24)] = TX[24, p] - TX[24, p + 1]


@kernel(fastmath={"contract"})
def _series_bounds(W, nc, h):
    """Bounds of every contact lane's compression over a series step [0, h].

    From the rows c_k of the work tiles into their rows LO_ROW, HI_ROW: the hull
    of the Bernstein coefficients of the lane's series up to degree DB, widened
    by the magnitude of the higher terms and by rounding, as _bernstein_range
    does for one contact.
    """
    nt = (nc + SERIES_TILE - 1) // SERIES_TILE
    h1 = h
    h2 = h1 * h
    h3 = h2 * h
    h4 = h3 * h
    h5 = h4 * h
    h6 = h5 * h
    h7 = h6 * h
    h8 = h7 * h
    h9 = h8 * h
    h10 = h9 * h
    h11 = h10 * h
    h12 = h11 * h
    h13 = h12 * h
    h14 = h13 * h
    h15 = h14 * h
    h16 = h15 * h
    h17 = h16 * h
    h18 = h17 * h
    h19 = h18 * h
    h20 = h19 * h
    h21 = h20 * h
    h22 = h21 * h
    h23 = h22 * h
    h24 = h23 * h
    for t in range(nt):
        for lane in range(SERIES_TILE):
            o = t * TILE_STRIDE + lane
            a0 = W[o]
            a1 = W[o + 1 * SERIES_TILE] * h1
            a2 = W[o + 2 * SERIES_TILE] * h2
            a3 = W[o + 3 * SERIES_TILE] * h3
            a4 = W[o + 4 * SERIES_TILE] * h4
            a5 = W[o + 5 * SERIES_TILE] * h5
            a6 = W[o + 6 * SERIES_TILE] * h6
            a7 = W[o + 7 * SERIES_TILE] * h7
            a8 = W[o + 8 * SERIES_TILE] * h8
            a9 = W[o + 9 * SERIES_TILE] * h9
            a10 = W[o + 10 * SERIES_TILE] * h10
            a11 = W[o + 11 * SERIES_TILE] * h11
            a12 = W[o + 12 * SERIES_TILE] * h12
            a13 = W[o + 13 * SERIES_TILE] * h13
            a14 = W[o + 14 * SERIES_TILE] * h14
            a15 = W[o + 15 * SERIES_TILE] * h15
            a16 = W[o + 16 * SERIES_TILE] * h16
            a17 = W[o + 17 * SERIES_TILE] * h17
            a18 = W[o + 18 * SERIES_TILE] * h18
            a19 = W[o + 19 * SERIES_TILE] * h19
            a20 = W[o + 20 * SERIES_TILE] * h20
            a21 = W[o + 21 * SERIES_TILE] * h21
            a22 = W[o + 22 * SERIES_TILE] * h22
            a23 = W[o + 23 * SERIES_TILE] * h23
            a24 = W[o + 24 * SERIES_TILE] * h24
            r = 64.0 * EPS * ((abs(a0) + abs(a2) + abs(a4) + abs(a6) + abs(a8) + abs(a10) + abs(a12) + abs(a14) + abs(a16)) + (abs(a1) + abs(a3) + abs(a5) + abs(a7) + abs(a9) + abs(a11) + abs(a13) + abs(a15))) + (abs(a17) + abs(a19) + abs(a21) + abs(a23)) + (abs(a18) + abs(a20) + abs(a22) + abs(a24))
            b1 = a0 + 0.0625 * a1
            b2 = a0 + 0.125 * a1 + 0.008333333333333333 * a2
            b3 = (a0 + 0.025 * a2) + (0.1875 * a1 + 0.0017857142857142857 * a3)
            b4 = (a0 + 0.05 * a2 + 0.0005494505494505495 * a4) + (0.25 * a1 + 0.007142857142857143 * a3)
            b5 = (a0 + 0.08333333333333333 * a2 + 0.0027472527472527475 * a4) + (0.3125 * a1 + 0.017857142857142856 * a3 + 0.00022893772893772894 * a5)
            b6 = (a0 + 0.125 * a2 + 0.008241758241758242 * a4 + 0.00012487512487512488 * a6) + (0.375 * a1 + 0.03571428571428571 * a3 + 0.0013736263736263737 * a5)
            b7 = (a0 + 0.175 * a2 + 0.019230769230769232 * a4 + 0.0008741258741258741 * a6) + (0.4375 * a1 + 0.0625 * a3 + 0.004807692307692308 * a5 + 8.741258741258741e-05 * a7)
            b8 = (a0 + 0.23333333333333334 * a2 + 0.038461538461538464 * a4 + 0.0034965034965034965 * a6 + 7.77000777000777e-05 * a8) + (0.5 * a1 + 0.1 * a3 + 0.01282051282051282 * a5 + 0.0006993006993006993 * a7)
            b9 = (a0 + 0.3 * a2 + 0.06923076923076923 * a4 + 0.01048951048951049 * a6 + 0.0006993006993006993 * a8) + (0.5625 * a1 + 0.15 * a3 + 0.028846153846153848 * a5 + 0.003146853146853147 * a7 + 8.741258741258741e-05 * a9)
            b10 = (a0 + 0.375 * a2 + 0.11538461538461539 * a4 + 0.026223776223776224 * a6 + 0.0034965034965034965 * a8 + 0.00012487512487512488 * a10) + (0.625 * a1 + 0.21428571428571427 * a3 + 0.057692307692307696 * a5 + 0.01048951048951049 * a7 + 0.0008741258741258741 * a9)
            b11 = (a0 + 0.4583333333333333 * a2 + 0.1813186813186813 * a4 + 0.057692307692307696 * a6 + 0.01282051282051282 * a8 + 0.0013736263736263737 * a10) + (0.6875 * a1 + 0.29464285714285715 * a3 + 0.10576923076923077 * a5 + 0.028846153846153848 * a7 + 0.004807692307692308 * a9 + 0.00022893772893772894 * a11)
            b12 = (a0 + 0.55 * a2 + 0.27197802197802196 * a4 + 0.11538461538461539 * a6 + 0.038461538461538464 * a8 + 0.008241758241758242 * a10 + 0.0005494505494505495 * a12) + (0.75 * a1 + 0.39285714285714285 * a3 + 0.1813186813186813 * a5 + 0.06923076923076923 * a7 + 0.019230769230769232 * a9 + 0.0027472527472527475 * a11)
            b13 = (a0 + 0.65 * a2 + 0.39285714285714285 * a4 + 0.21428571428571427 * a6 + 0.1 * a8 + 0.03571428571428571 * a10 + 0.007142857142857143 * a12) + (0.8125 * a1 + 0.5107142857142857 * a3 + 0.29464285714285715 * a5 + 0.15 * a7 + 0.0625 * a9 + 0.017857142857142856 * a11 + 0.0017857142857142857 * a13)
            b14 = (a0 + 0.7583333333333333 * a2 + 0.55 * a4 + 0.375 * a6 + 0.23333333333333334 * a8 + 0.125 * a10 + 0.05 * a12 + 0.008333333333333333 * a14) + (0.875 * a1 + 0.65 * a3 + 0.4583333333333333 * a5 + 0.3 * a7 + 0.175 * a9 + 0.08333333333333333 * a11 + 0.025 * a13)
            b15 = (a0 + 0.875 * a2 + 0.75 * a4 + 0.625 * a6 + 0.5 * a8 + 0.375 * a10 + 0.25 * a12 + 0.125 * a14) + (0.9375 * a1 + 0.8125 * a3 + 0.6875 * a5 + 0.5625 * a7 + 0.4375 * a9 + 0.3125 * a11 + 0.1875 * a13 + 0.0625 * a15)
            b16 = (a0 + 1.0 * a2 + 1.0 * a4 + 1.0 * a6 + 1.0 * a8 + 1.0 * a10 + 1.0 * a12 + 1.0 * a14 + 1.0 * a16) + (1.0 * a1 + 1.0 * a3 + 1.0 * a5 + 1.0 * a7 + 1.0 * a9 + 1.0 * a11 + 1.0 * a13 + 1.0 * a15)
            W[o + LO_ROW * SERIES_TILE] = min(a0, b1, b2, b3, b4, b5, b6, b7, b8, b9, b10, b11, b12, b13, b14, b15, b16) - r
            W[o + HI_ROW * SERIES_TILE] = max(a0, b1, b2, b3, b4, b5, b6, b7, b8, b9, b10, b11, b12, b13, b14, b15, b16) + r
# ---- END GENERATED STAGES ----


@kernel(inline="always")
def _tw(p, r):
    """Index in the work tiles TW of row r of contact lane p."""
    return (p // SERIES_TILE) * TILE_STRIDE + r * SERIES_TILE + p % SERIES_TILE


@kernel(fastmath={"contract"})
def _taylor(S):
    """Taylor series of every compact ball's x(t) at the step's start (X0, V0) to order PT.

    Between events the active set is fixed and the motion analytic, with a radius of
    convergence set by the nearest complex time where a compression vanishes (about 3
    time units inside a Hertz wave), so the series takes steps several times those of
    DOP853 at the same tolerance, and is its own dense output. The series of the
    accelerations follow from those of the positions: for f = c |c|^(alpha-1),
    c f' = alpha c' f gives f_k = sum_{j=1..k} ((alpha+1) j - k) c_j f_{k-j} / (k c_0);
    for alpha = 1, f = c (Jorba & Zou, see the module's references).

    The series are order-major (row k holds every ball's term of order k), and every
    loop runs across the window, clusters and all: the gap after a cluster's last ball
    is a contact lane whose force is masked to 0. The lanes are independent, so the
    loops vectorise, where a loop over one contact's orders would be one long chain;
    each order's sum over the lower ones is a pass over the window's tiles
    (_series_orders, generated by _codegen).

    Returns the longest step whose truncation (estimated by the last two terms of x
    and of v) is within TAYLOR_TOL of the tolerance, or 0 where the series does not
    exist: a compression exactly 0 (just closed) is a branch point of c^alpha, which
    DOP853 steps through.
    """
    m = S.ints[I_M]
    nc = m - 1  # contact lanes: lane p joins compact balls p and p + 1
    mode = S.ints[I_MODE]
    alpha = S.fs[F_ALPHA]
    TX, W, MK = S.TX, S.TW, S.TR
    X0, V0 = S.X0, S.V0
    for p in range(m):
        TX[0, p] = X0[p]
        TX[1, p] = V0[p]
    # the last tile's spare lanes carry no force
    f0 = PT + 1  # row of the forces' f_0
    for p in range(nc, (nc + SERIES_TILE - 1) // SERIES_TILE * SERIES_TILE):
        W[_tw(p, f0)] = 0.0
        W[_tw(p, 2 * PT)] = 0.0
    for p in range(nc):
        c0 = X0[p] - X0[p + 1]
        if c0 == 0.0 and MK[p] != 0.0 and mode != 0:
            return 0.0
        W[_tw(p, 0)] = c0
        W[_tw(p, f0)] = _force(c0, mode, alpha) * MK[p]
        W[_tw(p, 2 * PT)] = MK[p] / c0 if MK[p] != 0.0 and mode != 0 else 0.0
    for p in range(m):
        fl = W[_tw(p - 1, f0)] if p > 0 else 0.0
        fr = W[_tw(p, f0)] if p < nc else 0.0
        TX[2, p] = 0.5 * (fl - fr)
    if mode == 0:
        for k in range(1, PT + 1):
            for p in range(nc):
                W[_tw(p, k)] = TX[k, p] - TX[k, p + 1]
            if k < PT - 1:
                s = 1.0 / ((k + 1) * (k + 2))
                for p in range(m):
                    fl = W[_tw(p - 1, k)] * MK[p - 1] if p > 0 else 0.0
                    fr = W[_tw(p, k)] * MK[p] if p < nc else 0.0
                    TX[k + 2, p] = (fl - fr) * s
    else:
        _series_orders(TX, W, nc, m, alpha)
    # truncation: the last two terms of x and of v against the tolerance of each ball
    tol = TAYLOR_TOL * S.fs[F_TOL]
    qx1 = 0.0
    qx2 = 0.0
    qv1 = 0.0
    qv2 = 0.0
    for p in range(m):
        ax = 1.0 / (tol + 64.0 * EPS * abs(X0[p]))
        av = 1.0 / (tol + 64.0 * EPS * abs(V0[p]))
        t1 = abs(TX[PT, p])
        t2 = abs(TX[PT - 1, p])
        qx1 = max(qx1, t1 * ax)
        qx2 = max(qx2, t2 * ax)
        qv1 = max(qv1, PT * t1 * av)
        qv2 = max(qv2, (PT - 1) * t2 * av)
    if not (qx1 < np.inf and qx2 < np.inf and qv1 < np.inf and qv2 < np.inf):
        return 0.0
    S.fs[F_QX1] = qx1
    S.fs[F_QX2] = qx2
    S.fs[F_QV1] = qv1
    S.fs[F_QV2] = qv2
    h = np.inf
    if qx1 > 0.0:
        h = min(h, qx1 ** (-1.0 / PT))
    if qx2 > 0.0:
        h = min(h, qx2 ** (-1.0 / (PT - 1)))
    if qv1 > 0.0:
        h = min(h, qv1 ** (-1.0 / (PT - 1)))
    if qv2 > 0.0:
        h = min(h, qv2 ** (-1.0 / (PT - 2)))
    return 0.9 * h


@kernel(inline="always")
def _taylor_at(S, p, s):
    """(x, v) of compact ball p at time s after the step's start, from its series."""
    T = S.TX
    x = T[PT, p]
    v = PT * T[PT, p]
    for k in range(PT - 1, 0, -1):
        x = x * s + T[k, p]
        v = v * s + k * T[k, p]
    return x * s + T[0, p], v


@kernel(fastmath={"contract"})
def _taylor_step(S, h):
    """Evaluate the series at h into (X, V, A); return the truncation estimate / tolerance.

    Horner across the window, order by order (the balls' chains are independent).
    """
    m = S.ints[I_M]
    T, X, V = S.TX, S.X, S.V
    for p in range(m):
        X[p] = T[PT, p]
        V[p] = PT * T[PT, p]
    for k in range(PT - 1, 0, -1):
        for p in range(m):
            X[p] = X[p] * h + T[k, p]
            V[p] = V[p] * h + k * T[k, p]
    for p in range(m):
        X[p] = X[p] * h + T[0, p]
    _rhs(S, X, S.A)
    for p in range(m):
        if not (np.isfinite(X[p]) and np.isfinite(V[p])):
            return np.inf
    h1 = abs(h) ** (PT - 2)
    return max(S.fs[F_QX1] * h1 * h * h, S.fs[F_QX2] * h1 * h,
               S.fs[F_QV1] * h1 * h, S.fs[F_QV2] * h1)


@kernel(inline="always")
def _series_at(T, s):
    """The polynomial sum_k T[k] s^k (Horner)."""
    y = T[PT]
    for k in range(PT - 1, -1, -1):
        y = y * s + T[k]
    return y


@kernel
def _contact_series(S, j):
    """The series of contact j's compression over the last (series) step into TD.

    A free ball's series is its straight line.
    """
    pa = S.bmap[j]
    pb = S.bmap[j + 1]
    TD, TX = S.TD, S.TX
    t0 = S.fs[F_TPREV]
    if pa >= 0:
        for k in range(PT + 1):
            TD[k] = TX[k, pa]
    else:
        for k in range(2, PT + 1):
            TD[k] = 0.0
        TD[0] = S.bx[j] + S.bv[j] * (t0 - S.bt[j])
        TD[1] = S.bv[j]
    if pb >= 0:
        for k in range(PT + 1):
            TD[k] -= TX[k, pb]
    else:
        TD[0] -= S.bx[j + 1] + S.bv[j + 1] * (t0 - S.bt[j + 1])
        TD[1] -= S.bv[j + 1]


@kernel
def _sample_series(S, ns, h):
    """TD's polynomial at s = h (i + 1) / ns, i < ns, into TS[1] (TS[0]: the s).

    All samples at once: independent Horner chains, which vectorise.
    """
    SS, YS, TD = S.TS[0], S.TS[1], S.TD
    for i in range(ns):
        SS[i] = (i + 1) / ns * h
        YS[i] = TD[PT]
    for k in range(PT - 1, -1, -1):
        tk = TD[k]
        for i in range(ns):
            YS[i] = YS[i] * SS[i] + tk


@kernel
def _pressed_in_step(S, j):
    """Whether fresh contact j was pressed beyond eps_rel inside the last series step."""
    h = S.fs[F_HLAST]
    epsrel = S.fs[F_EPSREL]
    _contact_series(S, j)
    if _bernstein_range(S.TD, h, S.TS[0])[1] <= epsrel:
        return False
    ns = N_SERIES_SAMPLES
    _sample_series(S, ns, h)
    for i in range(ns):
        if S.TS[1, i] > epsrel:
            return True
    return False


@kernel
def _bernstein_range(T, h, B):
    """Bounds of the polynomial sum_k T[k] s^k over s in [0, h] (B: scratch).

    The smallest and largest Bernstein coefficients of its terms up to degree DB
    (the values at the ends are the first and last), widened by the magnitude of the
    higher terms and by rounding. (R. T. Farouki, Computer Aided Geometric Design 29,
    2012: the Bernstein polynomial basis, a centennial retrospective.)
    """
    for i in range(DB + 1):
        B[i] = 0.0
    hk = 1.0
    tot = 0.0
    for k in range(DB + 1):
        a = T[k] * hk
        tot += abs(a)
        hk *= h
        for i in range(k, DB + 1):
            B[i] += _BERN[k, i] * a
    tail = 0.0
    for k in range(DB + 1, PT + 1):
        tail += abs(T[k]) * hk
        hk *= h
    lo = np.inf
    hi = -np.inf
    for i in range(DB + 1):
        lo = min(lo, B[i])
        hi = max(hi, B[i])
    r = tail + 64.0 * EPS * tot
    return lo - r, hi + r


@kernel
def _curvature_bound(S, j):
    """A bound on |c''| of contact j over the last (DOP853) step: the larger of |c''| at
    its two ends (the step is short)."""
    pa = S.bmap[j]
    pb = S.bmap[j + 1]
    g0 = (S.A0[pa] if pa >= 0 else 0.0) - (S.A0[pb] if pb >= 0 else 0.0)
    g1 = (S.A[pa] if pa >= 0 else 0.0) - (S.A[pb] if pb >= 0 else 0.0)
    return max(abs(g0), abs(g1))


@kernel
def _stays_open(T, h, level, floor, D, B):
    """Whether an open contact whose compression is sum_k T[k] s^k can neither close nor
    engage for s in [0, h] (D, B: scratch).

    It closes only where its compression c reaches 0 at a rate of at least the floor,
    and engages only where c reaches its level (> 0). Upper bounds of c and of c' over
    [0, h] are the sums of their series' positive terms, and, where that of c' is not
    below the floor, the Bernstein bound of c' (_bernstein_range): behind a Hertz wave
    the ball just released and its cluster's first ball touch within rounding and part
    at rates far below the floor, and c' is a sum of large terms of both signs that
    cancel, which only the second bound sees.
    """
    cmax = T[0]
    cabs = abs(T[0])
    wmax = T[1]
    wabs = abs(T[1])
    hk1 = 1.0  # h^(k-1)
    for k in range(1, PT + 1):
        a = T[k] * hk1 * h
        cmax += max(a, 0.0)
        cabs += abs(a)
        if k >= 2:
            b = k * T[k] * hk1
            wmax += max(b, 0.0)
            wabs += abs(b)
        hk1 *= h
    cmax += 64.0 * EPS * cabs
    wmax += 64.0 * EPS * wabs
    if not cmax < level:
        return False
    if cmax < 0.0 or wmax < floor:
        return True
    for k in range(PT):
        D[k] = (k + 1) * T[k + 1]
    D[PT] = 0.0
    return _bernstein_range(D, h, B)[1] < floor


@kernel
def _step(S, h):
    """Take a trial step of size h from (X0, V0, A0); results in X, V, A; return error norm.

    By the series if this step's start chose it (I_TAY), else by DOP853.
    """
    if S.ints[I_TAY] == 1:
        return _taylor_step(S, h)
    m = S.ints[I_M]
    S.ints[I_DENSE] = 0
    S.ints[I_DSTAMP] += 1
    _stages(S, h)
    for p in range(m):
        S.A[p] = S.KV[_NS, p]
    err = _error_norm(S, h)
    if not np.isfinite(err):
        return np.inf
    for p in range(m):
        if not (np.isfinite(S.X[p]) and np.isfinite(S.V[p])):
            return np.inf
    return err


@kernel(inline="always")
def _interp_rows(S, p):
    """Rows 0..6 of compact ball p's interpolant (its dense stages are in KV)."""
    h = S.fs[F_HLAST]
    KV, FX, FV = S.KV, S.FX, S.FV
    dx = S.X[p] - S.X0[p]
    dv = S.V[p] - S.V0[p]
    FX[0, p] = dx
    FX[1, p] = h * S.V0[p] - dx
    FX[2, p] = 2.0 * dx - h * (S.V[p] + S.V0[p])
    FV[0, p] = dv
    FV[1, p] = h * KV[0, p] - dv
    FV[2, p] = 2.0 * dv - h * (KV[_NS, p] + KV[0, p])
    _dense_rows(S, p)


@kernel
def _dense(S):
    """Build the order-7 interpolant of the last accepted step for every ball."""
    if S.ints[I_DENSE] == 1:
        return
    _dense_stages(S)
    for p in range(S.ints[I_M]):
        _interp_rows(S, p)
    S.ints[I_DENSE] = 1


@kernel
def _dense_at(S, p):
    """Build the interpolant of compact ball p alone, unless it is built already.

    An event search asks for the two balls of a contact or so per step; the three
    extra stages they need reach three balls each way (_dense_ball), so the cost does
    not grow with the window.
    """
    if S.ints[I_DENSE] == 1 or S.DM[p] == S.ints[I_DSTAMP]:
        return
    _dense_ball(S, p)
    _interp_rows(S, p)
    S.DM[p] = S.ints[I_DSTAMP]


@kernel(inline="always")
def _poly(F, y0, p, th):
    u = 1.0 - th
    return y0 + th * (F[0, p] + u * (F[1, p] + th * (F[2, p] + u * (F[3, p] + th * (
        F[4, p] + u * (F[5, p] + th * F[6, p]))))))


# =========================================================================================
# positions of any ball inside the last step (theta in [0, 1]) or now
# =========================================================================================
@kernel(inline="always")
def _ball_at(S, b, th):
    """(x, v) of ball b at t_prev + th * h_last (its interpolant is built if need be)."""
    p = S.bmap[b]
    if p >= 0:
        if th >= 1.0:
            return S.X[p], S.V[p]
        if th <= 0.0:
            return S.X0[p], S.V0[p]
        if S.ints[I_TAY] == 1:
            return _taylor_at(S, p, th * S.fs[F_HLAST])
        _dense_at(S, p)
        return _poly(S.FX, S.X0[p], p, th), _poly(S.FV, S.V0[p], p, th)
    t = S.fs[F_TPREV] + th * S.fs[F_HLAST]
    return S.bx[b] + S.bv[b] * (t - S.bt[b]), S.bv[b]


@kernel(inline="always")
def _ball_now(S, b):
    p = S.bmap[b]
    if p >= 0:
        return S.X[p], S.V[p], S.A[p]
    return S.bx[b] + S.bv[b] * (S.fs[F_T] - S.bt[b]), S.bv[b], 0.0


# =========================================================================================
# heap of free-pair collisions (lazy invalidation by per-contact stamps)
# =========================================================================================
@kernel
def _heap_push(S, t, j):
    n = S.ints[I_NHEAP]
    if n >= S.hp_t.shape[0]:
        _heap_compact(S)
        n = S.ints[I_NHEAP]
        if n >= S.hp_t.shape[0]:
            return
    i = n
    S.hp_t[i] = t
    S.hp_j[i] = j
    S.hp_s[i] = S.stamp[j]
    S.ints[I_NHEAP] = n + 1
    while i > 0:
        q = (i - 1) // 2
        if S.hp_t[q] <= S.hp_t[i]:
            break
        _heap_swap(S, i, q)
        i = q


@kernel(inline="always")
def _heap_swap(S, a, b):
    S.hp_t[a], S.hp_t[b] = S.hp_t[b], S.hp_t[a]
    S.hp_j[a], S.hp_j[b] = S.hp_j[b], S.hp_j[a]
    S.hp_s[a], S.hp_s[b] = S.hp_s[b], S.hp_s[a]


@kernel
def _heap_pop(S):
    n = S.ints[I_NHEAP] - 1
    S.ints[I_NHEAP] = n
    if n == 0:
        return
    _heap_swap(S, 0, n)
    i = 0
    while True:
        l = 2 * i + 1
        if l >= n:
            break
        r = l + 1
        c = l
        if r < n and S.hp_t[r] < S.hp_t[l]:
            c = r
        if S.hp_t[i] <= S.hp_t[c]:
            break
        _heap_swap(S, i, c)
        i = c


@kernel
def _heap_valid_top(S):
    """Drop stale entries; return whether a valid entry is on top."""
    while S.ints[I_NHEAP] > 0:
        j = S.hp_j[0]
        if S.hp_s[0] == S.stamp[j]:
            return True
        _heap_pop(S)
    return False


@kernel
def _heap_compact(S):
    n = S.ints[I_NHEAP]
    k = 0
    for i in range(n):
        j = S.hp_j[i]
        if S.hp_s[i] == S.stamp[j]:
            S.hp_t[k] = S.hp_t[i]
            S.hp_j[k] = j
            S.hp_s[k] = S.hp_s[i]
            k += 1
    S.ints[I_NHEAP] = k
    # re-heapify
    for i in range(k // 2 - 1, -1, -1):
        q = i
        while True:
            l = 2 * q + 1
            if l >= k:
                break
            r = l + 1
            c = l
            if r < k and S.hp_t[r] < S.hp_t[l]:
                c = r
            if S.hp_t[q] <= S.hp_t[c]:
                break
            _heap_swap(S, q, c)
            q = c


@kernel
def _schedule_pair(S, j):
    """Predict the collision of free balls j, j+1 if they approach at >= floor."""
    if j < 0 or j >= S.cst.shape[0] or S.bmap.shape[0] < 2:
        return
    if _find_cluster(S, j) >= 0 or _find_cluster(S, j + 1) >= 0:
        return
    w = S.bv[j] - S.bv[j + 1]
    if not (w >= S.fs[F_FLOOR]):
        return
    t = S.fs[F_T]
    c = (S.bx[j] + S.bv[j] * (t - S.bt[j])) - (S.bx[j + 1] + S.bv[j + 1] * (t - S.bt[j + 1]))
    tc = t - c / w if c < 0.0 else t
    _heap_push(S, tc, j)


# =========================================================================================
# cluster bookkeeping (the list is sorted by lo and small)
# =========================================================================================
@kernel(inline="always")
def _find_cluster(S, b):
    lo = 0
    hi = S.ints[I_NCL] - 1
    while lo <= hi:
        mid = (lo + hi) // 2
        if S.chi[mid] < b:
            lo = mid + 1
        elif S.clo[mid] > b:
            hi = mid - 1
        else:
            return mid
    return -1


@kernel
def _sync(S):
    """Write the compact state back to the balls (all at the current time).

    Called before every change of structure, so each cluster's energy is projected
    back to its value at the last change first.
    """
    _project_energy(S)
    t = S.fs[F_T]
    for p in range(S.ints[I_M]):
        b = S.cb[p]
        S.bx[b] = S.X[p]
        S.bv[b] = S.V[p]
        S.bt[b] = t


@kernel
def _remove_cluster(S, c):
    n = S.ints[I_NCL]
    for i in range(c, n - 1):
        S.clo[i] = S.clo[i + 1]
        S.chi[i] = S.chi[i + 1]
    S.ints[I_NCL] = n - 1


@kernel
def _insert_cluster(S, lo, hi):
    n = S.ints[I_NCL]
    if n >= S.clo.shape[0]:
        return False
    i = n
    while i > 0 and S.clo[i - 1] > lo:
        S.clo[i] = S.clo[i - 1]
        S.chi[i] = S.chi[i - 1]
        i -= 1
    S.clo[i] = lo
    S.chi[i] = hi
    S.ints[I_NCL] = n + 1
    return True


@kernel(inline="always")
def _touch_ball(S, b):
    """Invalidate predictions involving ball b."""
    if b - 1 >= 0:
        S.stamp[b - 1] += 1
    if b < S.stamp.shape[0]:
        S.stamp[b] += 1


@kernel
def _free_ball(S, b):
    S.sep_t[b] = S.fs[F_T]
    S.sep_v[b] = S.bv[b]
    S.bmap[b] = -1
    _touch_ball(S, b)
    n = S.ints[I_NFREED]
    if n < S.freed.shape[0]:
        S.freed[n] = b
        S.ints[I_NFREED] = n + 1


@kernel
def _activate(S, j, state):
    """Make contact j active, joining the clusters/balls on both sides."""
    S.cst[j] = state
    cl = _find_cluster(S, j)
    cr = _find_cluster(S, j + 1)
    lo = j
    hi = j + 1
    if cl >= 0:
        lo = S.clo[cl]
    else:
        _touch_ball(S, j)
    if cr >= 0:
        hi = S.chi[cr]
        _remove_cluster(S, cr)
    else:
        _touch_ball(S, j + 1)
    if cl >= 0:
        _remove_cluster(S, cl)
    ok = _insert_cluster(S, lo, hi)
    S.ints[I_DIRTY] = 1
    return ok


@kernel
def _deactivate(S, j, level):
    """Make contact j inactive (engages again beyond ``level``), splitting its cluster."""
    S.cst[j] = OPEN
    S.lvl[j] = level
    c = _find_cluster(S, j)
    if c < 0:
        return True
    lo = S.clo[c]
    hi = S.chi[c]
    _remove_cluster(S, c)
    ok = True
    if j > lo:
        ok = ok and _insert_cluster(S, lo, j)
    else:
        _free_ball(S, j)
    if j + 1 < hi:
        ok = ok and _insert_cluster(S, j + 1, hi)
    else:
        _free_ball(S, j + 1)
    S.ints[I_DIRTY] = 1
    return ok


@kernel(inline="always")
def _potential(c, mode, alpha):
    """|c|^(alpha+1)/(alpha+1): the energy of an active contact's (odd-continued) force."""
    a = abs(c)
    if mode == 0:
        return 0.5 * a * a
    elif mode == 1:
        return 0.4 * a * a * np.sqrt(a)
    return a ** (alpha + 1.0) / (alpha + 1.0)


@kernel(inline="always")
def _mean_velocity(S, o, e):
    u = 0.0
    for p in range(o, e + 1):
        u += S.V[p]
    return u / (e - o + 1)


@kernel
def _cluster_energy(S, c):
    """Internal energy of cluster c: kinetic energy about its mean velocity plus potential.

    Momentum is conserved exactly, so this is conserved as well, and unlike the total
    energy it is computed with rounding relative to itself (a block moving at velocity
    1 with tiny relative motion has a large total and a tiny internal energy).
    """
    o = S.coff[c]
    e = o + S.chi[c] - S.clo[c]
    mode = S.ints[I_MODE]
    alpha = S.fs[F_ALPHA]
    u = _mean_velocity(S, o, e)
    en = 0.0
    for p in range(o, e + 1):
        en += 0.5 * (S.V[p] - u) * (S.V[p] - u)
    for p in range(o, e):
        en += _potential(S.X[p] - S.X[p + 1], mode, alpha)
    return en


@kernel
def _project_energy(S):
    """Restore each cluster's internal energy, conserved exactly between changes of structure.

    The velocities of the balls that move (|v| above 1e-3 of the cluster's largest)
    are scaled by one factor about their own mean: momentum is untouched, and balls
    nearly at rest (ahead of a wave, or in its wake) are never nudged into openings
    or collisions of rounding size. A correction that is not small against the
    motion it rescales (over 1e-6 of its kinetic energy) is not that motion's
    integration error, and is not applied. The corrections add up in fs[F_EPROJ], a
    measure of the integration error. (Hairer, Lubich & Wanner, Geometric Numerical
    Integration, IV.4: projection methods.)
    """
    for c in range(S.ints[I_NCL]):
        o = S.coff[c]
        e = o + S.chi[c] - S.clo[c]
        defect = S.cen[c] - _cluster_energy(S, c)
        vmax = 0.0
        for p in range(o, e + 1):
            vmax = max(vmax, abs(S.V[p]))
        cut = 1e-3 * vmax
        us = 0.0
        k = 0
        for p in range(o, e + 1):
            if abs(S.V[p]) > cut:
                us += S.V[p]
                k += 1
        if k < 2:
            continue
        us /= k
        ks = 0.0
        for p in range(o, e + 1):
            if abs(S.V[p]) > cut:
                ks += 0.5 * (S.V[p] - us) * (S.V[p] - us)
        if not (ks > 0.0 and abs(defect) <= 1e-6 * ks):
            continue
        S.fs[F_EPROJ] += abs(defect)
        lam = np.sqrt(1.0 + defect / ks)
        for p in range(o, e + 1):
            if abs(S.V[p]) > cut:
                S.V[p] = us + lam * (S.V[p] - us)


@kernel
def _rebuild(S):
    """Pack the clusters' balls into the compact arrays; 0 if done, else the size needed."""
    ncl = S.ints[I_NCL]
    m = 0
    for c in range(ncl):
        m += S.chi[c] - S.clo[c] + 1
    if m > S.X.shape[0]:
        return m
    for p in range(S.ints[I_M]):
        S.bmap[S.cb[p]] = -1
    t = S.fs[F_T]
    p = 0
    for c in range(ncl):
        S.coff[c] = p
        for b in range(S.clo[c], S.chi[c] + 1):
            S.cb[p] = b
            S.X[p] = S.bx[b] + S.bv[b] * (t - S.bt[b])
            S.V[p] = S.bv[b]
            S.bmap[b] = p
            p += 1
    S.ints[I_M] = m
    if m > S.ints[I_MAXWIN]:
        S.ints[I_MAXWIN] = m
    # contact lanes: 1 inside a cluster, 0 from a cluster's last ball to the next's first
    for p in range(m):
        S.TR[p] = 0.0
    for c in range(ncl):
        for p in range(S.coff[c], S.coff[c] + S.chi[c] - S.clo[c]):
            S.TR[p] = 1.0
    for c in range(ncl):
        S.cen[c] = _cluster_energy(S, c)
    _rhs(S, S.X, S.A)
    S.ints[I_DIRTY] = 0
    S.ints[I_DENSE] = 0
    S.ints[I_DSTAMP] += 1
    # balls that just lost their last contact may be on course to hit a free neighbour
    for i in range(S.ints[I_NFREED]):
        b = S.freed[i]
        _schedule_pair(S, b - 1)
        _schedule_pair(S, b)
    S.ints[I_NFREED] = 0
    return 0


# =========================================================================================
# events
# =========================================================================================
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
def _ball_end(S, b, th):
    """(x, v) of ball b at the start (th = 0) or the end (th = 1) of the last step."""
    p = S.bmap[b]
    if p >= 0:
        if th >= 1.0:
            return S.X[p], S.V[p]
        return S.X0[p], S.V0[p]
    t = S.fs[F_TPREV] + th * S.fs[F_HLAST]
    return S.bx[b] + S.bv[b] * (t - S.bt[b]), S.bv[b]


@kernel(inline="always")
def _contact_end(S, j, th):
    """_contact_at at th = 0 or 1, where no interpolant is needed (inlined)."""
    xl, vl = _ball_end(S, j, th)
    xr, vr = _ball_end(S, j + 1, th)
    return xl - xr, vl - vr, abs(xl) + abs(xr)


@kernel
def _crossing(S, j, ta, tb, ca, cb_, level):
    """Root of c_j(theta) = level in [ta, tb] (bracketed), by safeguarded regula falsi."""
    fa = ca - level
    fb = cb_ - level
    side = 0
    for _ in range(100):
        if tb - ta <= 4.0 * EPS * max(1.0, tb):
            break
        tm = tb - fb * (tb - ta) / (fb - fa) if fb != fa else 0.5 * (ta + tb)
        if not (tm > ta and tm < tb):
            tm = 0.5 * (ta + tb)
        cm, _w, _s = _contact_at(S, j, tm)
        fm = cm - level
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
        lev1 = S.fs[F_EPSREL]
        lev2 = lev1
    elif st == ACTIVE:
        lev1 = 0.0
        lev2 = 0.0
    elif st == DORMANT:
        # a dormant contact pressed slowly engages at the step's end (_post_step): its
        # force below FORCE_LOCATE is far under rounding; only a fast press is located
        if c1 < S.fs[F_LLOCATE]:
            return 2.0, 0, 0.0
        lev1 = S.fs[F_LDORM]
        lev2 = -S.fs[F_EPSREL]
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
def _find_event(S):
    """Scan the contacts touching clusters for the earliest event of the last step."""
    best = 2.0
    bj = -1
    bk = 0
    blev = 0.0
    ncont = S.cst.shape[0]
    h = S.fs[F_HLAST]
    q = 0.25 * h * h
    tay = S.ints[I_TAY] == 1
    W = S.TW
    if tay:
        _series_bounds(W, S.ints[I_M] - 1, h)
    epsrel = S.fs[F_EPSREL]
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
                    if W[_tw(p, LO_ROW)] > 0.0 or (st == FRESH and W[_tw(p, HI_ROW)] < epsrel):
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
                    if cq1 < S.fs[F_LLOCATE]:
                        continue
                elif st == OPEN:
                    if tay:
                        _contact_series(S, j)
                        if _stays_open(S.TD, h, S.lvl[j], S.fs[F_FLOOR], S.TS[1], S.TS[0]):
                            continue
                    elif max(cq0, cq1) + q * _curvature_bound(S, j) < 0.0:
                        continue  # stays open: below both of its levels (0 and lvl > 0)
            th, kind, lev = _contact_event(S, j, best)
            if th < best:
                best = th
                bj = j
                bk = kind
                blev = lev
    return best, bj, bk, blev


# =========================================================================================
# the step loop
# =========================================================================================
@kernel
def _save_start(S):
    for p in range(S.ints[I_M]):
        S.X0[p] = S.X[p]
        S.V0[p] = S.V[p]
        S.A0[p] = S.A[p]


@kernel
def _restore_start(S):
    for p in range(S.ints[I_M]):
        S.X[p] = S.X0[p]
        S.V[p] = S.V0[p]
        S.A[p] = S.A0[p]


@entry
def _snapshot(S, tout):
    """Fill (ox, ov) with the state at tout, inside the last step or in free flight."""
    t = S.fs[F_T]
    tp = S.fs[F_TPREV]
    hl = S.fs[F_HLAST]
    th = 1.0
    if tout < t and S.ints[I_JUMP] == 0 and hl > 0.0:
        th = (tout - tp) / hl
        if th < 0.0:
            th = 0.0
        if S.ints[I_TAY] == 0:
            _dense(S)
    for b in range(S.bx.shape[0]):
        p = S.bmap[b]
        if p >= 0:
            if th >= 1.0:
                S.ox[b] = S.X[p]
                S.ov[b] = S.V[p]
            elif S.ints[I_TAY] == 1:
                S.ox[b], S.ov[b] = _taylor_at(S, p, th * hl)
            else:
                S.ox[b] = _poly(S.FX, S.X0[p], p, th)
                S.ov[b] = _poly(S.FV, S.V0[p], p, th)
        else:
            S.ox[b] = S.bx[b] + S.bv[b] * (tout - S.bt[b])
            S.ov[b] = S.bv[b]


@kernel
def _engage_level(S, j):
    """Compression beyond which contact j, made inactive now, engages again.

    Its present compression plus eps_rel, and never within rounding of it (at tiny
    rtol eps_rel is below the rounding of the positions, and a level inside the
    rounding would flip the contact back and forth).
    """
    t = S.fs[F_T]
    xl = S.bx[j] + S.bv[j] * (t - S.bt[j])
    xr = S.bx[j + 1] + S.bv[j + 1] * (t - S.bt[j + 1])
    return max(xl - xr, 0.0) + max(S.fs[F_EPSREL], 4.0 * _rounding(abs(xl) + abs(xr)))


@kernel
def _apply_event(S, j, kind):
    """Set contact j's state from the event just reached (positions are synced)."""
    t = S.fs[F_T]
    if kind == EV_OPEN or kind == EV_RELEASE:
        ok = _deactivate(S, j, _engage_level(S, j))
        _log(S, t, j, kind)
    elif kind == EV_CLOSE:
        ok = _activate(S, j, ACTIVE)
        _log(S, t, j, EV_CLOSE)
    else:
        dormant = S.cst[j] == DORMANT
        ok = _activate(S, j, FRESH if dormant else ACTIVE)
        if not dormant:  # a dormant contact was closed already: nothing to log
            _log(S, t, j, EV_ENGAGE)
    return ok


@kernel
def _season(S):
    """Season the fresh contacts pressed beyond eps_rel in the last step (made ACTIVE).

    After every accepted step, whatever else it brings: a wave presses a fresh contact
    and passes on within a few steps, each of which may end on an event or an
    engagement at the front.
    """
    epsrel = S.fs[F_EPSREL]
    tay = S.ints[I_TAY] == 1 and S.ints[I_JUMP] == 0
    for c in range(S.ints[I_NCL]):
        o = S.coff[c]
        lo = S.clo[c]
        for j in range(lo, S.chi[c]):
            if S.cst[j] == FRESH:
                p = o + j - lo
                if S.X[p] - S.X[p + 1] > epsrel:
                    S.cst[j] = ACTIVE
                elif tay and S.TW[_tw(p, HI_ROW)] > epsrel and _pressed_in_step(S, j):
                    # pressed beyond eps_rel inside the step (a candidate only if its
                    # bound over the step, from the event scan, reaches eps_rel)
                    S.cst[j] = ACTIVE


@kernel
def _release_quiet(S):
    """Release the contacts below the floor.

    A seasoned contact is released when its relative motion and stored energy could
    not produce a speed above the floor (w^2 + 4 c^(alpha+1)/(alpha+1) < floor^2) and
    its neighbours do not load it (|c''| < floor). A fresh contact (at the front of a
    wave, never pressed beyond eps_rel) is released only when pulled apart beyond
    the rounding of its positions; it carried no force above the floor.
    """
    floor = S.fs[F_FLOOR]
    epsrel = S.fs[F_EPSREL]
    alpha = S.fs[F_ALPHA]
    nrel = 0
    for c in range(S.ints[I_NCL]):
        o = S.coff[c]
        lo = S.clo[c]
        for j in range(lo, S.chi[c]):
            p = o + j - lo
            st = S.cst[j]
            cj = S.X[p] - S.X[p + 1]
            if st == FRESH:
                if cj < -_rounding(abs(S.X[p]) + abs(S.X[p + 1])):
                    S.jbuf[nrel] = j
                    nrel += 1
            elif st == ACTIVE and cj < epsrel:
                w = S.V[p] - S.V[p + 1]
                if abs(w) >= floor or abs(S.A[p] - S.A[p + 1]) >= floor:
                    continue
                cp = cj if cj > 0.0 else 0.0
                if w * w + 4.0 * cp ** (alpha + 1.0) / (alpha + 1.0) < floor * floor:
                    S.jbuf[nrel] = j
                    nrel += 1
    if nrel == 0:
        return True
    _sync(S)
    t = S.fs[F_T]
    for i in range(nrel):
        j = S.jbuf[i]
        if not _deactivate(S, j, _engage_level(S, j)):
            return False
        _log(S, t, j, EV_RELEASE)
    return True


@kernel(inline="always")
def _due(S, j):
    """The event contact j is due at this instant, if its state disagrees with its motion.

    Several contacts can reach their levels at the same instant (a mirror-symmetric
    line opens two at once); the step lands on one, and the others sit within rounding
    of their level, possibly just past it, where no crossing will ever be seen.
    """
    t = S.fs[F_T]
    dl = S.bv[j] * (t - S.bt[j])
    dr = S.bv[j + 1] * (t - S.bt[j + 1])
    xl = S.bx[j] + dl
    xr = S.bx[j + 1] + dr
    c = xl - xr
    w = S.bv[j] - S.bv[j + 1]
    # the rounding of a free ball's x + v (t - tref) comes from its terms, not its value;
    # and t itself is resolved only to EPS t, in which balls closing at w move w EPS t:
    # a gap that closes within that is closed now (else it opens and closes forever)
    r = _rounding(abs(xl) + abs(xr) + abs(dl) + abs(dr)) + 4.0 * EPS * abs(t) * abs(w)
    st = S.cst[j]
    if st == ACTIVE:
        if (c <= r and w < 0.0) or c < -r:
            return EV_OPEN
    elif st == FRESH:
        if c < -r:
            return EV_RELEASE
    elif st == DORMANT:
        if c >= S.fs[F_LDORM]:
            return EV_ENGAGE
        if c <= -S.fs[F_EPSREL]:
            return EV_RELEASE
    else:
        if c >= -r and w >= S.fs[F_FLOOR]:
            return EV_CLOSE
        if c >= S.lvl[j]:
            return EV_ENGAGE
    return 0


@kernel
def _dormant_due(S):
    """Whether a dormant contact at a cluster's edge has been pressed (or pulled) past its levels."""
    ncont = S.cst.shape[0]
    for c in range(S.ints[I_NCL]):
        for j in (S.clo[c] - 1, S.chi[c]):
            if j < 0 or j >= ncont or S.cst[j] != DORMANT:
                continue
            xl, vl, al = _ball_now(S, j)
            xr, vr, ar = _ball_now(S, j + 1)
            cj = xl - xr
            if cj >= S.fs[F_LDORM] or cj <= -S.fs[F_EPSREL]:
                return True
    return False


@kernel
def _settle(S):
    """After a change of structure, apply every event due at this instant (positions synced)."""
    ncont = S.cst.shape[0]
    budget = 4 * (S.ints[I_M] + 2 * S.ints[I_NCL] + 4)
    changed = True
    while changed:
        changed = False
        budget -= 1
        if budget < 0:
            return False  # contacts flipping back and forth: a defect, reported by the driver
        for c in range(S.ints[I_NCL]):
            j0 = max(S.clo[c] - 1, 0)
            j1 = min(S.chi[c], ncont - 1)
            for j in range(j0, j1 + 1):
                kind = _due(S, j)
                if kind != 0:
                    if not _apply_event(S, j, kind):
                        return False
                    changed = True
                    break
            if changed:
                break
    return True


@kernel
def _post_step(S):
    """After an accepted step or jump: season contacts, then apply its event or release contacts."""
    if S.ints[I_JUMP] == 0 and S.ints[I_M] > 0:
        _season(S)
    k = S.ints[I_EVK]
    if k != 0:
        S.ints[I_EVK] = 0
        _sync(S)
        if not _apply_event(S, S.ints[I_EVJ], k):
            return False
    elif S.ints[I_M] > 0:
        if _dormant_due(S):
            _sync(S)
            S.ints[I_DIRTY] = 1
        elif not _release_quiet(S):
            return False
    if S.ints[I_DIRTY] == 1:
        return _settle(S)
    return True


@kernel(inline="always")
def _end_ball(S, b, t):
    p = S.bmap[b]
    if p >= 0:
        return S.X[p], S.V[p], S.A[p]
    return S.bx[b] + S.bv[b] * (t - S.bt[b]), S.bv[b], 0.0


@entry
def advance(S):
    """Run until something needs the driver; return a status code (ST_*).

    The driver sets ``fs[F_TOUT]`` and ``ints[I_HAVEOUT] = 1`` to ask for the next
    snapshot, empties the event log on ST_FLUSH, grows the compact arrays on ST_GROW
    and calls again.
    """
    nsteps = 0
    while True:
        if S.ints[I_DIRTY] == 1:
            need = _rebuild(S)
            if need > 0:
                S.ints[I_NEED] = need
                return ST_GROW
        t = S.fs[F_T]
        # snapshots inside the last step, before its event reshapes the clusters
        if S.ints[I_HAVEOUT] == 1 and S.fs[F_TOUT] <= t:
            _snapshot(S, S.fs[F_TOUT])
            S.ints[I_HAVEOUT] = 0
            return ST_OUTPUT
        if S.ints[I_POST] == 1:
            if S.ev_t.shape[0] - S.ints[I_NEV] < S.ints[I_M] + 4:
                return ST_FLUSH
            S.ints[I_POST] = 0
            if not _post_step(S):
                return ST_GROW
            continue
        if S.ints[I_MAXEV] >= 0 and S.ints[I_EVTOTAL] >= S.ints[I_MAXEV]:
            return ST_EVENT_LIMIT
        tend = S.fs[F_TEND]
        # next free-pair collision
        tcol = np.inf
        if _heap_valid_top(S):
            tcol = S.hp_t[0]
            if tcol <= t:
                # collisions at one instant: each contact closes there at most a few
                # times; more means states flipping back and forth, a defect that is
                # reported (as by _settle) rather than run forever
                if t == S.fs[F_TSAME]:
                    S.ints[I_NSAME] += 1
                    if S.ints[I_NSAME] > 4 * S.cst.shape[0] + 64:
                        S.ints[I_NEED] = 0
                        return ST_GROW
                else:
                    S.fs[F_TSAME] = t
                    S.ints[I_NSAME] = 0
                j = S.hp_j[0]
                _heap_pop(S)
                S.ints[I_EVJ] = j
                S.ints[I_EVK] = EV_CLOSE
                S.ints[I_POST] = 1
                continue
        if t >= tend:
            return ST_STOP_TIME
        if S.ints[I_NCL] == 0:
            if tcol == np.inf:
                return ST_TERMINAL
            # free flight: jump straight to the next collision (or the stop time)
            tn = min(tcol, tend)
            S.fs[F_TPREV] = t
            S.fs[F_HLAST] = tn - t
            S.fs[F_T] = tn
            S.ints[I_JUMP] = 1
            continue
        nsteps += 1
        if nsteps > YIELD_STEPS:
            return ST_YIELD
        # ---- one accepted step, ending at the earliest event if there is one ------------
        _save_start(S)
        # the series where it reaches further than DOP853's next step, else DOP853
        h = S.fs[F_H]
        ht = _taylor(S) if S.ints[I_NCL] <= SERIES_CLUSTERS else 0.0
        tay = ht >= h
        S.ints[I_TAY] = 1 if tay else 0
        if tay:
            h = ht
        order = PT if tay else 8
        tclip = min(tcol, tend)
        clipped = False
        if t + h >= tclip:
            h = tclip - t
            clipped = True
        S.fs[F_TPREV] = t
        S.ints[I_JUMP] = 0
        while True:
            err = _step(S, h)
            S.fs[F_HLAST] = h
            if not np.isfinite(err):
                if h < 1e-12 * max(1.0, abs(t)):
                    return ST_NON_FINITE
                h *= 0.2
                S.ints[I_REJ] += 1
                clipped = False
                continue
            th, j, kind, lev = _find_event(S)
            if err <= 1.0:
                break
            S.ints[I_REJ] += 1
            if j >= 0:
                # a step over a contact's change of state fails its error test where the
                # force is not smooth; the event cuts the step anyway: go and land on it
                # (the landing step passes the test, or is halved and retried)
                break
            h *= max(0.2, 0.9 * err ** (-1.0 / order))
            clipped = False
            if h < 8.0 * EPS * max(1.0, abs(t)):
                return ST_STEP_UNDERFLOW
        if tay:
            hnext = S.fs[F_H]  # DOP853's proposal stands; the series sizes its own steps
        else:
            hnext = h * (10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-1.0 / 8.0)))
        if j >= 0:
            # redo the step to end on the event, then refine by Newton on the step itself
            hev = th * h
            landing = 0  # 1 landed, 2 the step failed its error test, 3 Newton gave up
            nit = 0
            while landing == 0:
                if not (_step(S, hev) <= 1.0):
                    landing = 2
                    break
                xl, vl, al = _end_ball(S, j, t + hev)
                xr, vr, ar = _end_ball(S, j + 1, t + hev)
                res = (xl - xr) - lev
                w = vl - vr
                if abs(res) <= _rounding(abs(xl) + abs(xr)) or w == 0.0:
                    landing = 1
                    break
                dh = -res / w
                nit += 1
                if abs(dh) > 0.5 * hev or nit == 6:
                    landing = 3  # the state stays that of the last step taken
                    break
                hev += dh
            if landing == 2:
                # the shorter step failed its error test: halve it and look again
                _restore_start(S)
                S.fs[F_H] = 0.5 * hev
                S.ints[I_REJ] += 1
                continue
            if landing == 3 and err > 1.0:
                # an event seen only on a failed step, and not there on a good one:
                # shrink the step as for any failed step
                _restore_start(S)
                S.fs[F_H] = h * max(0.2, 0.9 * err ** (-1.0 / order))
                continue
            S.fs[F_HLAST] = hev
            S.fs[F_T] = t + hev
            S.ints[I_EVJ] = j
            S.ints[I_EVK] = kind
            # shorter than the step just cut short: its error estimate spoke for a
            # stretch that crossed the event, smoother than what follows it (after a
            # contact opens, the balls it leaves change fastest)
            S.fs[F_H] = min(hnext, AFTER_EVENT * h)
        else:
            S.fs[F_T] = tclip if clipped else t + h
            if not tay:
                S.fs[F_H] = max(hnext, S.fs[F_H]) if clipped else hnext
        S.ints[I_STEPS] += 1
        S.ints[I_POST] = 1
