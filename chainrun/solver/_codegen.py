"""Writes the DOP853 stage loops of ``_kernels.py`` as straight-line code.

The stage sums of an explicit Runge-Kutta step are fixed linear combinations of the
previous stages. Written as loops over the tableau, a window of a dozen balls spends
its time in loop overhead; written out with the coefficients as literals, each stage
is one pass over the balls. This script regenerates the section of ``_kernels.py``
between the markers below from scipy's DOP853 tableau::

    python -m chainrun.solver._codegen          # rewrite the section
    python -m chainrun.solver._codegen --check  # exit 1 if it is out of date
"""

from __future__ import annotations

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


def _stage_pass(out_x: str, out_kx: str, coefs) -> list[str]:
    return [
        "    for p in range(m):",
        f"        {out_x}[p] = X0[p] + {_combo(coefs, 'KX', 'h')}",
        f"        {out_kx}[p] = V0[p] + {_combo(coefs, 'KV', 'h')}",
    ]


def generate() -> str:
    A, B = dop.A, dop.B
    ns, nse = dop.N_STAGES, dop.N_STAGES_EXTENDED
    lines = [
        BEGIN,
        "@nb.njit(cache=True)",
        "def _stages(S, h):",
        '    """The 12 stages of a DOP853 step from (X0, V0, A0): new X in X, new V in KX[12].',
        "",
        "    KX[s] holds the stage velocities (the x part of f), KV[s] the accelerations.",
        '    """',
        "    m = S.ints[I_M]",
        "    KX, KV, X0, V0, A0, X = S.KX, S.KV, S.X0, S.V0, S.A0, S.X",
        "    for p in range(m):",
        "        KX[0, p] = V0[p]",
        "        KV[0, p] = A0[p]",
    ]
    for s in range(1, ns):
        lines += _stage_pass("X", f"KX[{s}]", A[s, :s])
        lines.append(f"    _rhs(S, X, KV[{s}])")
    lines += _stage_pass("X", f"KX[{ns}]", B)
    lines.append(f"    _rhs(S, X, KV[{ns}])")
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
        "def _dense_stages(S, Xs):",
        '    """The three extra stages of the dense output, positions staged in Xs."""',
        "    m = S.ints[I_M]",
        "    h = S.fs[F_HLAST]",
        "    KX, KV, X0, V0 = S.KX, S.KV, S.X0, S.V0",
    ]
    for s in range(ns + 1, nse):
        lines += _stage_pass("Xs", f"KX[{s}]", A[s, :s])
        lines.append(f"    _rhs(S, Xs, KV[{s}])")
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
    lines.append(END)
    return "\n".join(lines) + "\n"


def _splice(text: str, section: str) -> str:
    a = text.index(BEGIN)
    b = text.index(END) + len(END) + 1
    return text[:a] + section + text[b:]


def main(argv: list[str]) -> int:
    text = TARGET.read_text()
    new = _splice(text, generate())
    if "--check" in argv:
        if new != text:
            print(f"{TARGET} is out of date: run python -m chainrun.solver._codegen")
            return 1
        return 0
    TARGET.write_text(new)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
