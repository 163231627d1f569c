"""Writes the DOP853 stage loops of ``_kernels.py`` as straight-line code.

(It also writes ``_borrowed_state``, which must name every field of ``State``.)

The stage sums of an explicit Runge-Kutta step are fixed linear combinations of the
previous stages. Written as loops over the tableau, a window of a dozen balls spends
its time in loop overhead; written out with the coefficients as literals, each stage
is one pass over the balls. This script regenerates the section of ``_kernels.py``
between the markers below from scipy's DOP853 tableau::

    python -m chainrun.solver._codegen          # rewrite the section
    python -m chainrun.solver._codegen --check  # exit 1 if it is out of date
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
from scipy.integrate._ivp import dop853_coefficients as dop

BEGIN = "# ---- BEGIN GENERATED STAGES (python -m chainrun.solver._codegen) ----"
END = "# ---- END GENERATED STAGES ----"
TARGET = Path(__file__).with_name("_kernels.py")


def _combo(coefs, rows: str, scale: str) -> str:
    terms = [f"{float(a)!r} * {rows}[{i}, p]" for i, a in enumerate(coefs) if a != 0.0]
    return f"{scale} * (" + " + ".join(terms) + ")"


def _stage_pass(out_x: str, s: int, coefs) -> list[str]:
    """Stage s: positions into out_x, velocities into KX[s], accelerations into KV[s]."""
    return [
        "    for p in range(m):",
        f"        {out_x}[p] = X0[p] + {_combo(coefs, 'KX', 'h')}",
        f"        KX[{s}, p] = V0[p] + {_combo(coefs, 'KV', 'h')}",
        "    for c in range(ncl):",
        "        o = coff[c]",
        "        e = o + chi[c] - clo[c]",
        "        prev = 0.0",
        "        for p in range(o, e):",
        f"            f = _force({out_x}[p] - {out_x}[p + 1], mode, alpha)",
        f"            KV[{s}, p] = prev - f",
        "            prev = f",
        f"        KV[{s}, e] = prev",
    ]


_PROLOGUE = [
    "    m = S.ints[I_M]",
    "    ncl = S.ints[I_NCL]",
    "    mode = S.ints[I_MODE]",
    "    alpha = S.fs[F_ALPHA]",
    "    coff, clo, chi = S.coff, S.clo, S.chi",
]


def _state_fields(text: str) -> list[str]:
    block = text[text.index("State = namedtuple("):]
    block = block[block.index("[") : block.index("]")]
    return re.findall(r'"(\w+)"', block)


def generate(text: str) -> str:
    A, B = dop.A, dop.B
    ns, nse = dop.N_STAGES, dop.N_STAGES_EXTENDED
    lines = [
        BEGIN,
        "@nb.njit(cache=True)",
        "def _stages(S, h):",
        '    """The 12 stages of a DOP853 step from (X0, V0, A0): new X in X, new V in KX[12].',
        "",
        "    KX[s] holds the stage velocities (the x part of f), KV[s] the accelerations",
        "    (the force loop of _rhs, written out so no array view is made per stage).",
        '    """',
        *_PROLOGUE,
        "    KX, KV, X0, V0, A0, X = S.KX, S.KV, S.X0, S.V0, S.A0, S.X",
        "    for p in range(m):",
        "        KX[0, p] = V0[p]",
        "        KV[0, p] = A0[p]",
    ]
    for s in range(1, ns):
        lines += _stage_pass("X", s, A[s, :s])
    lines += _stage_pass("X", ns, B)
    lines += [
        "",
        "",
        "@nb.njit(cache=True)",
        "def _error_norm(S, h):",
        '    """DOP853\'s error estimate of the last step, max over balls, scaled by the tolerance."""',
        "    m = S.ints[I_M]",
        "    KX, KV, X0, V0, X, V = S.KX, S.KV, S.X0, S.V0, S.X, S.V",
        "    tol = S.fs[F_TOL]",
        "    err = 0.0",
        "    for p in range(m):",
    ]
    for comp, rows, y0, y1 in (("x", "KX", "X0", "X"), ("v", "KV", "V0", "V")):
        lines += [
            f"        e5 = {_combo(dop.E5, rows, '1.0')}",
            f"        e3 = {_combo(dop.E3, rows, '1.0')}",
            f"        sc = tol + 64.0 * EPS * max(abs({y0}[p]), abs({y1}[p]))",
            "        d = e5 * e5 + 0.01 * e3 * e3",
            "        if d > 0.0:",
            "            e = abs(h) * e5 * e5 / (np.sqrt(d) * sc)",
            "            if e > err:",
            "                err = e",
        ]
    lines += [
        "    return err",
        "",
        "",
        "@nb.njit(cache=True)",
        "def _dense_stages(S):",
        '    """The three extra stages of the dense output (positions staged in XS)."""',
        *_PROLOGUE,
        "    h = S.fs[F_HLAST]",
        "    KX, KV, X0, V0, Xs = S.KX, S.KV, S.X0, S.V0, S.XS",
    ]
    for s in range(ns + 1, nse):
        lines += _stage_pass("Xs", s, A[s, :s])
    lines += [
        "",
        "",
        "@nb.njit(cache=True)",
        "def _dense_rows(S):",
        '    """Rows 3..6 of the interpolant: h * D @ K for positions and velocities."""',
        "    m = S.ints[I_M]",
        "    h = S.fs[F_HLAST]",
        "    KX, KV, FX, FV = S.KX, S.KV, S.FX, S.FV",
        "    for p in range(m):",
    ]
    for r in range(dop.D.shape[0]):
        lines.append(f"        FX[{3 + r}, p] = {_combo(dop.D[r], 'KX', 'h')}")
        lines.append(f"        FV[{3 + r}, p] = {_combo(dop.D[r], 'KV', 'h')}")
    lines += [
        "",
        "",
        "@nb.njit(cache=True)",
        "def _borrowed_state(S):",
        '    """The state with every array borrowed (see _borrowed)."""',
        "    return State(",
        *[f"        _borrowed(S.{f})," for f in _state_fields(text)],
        "    )",
    ]
    lines.append(END)
    return "\n".join(lines) + "\n"


def _splice(text: str, section: str) -> str:
    a = text.index(BEGIN)
    b = text.index(END) + len(END) + 1
    return text[:a] + section + text[b:]


def main(argv: list[str]) -> int:
    text = TARGET.read_text()
    new = _splice(text, generate(text))
    if "--check" in argv:
        if new != text:
            print(f"{TARGET} is out of date: run python -m chainrun.solver._codegen")
            return 1
        return 0
    TARGET.write_text(new)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
