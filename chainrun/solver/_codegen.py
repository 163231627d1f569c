"""Writes ``_generated.py``: the DOP853 stages and the Taylor-series sums as straight-line code.

The stage sums of an explicit Runge-Kutta step are fixed linear combinations of the
previous stages; for x'' = a(x) they are taken in Nystrom form, on the accelerations
alone (see ``_nystrom``). Written as loops over the tableau, a window of a dozen balls
spends its time in loop overhead; written out with the coefficients as literals, each
stage is one pass over the balls. The Taylor series' sums (``_series_orders``) loop
over orders with a tile's lanes written out, as does a linear line's
(``_linear_orders``), and its bounds (``_series_bounds``) are written out whole. The
coefficients are computed exactly (``_exact_product``), so the text is the same on
every machine. This script writes the whole of ``_generated.py`` from scipy's DOP853
tableau and the series' orders::

    python -m chainrun.solver._codegen          # rewrite _generated.py
    python -m chainrun.solver._codegen --check  # exit 1 if it is out of date
"""

from __future__ import annotations

import math
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
from scipy.integrate._ivp import dop853_coefficients as dop

TARGET = Path(__file__).with_name("_generated.py")
EPS = np.finfo(float).eps


def _combo(coefs, rows: str, scale: str, index: str = "p") -> str:
    """``scale * (coefs @ rows[:, index])`` as a sum of literal terms.

    Entries below the rounding of the row's largest are left out: products of the
    tableau give them where the exact entry is zero.
    """
    coefs = np.asarray(coefs, dtype=float)
    cut = 64 * EPS * np.abs(coefs).max(initial=0.0)
    terms = [f"{float(a)!r} * {rows}[{i}, {index}]" for i, a in enumerate(coefs)
             if abs(a) > cut]
    return f"{scale} * (" + " + ".join(terms) + ")" if terms else "0.0"


def _force_pass(x: str, s: int, v: str | None = None, vcoefs=None, weight: float = 0.0,
                node: float = 1.0) -> list[str]:
    """Accelerations at positions x into KV[s], across the window (_accelerations).

    On a damped line the forces depend on the velocities too: the stage's velocities
    (``v``, or V0 + h vcoefs @ KV into VS) and, where ``weight`` (a weight of the
    step's quadrature) is not 0, the lanes' dissipated power into DS. On a driven line
    the drives' accelerations at the stage's time t0 + node h are added, and, with a
    weight, their power (from the driven balls' stage velocities, kept in fs from dvo)
    to jw.
    """
    if v is None:
        v = "VS"
        stage_v = ["        for p in range(m):",
                   f"            VS[p] = V0[p] + {_combo(vcoefs, 'KV', 'h')}"]
    else:
        stage_v = []
    wgt = f"h * {float(weight)!r}" if weight != 0.0 else "0.0"
    impulse = [
        "    if lwl >= 0:",
        f"        jl += {wgt} * F[lwl]",
        "    if rwl >= 0:",
        f"        jr += {wgt} * F[rwl]",
    ] if weight != 0.0 else []
    if weight != 0.0:
        drive = [
            "    if driven:",
            "        for d in range(nd):",
            "            p = S.ints[dco + 2 * d + 1]",
            f"            S.fs[dvo + d] = V0[p] + {_combo(vcoefs, 'KV', 'h')}",
            f"        jw += _drive_stage(S, KV[{s}], F, t0 + {float(node)!r} * h, {wgt}, True)",
        ]
    else:
        drive = [
            "    if driven:",
            f"        _drive_stage(S, KV[{s}], F, t0 + {float(node)!r} * h, 0.0, True)",
        ]
    return [
        "    if damped:",
        *stage_v,
        f"        _damped_accelerations({x}, {v}, F, MK, WP, DS, {wgt}, KV[{s}], m, mode, alpha)",
        "    else:",
        f"        _accelerations({x}, F, MK, WP, KV[{s}], m, mode, alpha, unit)",
        *impulse,
        *drive,
    ]


def _drift(node: float, coefs, index: str) -> str:
    """A stage's displacement over h: node V0 + h coefs @ KV (the first term alone where
    the stage has no coefficients)."""
    drift = f"{float(node)!r} * V0[{index}]"
    if np.any(coefs != 0.0):
        drift += f" + {_combo(coefs, 'KV', 'h', index)}"
    return drift


def _stage_pass(out_x: str, s: int, node: float, coefs, vcoefs, weight: float = 0.0
                ) -> list[str]:
    """Stage s in Nystrom form: positions into out_x, accelerations into KV[s]."""
    return [
        "    for p in range(m):",
        f"        {out_x}[p] = X0[p] + h * ({_drift(node, coefs, 'p')})",
        *_force_pass(out_x, s, vcoefs=vcoefs, weight=weight, node=node),
    ]


def _band_pass(s: int, reach: int, node: float, coefs, vcoefs, out: str = "Xs",
               end: bool = False) -> list[str]:
    """Stage s on the balls within ``reach`` of p (positions into ``out``, and on a damped
    line velocities) and within ``reach - 1`` (accelerations), inside p's cluster o..e.
    With ``end``, the step's end: its velocities into V on every line, and its
    accelerations into A as well."""
    if end:
        vel = ["    for q in range(lo, hi + 1):",
               f"        V[q] = V0[q] + {_combo(vcoefs, 'KV', 'h', 'q')}",
               "    if damped:",
               f"        _damped_band({out}, V, F, MK, WP, lo, hi, mode, alpha)"]
    else:
        vel = ["    if damped:",
               "        for q in range(lo, hi + 1):",
               f"            VS[q] = V0[q] + {_combo(vcoefs, 'KV', 'h', 'q')}",
               f"        _damped_band({out}, VS, F, MK, WP, lo, hi, mode, alpha)"]
    return [
        f"    lo = max(o, p - {reach})",
        f"    hi = min(e, p + {reach})",
        "    for q in range(lo, hi + 1):",
        f"        {out}[q] = X0[q] + h * ({_drift(node, coefs, 'q')})",
        *vel,
        "    else:",
        f"        _forces({out}, F, MK, WP[W_ALPHA], lo, hi, mode, alpha)",
        "    qa = lo if lo == o else lo + 1",
        "    qb = hi if hi == e else hi - 1",
        "    for q in range(qa, qb + 1):",
        f"        KV[{s}, q] = ((F[q - 1] if q > o else 0.0) - (F[q] if q < e else 0.0))"
        " * WP[W_IM, q] + WP[W_ACC, q]",
        "    if driven:",
        f"        _drive_band(S, KV[{s}], t0 + {float(node)!r} * h, qa, qb)",
        *(["    for q in range(qa, qb + 1):",
           f"        A[q] = KV[{s}, q]"] if end else []),
    ]


def _band_prologue(arrays: str) -> list[str]:
    """What a band's stages read, and p's cluster o..e."""
    return [
        "    mode = S.ints[I_MODE]",
        "    alpha = S.fs[F_ALPHA]",
        "    damped = S.ints[I_DAMPED] == 1",
        f"    {arrays}",
        "    VS = S.KV[KV_VS]",
        "    driven = S.ints[I_DRIVEN] == 1",
        "    t0 = S.fs[F_TPREV]",
        "    c = _find_cluster(S, S.cb[p])",
        "    o = S.coff[c]",
        "    e = o + S.chi[c] - S.clo[c]",
    ]


_PROLOGUE = [
    "    m = S.ints[I_M]",
    "    mode = S.ints[I_MODE]",
    "    alpha = S.fs[F_ALPHA]",
    "    unit = S.ints[I_UNIT] == 1",
    "    damped = S.ints[I_DAMPED] == 1",
    "    F, MK, WP = S.FS, S.TR, S.WP",
    "    VS, DS = S.KV[KV_VS], S.KV[KV_DS]",
    "    driven = S.ints[I_DRIVEN] == 1",
    "    nd = S.ints[I_NDRIVE]",
    "    dco = S.ints[I_DCUR]",
    "    dvo = F_NFLOAT + nd",
    "    t0 = S.fs[F_TPREV]",
]


def _exact_product(a, b) -> np.ndarray:
    """``a @ b`` computed exactly in rationals, each entry rounded once to a double.

    numpy's matrix product sums in an order (and with fused multiply-adds) that depend
    on the CPU and the BLAS, so its last digits, and with them the generated text, would
    differ between machines. Every double is a rational, and ``float(Fraction)`` rounds
    correctly: the product here is the same on every machine.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.asarray(b, dtype=float)
    fa = [[Fraction(float(x)) for x in row] for row in a]
    fb = [[Fraction(float(x)) for x in row] for row in b]
    return np.array([[float(sum((r[k] * fb[k][j] for k in range(len(r))), Fraction(0)))
                      for j in range(b.shape[1])] for r in fa])


def _nystrom(rows):
    """Coefficients on the accelerations of ``rows @ KX``, whose entries sum to zero.

    For x'' = a(x) the stage velocities are KX[j] = V0 + h sum_k A[j, k] KV[k], so
    ``r @ KX = sum(r) V0 + h (r @ A) @ KV``: the step needs no stage velocities.
    The error and dense-output rows of DOP853 sum to zero (up to rounding).
    """
    rows = np.atleast_2d(rows)
    width = rows.shape[1]
    sums = rows.sum(axis=1)
    if np.any(np.abs(sums) > 64 * EPS * np.abs(rows).sum(axis=1)):
        raise ValueError(f"rows do not sum to zero: {sums}")
    return _exact_product(rows, dop.A[:width, :width])


def _chains(terms: list[str]) -> str:
    """A sum as two interleaved chains (every other term), half as deep as one."""
    if len(terms) < 4:
        return " + ".join(terms)
    return "(" + " + ".join(terms[0::2]) + ") + (" + " + ".join(terms[1::2]) + ")"


def _series(pt: int, tile: int, mixed: bool) -> list[str]:
    """Orders 1..pt-2 of the force series and 3..pt of the positions' (see _taylor).

    f_k = (alpha c_k f_0 + sum_{j=1..k-1} ((alpha+1) j / k - 1) c_j f_{k-j}) / c_0, the
    recurrence of _taylor with 1/k folded into its weights, on the work tiles TW
    (rows c_k at k, f_k at pt + 1 + k, 1/c_0 at 2 pt; see _tw); a ball's term of order
    k + 2 is its net force's of order k over its mass, over (k + 1)(k + 2). The sum
    over j is a loop; within it the tile's ``tile`` lanes are written out, each with two
    accumulators (even and odd j), so that they stay in registers and the compiler
    packs the lanes into vector instructions: a loop over the lanes would load and
    store its partial sums at every j, and sums written out for every order would be a
    function of thousands of lines, slow to compile. Each tile takes its lanes' c_k
    from the balls' rows of TX (one column past the tile: TX has a column past the
    last tile's) and stores them in its row k as it uses them: written by a pass of
    scalar stores, that row would be read back as vectors, which wait until the stores
    are done. A lane past the window takes the difference of columns no ball holds;
    its force terms (f_0 = 0, 1/c_0 = 0) are read by nothing. ``mixed``: each lane has
    its own exponent (AL), and so its own weights. ``unit``: every mass 1 (no division).
    """
    lanes = range(tile)
    if mixed:
        name, args = "_series_orders_mixed", "TX, W, G, IM, AL, nc, m, unit, DT, DC"
        doc = "Orders 1 and up of the force series, each lane its own alpha (see _taylor)."
        head = [f"            a{i} = AL[q + {i}]" for i in lanes]
        head += [f"            b{i} = a{i} + 1.0" for i in lanes]
        first = [f"            e{i} = a{i} * c{i} * W[f + {i}]" for i in lanes]
        weight = ["                jk = J_OVER_K[k, j]"]

        def term(acc, i):
            return f"                {acc}{i} += (b{i} * jk - 1.0) * W[c + {i}] * W[f + {i}]"
    else:
        name, args = "_series_orders", "TX, W, G, IM, nc, m, alpha, unit, DT, DC"
        doc = "Orders 1 and up of the force series of every contact lane (see _taylor)."
        head = []
        first = [f"            e{i} = alpha * c{i} * W[f + {i}]" for i in lanes]
        weight = ["                w = a1 * J_OVER_K[k, j] - 1.0"]

        def term(acc, i):
            return f"                {acc}{i} += w * W[c + {i}] * W[f + {i}]"
    lines = [
        "@kernel",
        f"def {name}({args}):",
        f'    """{doc}"""',
        *([] if mixed else ["    a1 = alpha + 1.0"]),
        "    nt = (nc + SERIES_TILE - 1) // SERIES_TILE",
        f"    f0 = {pt + 1}  # row of f_0",
        f"    for k in range(1, {pt - 1}):",
        "        for t in range(nt):",
        "            q = t * SERIES_TILE",
        "            o = t * TILE_STRIDE",
        "            c = o + k * SERIES_TILE",
        "            f = o + f0 * SERIES_TILE",
        *[f"            x{i} = TX[k, q + {i}]" for i in range(tile + 1)],
        *[f"            c{i} = x{i} - x{i + 1}" for i in lanes],
        *[f"            W[c + {i}] = c{i}" for i in lanes],
        *head,
        *first,
        *[f"            d{i} = 0.0" for i in lanes],
        "            for j in range(1, k, 2):",
        *weight,
        "                c = o + j * SERIES_TILE",
        "                f = o + (f0 + k - j) * SERIES_TILE",
        *[term("d", i) for i in lanes],
        "            for j in range(2, k, 2):",
        *weight,
        "                c = o + j * SERIES_TILE",
        "                f = o + (f0 + k - j) * SERIES_TILE",
        *[term("e", i) for i in lanes],
        "            c = o + (f0 + k) * SERIES_TILE",
        f"            f = o + {2 * pt} * SERIES_TILE",
        "            g = t * SERIES_TILE",
        *[f"            e{i} = (e{i} + d{i}) * W[f + {i}]" for i in lanes],
        *[f"            W[c + {i}] = e{i}" for i in lanes],
        *[f"            G[g + {i}] = e{i}" for i in lanes],
        "        # the balls' terms from the forces, which G holds in one row (and the",
        "        # drives' terms, on a driven line)",
        "        _series_terms(TX, k + 2, G, IM, nc, SERIES_SCALE[k], unit)",
        "        if DT.shape[0] > 0:",
        "            _drive_terms(TX, k + 2, DT, DC)",
        "    # the compressions' last two orders, for the bounds (_series_bounds)",
        "    for p in range(nc):",
        f"        W[_tw(p, {pt - 1})] = TX[{pt - 1}, p] - TX[{pt - 1}, p + 1]",
        f"        W[_tw(p, {pt})] = TX[{pt}, p] - TX[{pt}, p + 1]",
    ]
    return lines


def _linear(pt: int, tile: int) -> list[str]:
    """A linear line's orders of the series (see _taylor), a pass across the window per
    order: each lane's compression c_k into the work tiles, and its force kappa c_k.

    Each full tile's lanes are written out, loaded into locals before anything is
    stored, so that the compiler packs them into vector instructions (it cannot prove
    that the rows it stores to do not overlap those it reads, and keeps a loop over
    the lanes, which stores at a computed place in the tiles, scalar); the last,
    partial tile is a loop. The arithmetic is that of a loop over the lanes.
    """
    lanes = range(tile)
    xs = range(tile + 1)
    lines = [
        "@kernel",
        "def _linear_orders(TX, W, G, MK, IM, nc, unit, DT, DC):",
        '    """Orders 1 and up of a linear line\'s series (see _taylor): each lane\'s',
        "    compression c_k into the work tiles and its force kappa c_k into G (one row, so",
        '    that the pass over the balls, _series_terms, reads neighbours with no branch)."""',
        "    nf = nc // SERIES_TILE",
        f"    for k in range(1, {pt + 1}):",
        "        for t in range(nf):",
        "            b = t * SERIES_TILE",
        "            c = t * TILE_STRIDE + k * SERIES_TILE",
        *[f"            x{i} = TX[k, b + {i}]" for i in xs],
        *[f"            m{i} = MK[b + {i}]" for i in lanes],
        *[f"            d{i} = x{i} - x{i + 1}" for i in lanes],
        *[f"            W[c + {i}] = d{i}" for i in lanes],
        *[f"            G[b + {i}] = d{i} * m{i}" for i in lanes],
        "        for p in range(nf * SERIES_TILE, nc):",
        "            d = TX[k, p] - TX[k, p + 1]",
        "            W[_tw(p, k)] = d",
        "            G[p] = d * MK[p]",
        f"        if k < {pt - 1}:",
        "            _series_terms(TX, k + 2, G, IM, nc, 1.0 / ((k + 1) * (k + 2)), unit)",
        "            if DT.shape[0] > 0:",
        "                _drive_terms(TX, k + 2, DT, DC)",
    ]
    return lines


def _bounds(pt: int, db: int) -> list[str]:
    """Bernstein bounds of every contact lane's compression over a series step."""
    lines = [
        "@kernel",
        "def _series_bounds(W, nc, h):",
        '    """Bounds of every contact lane\'s compression over a series step [0, h].',
        "",
        "    From the rows c_k of the work tiles into their rows LO_ROW, HI_ROW: the hull",
        "    of the Bernstein coefficients of the lane's series up to degree DB, widened",
        "    by the magnitude of the higher terms and by rounding, as _bernstein_range",
        "    does for one contact.",
        '    """',
        "    nt = (nc + SERIES_TILE - 1) // SERIES_TILE",
        "    h1 = h",
    ]
    lines += [f"    h{k} = h{k - 1} * h" for k in range(2, pt + 1)]
    lines += [
        "    for t in range(nt):",
        "        for lane in range(SERIES_TILE):",
        "            o = t * TILE_STRIDE + lane",
        "            a0 = W[o]",
    ]
    lines += [f"            a{k} = W[o + {k} * SERIES_TILE] * h{k}" for k in range(1, pt + 1)]
    low = [f"abs(a{k})" for k in range(db + 1)]
    high = [f"abs(a{k})" for k in range(db + 1, pt + 1)]
    lines.append(f"            r = 64.0 * EPS * ({_chains(low)}) + {_chains(high)}")
    for i in range(1, db + 1):
        terms = ["a0"] + [f"{math.comb(i, k) / math.comb(db, k)!r} * a{k}"
                          for k in range(1, i + 1)]
        lines.append(f"            b{i} = {_chains(terms)}")
    bs = ", ".join(["a0"] + [f"b{i}" for i in range(1, db + 1)])
    lines += [
        f"            W[o + LO_ROW * SERIES_TILE] = min({bs}) - r",
        f"            W[o + HI_ROW * SERIES_TILE] = max({bs}) + r",
    ]
    return lines


_HEADER = [
    '"""Generated by ``python -m chainrun.solver._codegen``: do not edit by hand.',
    "",
    "The DOP853 stages, error estimate and dense output that ``_steppers`` steps with, the",
    "Taylor series' sums and bounds, and the DOP853 step of a damped pair's relative motion",
    "(``_pair_damped``), written out as straight-line code with their coefficients as",
    "literals (see ``_codegen``). To change them, edit ``_codegen.py`` and run::",
    "",
    "    python -m chainrun.solver._codegen          # rewrite this file",
    "    python -m chainrun.solver._codegen --check  # exit 1 if it is out of date",
    '"""',
    "",
    "from __future__ import annotations",
    "",
    "import numpy as np",
    "",
    "from chainrun.solver._drive import _drive_band, _drive_stage, _drive_terms",
    "from chainrun.solver._forces import (",
    "    _accelerations, _damped_accelerations, _damped_band, _damped_forces, _forces, _load,",
    "    _series_terms,",
    ")",
    "from chainrun.solver._jit import kernel",
    "from chainrun.solver._state import (",
    "    EPS, F_ALPHA, F_HLAST, F_JSL, F_JSR, F_NFLOAT, F_TOL, F_TPREV, F_WSTEP, HI_ROW,",
    "    I_DAMPED, I_DCUR, I_DRIVEN, I_LWL, I_M, I_MODE, I_NDRIVE, I_RWL, I_UNIT, J_OVER_K,",
    "    KV_DS, KV_VS, LO_ROW, PAIR_ATOL, PAIR_RTOL, SERIES_SCALE, SERIES_TILE, TILE_STRIDE,",
    "    W_ACC, W_ALPHA, W_IM, _find_cluster, _tw,",
    ")",
]


def _scalar_combo(coefs, names: list[str]) -> str:
    """``coefs @ names`` as a sum of literal terms (zero entries left out)."""
    terms = [f"{float(a)!r} * {n}" for a, n in zip(coefs, names) if float(a) != 0.0]
    return " + ".join(terms) if terms else "0.0"


def _pair_step() -> list[str]:
    """One DOP853 step of a damped pair's scaled relative motion (see _pair_damped)."""
    A, B = dop.A, dop.B
    ns = dop.N_STAGES
    # (the error estimate's weight on the step's end, a 13th stage, is 0)
    assert dop.E5[ns] == 0.0 and dop.E3[ns] == 0.0
    ks = [f"ks{i}" for i in range(ns)]
    ku = [f"ku{i}" for i in range(ns)]
    lines = [
        "@kernel",
        "def _pair_force(s, u, g, alpha, beta):",
        '    """-(s |s|^(alpha-1) + g |s|^beta u): the scaled pair\'s acceleration (a call, not',
        '    inlined: twelve copies of the law would cost compile time, not run time)."""',
        "    return -_load(1.0, alpha, g, beta, s, u)",
        "",
        "",
        "@kernel",
        "def _pair_step(s, u, h, g, alpha, beta):",
        '    """One DOP853 step of s\' = u, u\' = -(s |s|^(alpha-1) + g |s|^beta u) from (s, u):',
        "    (s, u) after h, and the error estimate scaled by PAIR_RTOL (accepted at <= 1).",
        '    """',
        "    ks0 = u",
        "    ku0 = _pair_force(s, u, g, alpha, beta)",
    ]
    for i in range(1, ns):
        lines += [
            f"    si = s + h * ({_scalar_combo(A[i, :i], ks[:i])})",
            f"    ui = u + h * ({_scalar_combo(A[i, :i], ku[:i])})",
            f"    ks{i} = ui",
            f"    ku{i} = _pair_force(si, ui, g, alpha, beta)",
        ]
    lines += [
        f"    s1 = s + h * ({_scalar_combo(B, ks[:ns])})",
        f"    u1 = u + h * ({_scalar_combo(B, ku[:ns])})",
        "    # the error norm of scipy's DOP853: RMS over (s, u) of |h| e5^2 / sqrt(e5^2 +",
        "    # e3^2 / 100), each scaled by its tolerance",
        "    sc = PAIR_ATOL + PAIR_RTOL * max(abs(s), abs(s1))",
        "    uc = PAIR_ATOL + PAIR_RTOL * max(abs(u), abs(u1))",
        f"    e5s = ({_scalar_combo(dop.E5[:ns], ks)}) / sc",
        f"    e5u = ({_scalar_combo(dop.E5[:ns], ku)}) / uc",
        f"    e3s = ({_scalar_combo(dop.E3[:ns], ks)}) / sc",
        f"    e3u = ({_scalar_combo(dop.E3[:ns], ku)}) / uc",
        "    n5 = e5s * e5s + e5u * e5u",
        "    d = n5 + 0.01 * (e3s * e3s + e3u * e3u)",
        "    if d == 0.0:",
        "        return s1, u1, 0.0",
        "    return s1, u1, abs(h) * n5 / np.sqrt(2.0 * d)",
    ]
    return lines


def _branch_error() -> list[str]:
    """DOP853's error estimate of a step that starts as a force A t^a begins, or ends as
    one vanishes: a contact closing or opening at compression 0, where c^alpha is a
    branch point (see ``_steppers._branch_step``)."""
    ns = dop.N_STAGES
    nodes = [f"k{i}" for i in range(ns)]
    (e5x,), (e3x,) = _nystrom(dop.E5), _nystrom(dop.E3)
    lines = [
        "@kernel",
        "def _branch_error(a, at_end):",
        '    """(g_v, g_x): the error estimate (_error_norm) of a ball\'s velocity and position',
        "    over a step of h from the instant an acceleration A t^a begins (or, at_end, to",
        "    the instant A (h - t)^a vanishes), over A h^(a + 1) and A h^(a + 2) and times the",
        "    tolerance: the stages see A (C h)^a (A ((1 - C) h)^a), and the estimate",
        "    e5^2 / sqrt(e5^2 + e3^2 / 100) of that alone. Both are 0 to rounding where a is",
        '    0, 1, 2 or 3: the estimate vanishes on a polynomial acceleration of low degree."""',
    ]
    lines += [f"    k{i} = ({float(1.0 - c)!r} if at_end else {float(c)!r}) ** a"
              for i, c in enumerate(dop.C[:ns])]
    out = []
    for name, e5, e3 in (("gv", dop.E5[:ns], dop.E3[:ns]), ("gx", e5x[:ns], e3x[:ns])):
        lines += [f"    e5 = {_scalar_combo(e5, nodes)}",
                  f"    e3 = {_scalar_combo(e3, nodes)}",
                  "    d = np.sqrt(e5 * e5 + 0.01 * e3 * e3)",
                  f"    {name} = e5 * e5 / d if d > 0.0 else 0.0"]
        out.append(name)
    lines.append(f"    return {', '.join(out)}")
    return lines


def generate() -> str:
    from chainrun.solver._state import DB, PT, SERIES_TILE

    A, B, C = dop.A, dop.B, dop.C
    ns, nse = dop.N_STAGES, dop.N_STAGES_EXTENDED
    AA = _exact_product(A, A)  # stage positions: X0 + h C V0 + h^2 (A @ A) @ KV
    lines = [
        *_HEADER,
        "",
        "",
        "@kernel",
        "def _stages(S, h):",
        '    """The 12 stages of a DOP853 step from (X0, V0, A0): new (X, V), stages in KV.',
        "",
        "    DOP853 applied to y = (x, v), y' = (v, a(x, v)), written in Nystrom form:",
        "    KV[s] holds the stage accelerations and KV[12] those at the step's end. The",
        "    stage velocities are needed only on a damped line (VS), where the lanes'",
        "    dissipated power is summed with the step's weights into DS. The walls'",
        "    forces are summed likewise into their impulses over the step (F_JSL, F_JSR),",
        "    and on a driven line the drives' power into their work over it (F_WSTEP).",
        '    """',
        *_PROLOGUE,
        "    KV, X0, V0, A0, X, V = S.KV, S.X0, S.V0, S.A0, S.X, S.V",
        "    lwl = S.ints[I_LWL]",
        "    rwl = S.ints[I_RWL]",
        "    for p in range(m):",
        "        KV[0, p] = A0[p]",
        "    if damped:",
        "        for p in range(m):",
        "            DS[p] = 0.0",
        f"        _damped_forces(X0, V0, F, MK, WP, DS, h * {float(B[0])!r}, m, mode, alpha)",
        "    else:",
        "        if lwl >= 0:",
        "            _forces(X0, F, MK, WP[W_ALPHA], lwl, lwl + 1, mode, alpha)",
        "        if rwl >= 0:",
        "            _forces(X0, F, MK, WP[W_ALPHA], rwl, rwl + 1, mode, alpha)",
        "    jl = 0.0",
        "    jr = 0.0",
        "    if lwl >= 0:",
        f"        jl = h * {float(B[0])!r} * F[lwl]",
        "    if rwl >= 0:",
        f"        jr = h * {float(B[0])!r} * F[rwl]",
        "    jw = 0.0",
        "    if driven:",
        "        for d in range(nd):",
        "            S.fs[dvo + d] = V0[S.ints[dco + 2 * d + 1]]",
        f"        jw = _drive_stage(S, KV[0], F, t0, h * {float(B[0])!r}, False)",
    ]
    for s in range(1, ns):
        lines += _stage_pass("X", s, C[s], AA[s, :s], A[s, :s], B[s])
    lines += [
        "    for p in range(m):",
        f"        X[p] = X0[p] + h * (V0[p] + {_combo(AA[ns, :ns], 'KV', 'h')})",
        f"        V[p] = V0[p] + {_combo(B, 'KV', 'h')}",
        *_force_pass("X", ns, v="V"),
        "    S.fs[F_JSL] = jl",
        "    S.fs[F_JSR] = jr",
        "    S.fs[F_WSTEP] = jw",
    ]
    e5x, e3x = _nystrom(dop.E5), _nystrom(dop.E3)
    lines += [
        "",
        "",
        "@kernel",
        "def _error_norm(S, h):",
        '    """DOP853\'s error estimate of the last step, max over balls, scaled by the tolerance.',
        "",
        "    Per component e = |h| e5^2 / (sqrt(d) sc), d = e5^2 + e3^2 / 100; the largest",
        "    e^2 = h^2 e5^4 / (d sc^2) is kept as a fraction, so the loop takes no square",
        "    root or division per ball. An infinite or NaN fraction is kept: it fails the",
        "    step.",
        '    """',
        "    m = S.ints[I_M]",
        "    KV, X0, V0, X, V = S.KV, S.X0, S.V0, S.X, S.V",
        "    tol = S.fs[F_TOL]",
        "    num = 0.0",
        "    den = 1.0",
        "    for p in range(m):",
    ]
    for e5, e3, y0, y1 in ((e5x[0], e3x[0], "X0", "X"), (dop.E5, dop.E3, "V0", "V")):
        scale = "h" if y0 == "X0" else "1.0"
        lines += [
            f"        e5 = {_combo(e5, 'KV', scale)}",
            f"        e3 = {_combo(e3, 'KV', scale)}",
            f"        sc = tol + 64.0 * EPS * max(abs({y0}[p]), abs({y1}[p]))",
            "        n = e5 * e5 * e5 * e5",
            "        d = (e5 * e5 + 0.01 * e3 * e3) * sc * sc",
            "        if num < np.inf and not n * den <= num * d:",
            "            num = n",
            "            den = d",
        ]
    lines += [
        "    return abs(h) * np.sqrt(num / den)",
        "",
        "",
        "@kernel",
        "def _dense_stages(S):",
        '    """The three extra stages of the dense output (positions staged in XS)."""',
        *_PROLOGUE,
        "    h = S.fs[F_HLAST]",
        "    KV, X0, V0, Xs = S.KV, S.X0, S.V0, S.XS",
    ]
    for s in range(ns + 1, nse):
        lines += _stage_pass("Xs", s, C[s], AA[s, :s], A[s, :s])
    lines += [
        "",
        "",
        "@kernel",
        "def _dense_ball(S, p):",
        '    """The three extra stages of the dense output at compact ball p alone.',
        "",
        "    Each stage's accelerations at a ball need its positions (on a damped line, and",
        "    velocities) one ball further each way, so the last stage at p needs the first",
        "    on p - 3 .. p + 3. Every band is cut at the ends of p's cluster, where its",
        "    forces stop. Each ball's stages are those the whole window's give",
        "    (_dense_stages): the same operations.",
        '    """',
        "    h = S.fs[F_HLAST]",
        *_band_prologue("KV, X0, V0, Xs, F, MK, WP = S.KV, S.X0, S.V0, S.XS, S.FS, S.TR, S.WP"),
    ]
    for s in range(ns + 1, nse):
        lines += _band_pass(s, nse - s, C[s], AA[s, :s], A[s, :s])
    lines += [
        "",
        "",
        "@kernel",
        "def _step_band(S, h, p):",
        '    """A DOP853 step of h from (X0, V0, A0) at compact balls p and p + 1 alone: their',
        "    X, V and A at its end, the numbers the whole window's step gives them (the same",
        "    operations).",
        "",
        "    Each stage's accelerations at a ball need the previous stage's positions (on a",
        "    damped line, and velocities) one ball further each way, so the end's at p and",
        f"    p + 1 need the first stage's on p - {ns + 1} .. p + {ns + 1}; the balls between hold the",
        "    stages' values, not the step's. Every band is cut at the ends of p's cluster,",
        "    where its forces stop. The walls' impulses, the drives' work, the damping's",
        "    power and the error estimate are not taken: a step that is kept is taken whole",
        "    (``_steppers._step``).",
        '    """',
        *_band_prologue("KV, X0, V0, A0, X, V, A = S.KV, S.X0, S.V0, S.A0, S.X, S.V, S.A"),
        "    F, MK, WP = S.FS, S.TR, S.WP",
        f"    for q in range(max(o, p - {ns + 1}), min(e, p + {ns + 1}) + 1):",
        "        KV[0, q] = A0[q]",
    ]
    for s in range(1, ns):
        lines += _band_pass(s, ns + 2 - s, C[s], AA[s, :s], A[s, :s], out="X")
    lines += _band_pass(ns, 2, 1.0, AA[ns, :ns], B, out="X", end=True)
    dx = _nystrom(dop.D)
    lines += [
        "",
        "",
        "@kernel(inline=\"always\")",
        "def _dense_rows(S, p):",
        '    """Rows 3..6 of ball p\'s interpolant: h * D @ K for positions and velocities."""',
        "    h = S.fs[F_HLAST]",
        "    KV, FX, FV = S.KV, S.FX, S.FV",
    ]
    for r in range(dop.D.shape[0]):
        lines.append(f"    FX[{3 + r}, p] = h * {_combo(dx[r], 'KV', 'h')}")
        lines.append(f"    FV[{3 + r}, p] = {_combo(dop.D[r], 'KV', 'h')}")
    lines += ["", ""] + _linear(PT, SERIES_TILE)
    lines += ["", ""] + _series(PT, SERIES_TILE, False) + ["", ""]
    lines += _series(PT, SERIES_TILE, True) + ["", ""] + _bounds(PT, DB)
    lines += ["", ""] + _pair_step()
    lines += ["", ""] + _branch_error()
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    new = generate()
    if "--check" in argv:
        if not TARGET.exists() or new != TARGET.read_text():
            print(f"{TARGET} is out of date: run python -m chainrun.solver._codegen")
            return 1
        return 0
    TARGET.write_text(new)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
