"""The solver's state: the ``State`` arrays, their scalar slots, and the shared constants.

Every kernel takes one ``State`` and reads its scalars through the slots ``F_*`` (in
``fs``) and ``I_*`` (in ``ints``). The status codes (``ST_*``), contact states and
event kinds (``EV_*``) are the kernels' vocabulary with the driver; the sizes of the
series and of their work tiles are shared by the steppers and the generated code.
``_tw`` and ``_find_cluster`` are here, beside the layout they index, because the
generated code and the heap use them.

State model
-----------
A ball is either *free* (no active contact; it moves as ``x + v (t - tref)``) or a
member of a *cluster*, a maximal run of balls joined by active contacts. Only cluster
balls are integrated: their state is packed, cluster after cluster, into compact
arrays (``_clusters._rebuild``) and advanced together.

Contact states (``cst``)::

    DORMANT  touching at zero compression since t = 0, never pressed; engages when
             its force would reach ``FORCE_DORMANT`` (not logged: it was closed already)
    FRESH    active, not yet compressed beyond the floor's compression ``eps_rel``;
             openings fire only below minus the rounding level of its positions
    ACTIVE   active ("seasoned"); opens exactly where the compression crosses 0
    OPEN     inactive; closes where the gap reaches 0 with approach speed >= floor,
             or engages where the compression exceeds ``lvl[j]`` (a slow press)
    SEALED   an isolated binary collision in progress, in closed form (``_pairs``):
             its two balls are in no cluster, and their motion is known exactly
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from chainrun.solver._jit import kernel


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
# contact states that do not settle (a defect of the solver, not of the line): the
# driver reports it; ST_GROW always carries the capacity needed in ints[I_NEED]
ST_DEFECT = 9
# what the parts of one pass of ``_loop.advance`` tell it besides a status (ST_* >= 0):
# go round the loop again, go on to the next part, or go round after a step's worth of
# work (a sealed collision, counted against YIELD_STEPS like a step)
AGAIN = -1
GO_ON = -2
COUNTED = -3

# ---- contact states -------------------------------------------------------------------
DORMANT = 3
FRESH = 1
ACTIVE = 2
OPEN = 0
SEALED = 4

# ---- event kinds (same values as chainrun.solver.EventKind) ---------------------------
EV_RELEASE = -2
EV_OPEN = -1
EV_CLOSE = 1
EV_ENGAGE = 2
# a damped contact's force reaches 0 while it is still compressed (the collision
# ends), and rises again from 0 before the compression has gone (a third ball pushes)
EV_UNLOAD = -3
EV_RELOAD = 3

#: a dormant contact engages where its force kappa c^alpha would reach this (cp[C_DORM] =
#: (FORCE_DORMANT/kappa)^(1/alpha), 1e-24 for alpha = 1, 1e-16 for Hertz): far below rounding of
#: order-1 velocities, it keeps subnormals out of the front, and the balls ahead of a
#: wave, which it never moves, out of the window
FORCE_DORMANT = 1e-24
#: a dormant contact pressed at the end of a step less than FORCE_LOCATE^(1/alpha)
#: (cp[C_LOC], 1e-18 for alpha = 1, 1e-12 for Hertz) engages there without being
#: located: the force it missed, over a fraction of the step, is below FORCE_LOCATE
FORCE_LOCATE = 1e-18
EPS = 2.220446049250313e-16
N_SAMPLES = 8  # subintervals sampled per step for each candidate contact
N_SERIES_SAMPLES = 4 * N_SAMPLES  # on a series step, several DOP853 steps long
# the series' work tiles TW (see _tw): lanes in tiles of SERIES_TILE, each tile holding
# TILE_ROWS rows: the compressions' series c_k (rows k <= PT), the forces' f_k (rows
# PT + 1 + k), 1 / c_0 (row 2 PT), and the bounds of the compression over a series step
# (rows LO_ROW, HI_ROW, _series_bounds); TR holds each contact lane's stiffness inside
# a cluster, and 0 from a cluster's last ball to the next's first (_rebuild)
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
F_T, F_H, F_TPREV, F_HLAST, F_TOUT, F_TEND, F_TOL, F_FLOOR, F_ALPHA, \
    F_EPROJ, F_TSAME, F_QX1, F_QX2, F_QV1, F_QV2, F_DISS, F_DOUT, F_JL, F_JR, F_JSL, \
    F_JSR, F_TTASK, F_HCAP, F_WORK, F_WSTEP, F_WOUT, F_TDEF, F_NFLOAT = range(28)
# int scalars
I_NCL, I_M, I_NHEAP, I_NEV, I_STEPS, I_REJ, I_EVTOTAL, I_DIRTY, I_DENSE, I_NFREED, \
    I_MODE, I_MAXWIN, I_POST, I_EVJ, I_EVK, I_NEED, I_HAVEOUT, I_MAXEV, I_JUMP, \
    I_NSAME, I_DSTAMP, I_TAY, I_UNIT, I_FORCED, I_DAMPED, I_LWALL, I_RWALL, I_LWL, I_RWL, \
    I_TASK, I_XEND, I_PAIRS, I_NSEAL, I_SEALED, I_DRIVEN, I_NDRIVE, I_DCUR, I_PCQ, I_PCT, \
    I_DQ, I_DT, I_DEFJ, I_NINT = range(43)

# F_JL, F_JR: the impulse the left and right walls gave so far (F_JSL, F_JSR: over the
# step being taken); I_LWALL, I_RWALL: 1 if the line has that wall; I_LWL, I_RWL: the
# window's contact lane to that wall, -1 when no cluster touches it (_rebuild)

# I_DRIVEN: 1 on a driven line (a moving wall, or a force prescribed in time: _drive);
# F_WORK: the work the drives did so far; F_WSTEP: over the last step (on a DOP853
# step summed over its stages as it is taken); F_WOUT: by the time of a snapshot

# F_HCAP: a cap on the next series step, set where a series step's landing on an event
# failed (the series sizes its own steps, and would take the same failing step again),
# and lifted (inf) by the next accepted step

# I_PAIRS: 1 when an isolated binary collision may be taken in closed form (_pairs;
# a line without external forces, unless the caller asked otherwise);
# I_NSEAL: how many were; I_SEALED: how many are sealed now (the checks for them are
# skipped while there are none)

# I_XEND: 1 when (X, V, A) hold the window at the end of the last step (or trial step);
# 0 while a series step is tried before the window is evaluated (see _loop.advance):
# the ends of the few balls the event scan reads come from their series then

# I_DEFJ: a damped contact held at 0 whose compression crossed 0 inside the step being
# taken, -1 if none; F_TDEF: the time of that crossing. Its opening changes no force
# (a held contact carries none, open or not), so it does not end the step: it is
# applied, and logged at F_TDEF, after the step (_events._find_event, _settle._post_step)

# ---- the drives (_drive) -------------------------------------------------------------
# A driven line keeps its drives past the scalar slots, in ints and fs, so that the
# State of a line without drives is no larger than it was (kernels that are not inlined
# take the State whole, and a field more costs every such call). ints[I_NDRIVE] = D
# drives; in ints, from I_NINT, each drive's row of DV_* (DV_ROW each); from
# ints[I_DCUR], each drive's piece in force and its ball's compact index (2 each);
# from ints[I_PCQ], each piece's first and one past its last term (2 each). In fs,
# from F_NFLOAT, each drive's DM (the mass it drives, or a moving wall's place), then
# each drive's stage velocity; from ints[I_PCT], each piece's start; from ints[I_DQ],
# the terms (drive.TERM each: the polynomial's coefficients, omega, phi); from
# ints[I_DT], each drive's terms of the positions' series at a series step's start
# (PT + 1 each).
# the fields of a drive's row: the internal ball, the kind, the first and one past the
# last piece
DV_BALL, DV_KIND, DV_LO, DV_HI = range(4)
DV_ROW = 4
# a kind: the ball's position is u(t) (a moving wall), or its acceleration gains u(t)
# (a force prescribed in time, over the ball's mass)
DRIVE_POSITION = 0
DRIVE_FORCE = 1

# ---- what a call of ``advance`` does (I_TASK, at the time F_TTASK) --------------------
# ``advance`` is the kernels' one entry point (one compiled library to load): besides
# running, it evaluates the state at a time inside the last step or in free flight,
# every ball's into (ox, ov), or the balls listed in ``probe`` into ox[:P], ov[:P]
TASK_RUN, TASK_SNAPSHOT, TASK_SAMPLE = range(3)

# ---- the force laws (I_MODE) ----------------------------------------------------------
MODE_LINEAR = 0  # every contact alpha = 1
MODE_HERTZ = 1  # every contact alpha = 3/2
MODE_POWER = 2  # every contact the same alpha, fs[F_ALPHA]
MODE_MIXED = 3  # each contact its own alpha (WP[W_ALPHA] in the window)

# ---- rows of the parameter arrays -----------------------------------------------------
# per ball, bp: mass (0 for a wall), inverse mass (0 for a wall: it never moves), and
# the constant acceleration of its external force (f / m)
B_MASS, B_IM, B_ACC = range(3)
# per contact, cp: stiffness, exponent, and the contact's thresholds: the compression
# whose energy gives a relative speed of the floor (eps_rel, see _driver), and those
# where its force reaches FORCE_DORMANT and FORCE_LOCATE; its damping and damping
# exponent, 1 while its damped force is held at 0 (since EV_UNLOAD), and the energy
# its damping has dissipated so far (these four rows on a damped line only)
C_KAPPA, C_ALPHA, C_EPS, C_DORM, C_LOC, C_ETA, C_BETA, C_HELD, C_DISS = range(9)
# per compact ball, WP: inverse mass, external acceleration, mass, and the exponent,
# damping, damping exponent and C_HELD of the contact lane it starts
W_IM, W_ACC, W_MASS, W_ALPHA, W_ETA, W_BETA, W_HELD = range(7)
# per contact, sl: a sealed collision's closed form (see _pairs): the time its
# compression was 0 going in, its duration, the centre of mass's position then and its
# velocity, the approach speed, and the greatest compression (a damped contact's
# length scale D, see _pair_damped)
SL_T0, SL_TAU, SL_X, SL_V, SL_W, SL_CMAX = range(6)
# and on a damped line only (NSL_DAMPED rows): the time from SL_T0 to the unload (to
# the end, for an elastic contact), the coefficient of restitution, the compression at
# the unload, the scaled damping G (0: elastic), and 1 once the unload is past
SL_TU, SL_E, SL_RU, SL_G, SL_PH = range(6, 11)
NSL, NSL_DAMPED = 6, 11
#: relative and absolute tolerances of a damped pair's scaled relative motion, whose
#: variables are of order 1 (see _pair_damped)
PAIR_RTOL = 1e-13
PAIR_ATOL = 1e-18
# extra rows of KV on a damped line: the stage velocities, and each lane's energy
# dissipated over the step being taken (see _forces._damped_forces)
KV_VS = _NSE
KV_DS = _NSE + 1

State = namedtuple(
    "State",
    [
        # balls, shape (N,) (walls are balls of infinite mass at the ends); their
        # parameters (bp, rows B_*)
        "bx", "bv", "bt", "sep_t", "sep_v", "bmap", "bp",
        # contacts, shape (N-1,) (at least 1); their parameters (cp, rows C_*)
        "cst", "lvl", "stamp", "cp", "sl",
        # clusters: ball range, offset in the compact arrays (-1 until packed), energy
        # since it formed
        "clo", "chi", "coff", "cen",
        # compact (integrated) balls: state, step start, dense-stage positions (XS; a
        # series step's scratch row of one order's forces, lanes long),
        # contact forces (FS), stage accelerations (KV), interpolant rows (FX, FV) and
        # the stamp of the step they were built for (DM, see _dense_at), the balls'
        # and lanes' parameters (WP, rows W_*; TR holds each lane's stiffness); the Taylor
        # series of the positions (TX), order-major (see _taylor), with the work tiles
        # of the compressions' and forces' series (TW, see _tw) and lane mask (TR),
        # and of one contact's compression (TD, shape (PT + 1,)) with its samples (TS)
        "cb", "X", "V", "A", "X0", "V0", "A0", "XS", "FS", "KV", "FX", "FV", "DM", "WP",
        "TX", "TW", "TR", "TD", "TS",
        # heap of free-pair collisions and of the ends of sealed ones (hp_j >= N - 1:
        # contact hp_j - (N - 1) parts)
        "hp_t", "hp_j", "hp_s",
        # event log buffer
        "ev_t", "ev_j", "ev_k",
        # snapshot buffer, and the balls a sample evaluates (TASK_SAMPLE)
        "ox", "ov", "probe",
        # scratch lists of ball / contact indices, and flags of lanes, shape (N,)
        "freed", "jbuf",
        # scalars
        "fs", "ints",
    ],
)


@kernel(inline="always")
def _tw(p, r):
    """Index in the work tiles TW of row r of contact lane p."""
    return (p // SERIES_TILE) * TILE_STRIDE + r * SERIES_TILE + p % SERIES_TILE


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


@kernel(inline="always")
def _flight(S, b, t):
    """(displacement since bt, velocity) of free ball b at t: a parabola under its
    constant acceleration (a straight line without one, to the same bits)."""
    dt = t - S.bt[b]
    if S.ints[I_FORCED] == 0:
        return dt * S.bv[b], S.bv[b]
    g = S.bp[B_ACC, b]
    return dt * (S.bv[b] + 0.5 * g * dt), S.bv[b] + g * dt


@kernel(inline="always")
def _free_at(S, b, t):
    """(x, v) of free ball b at t."""
    d, v = _flight(S, b, t)
    return S.bx[b] + d, v
