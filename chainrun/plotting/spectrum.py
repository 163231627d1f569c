"""The figure of a spectrum file: mode frequencies, and a periodic line's bands.

``draw_spectrum(ds)`` draws the Dataset ``chainrun.store.read_spectrum`` reads: the
angular frequency of each normal mode against its number and, for a periodic line, the
dispersion relation omega(q) beside it on the same frequency axis, its pass bands
shaded and its gaps marked; the frequency f = omega / (2 pi) on a second axis at the
right, in the unit drives are given in (Hz in SI). Colours are the Okabe-Ito palette, which readers with any
common colour-vision deficiency tell apart. Each artist carries a ``gid`` naming the
variable it shows.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from chainrun.units import axis_label

__all__ = ["OKABE_ITO", "draw_spectrum"]

#: Okabe & Ito's colour-blind-safe palette: blue, vermillion, bluish green, orange,
#: reddish purple, sky blue.
OKABE_ITO = ("#0072B2", "#D55E00", "#009E73", "#E69F00", "#CC79A7", "#56B4E9")
#: More modes than this are drawn as a line rather than as markers.
MARKED_MODES = 120
_BAND = dict(facecolor="0.88", edgecolor="none")
_GAP = dict(facecolor="#E69F00", alpha=0.2, edgecolor="none")


def _units(ds) -> str:
    return "si" if ds.attrs.get("units") == "SI" else "paper"


def _modes(axes, ds, scaled, label: str) -> None:
    mode, omega = ds["mode"].values, scaled(ds["omega"].values)
    style = (dict(marker="o", markersize=3, linestyle="none", clip_on=False)
             if mode.size <= MARKED_MODES else dict(linestyle="-"))
    axes.plot(mode, omega, color=OKABE_ITO[0], gid="omega", label="normal modes", **style)
    axes.set_xlabel("mode number")
    axes.xaxis.set_major_locator(MaxNLocator(integer=True))
    axes.set_ylabel(label)
    axes.set_xlim(0.5 if mode.size <= MARKED_MODES else 0, mode[-1] + 0.5)


def _bands(axes, ds, scaled) -> None:
    """The pass bands shaded, and the gaps between them marked."""
    bottom, top = scaled(ds["band_bottom"].values), scaled(ds["band_top"].values)
    for b, (low, high) in enumerate(zip(bottom, top)):
        axes.axhspan(low, high, gid=f"band/{b + 1}", **_BAND)
    for b in range(bottom.size - 1):
        if bottom[b + 1] > top[b]:
            axes.axhspan(top[b], bottom[b + 1], gid=f"gap/{b + 1}", **_GAP)


def _hertz(axes, scaled, omega: np.ndarray, units: str) -> None:
    """A second frequency axis on the right of ``axes``: f = omega / (2 pi), in its own
    readable unit (Hz in SI, as drives are given), beside the angular one."""
    label, in_hertz = axis_label(r"frequency $f = \omega / 2\pi$", "frequency", units,
                                 omega / (2.0 * np.pi))
    ratio = in_hertz(1.0) / scaled(1.0) / (2.0 * np.pi)  # f drawn per omega drawn
    axis = axes.secondary_yaxis("right", functions=(lambda w: w * ratio,
                                                    lambda f: f / ratio))
    axes.tick_params(axis="y", which="both", right=False)  # (the f axis's ticks only)
    axis.set_ylabel(label)
    axis.set_gid("frequency")


def _name(ds) -> str:
    """The experiment and run a spectrum is of, and what its line is (``views.describe``,
    from the experiment file the spectrum keeps), from its attributes ("" if unknown)."""
    experiment, run_id = ds.attrs.get("experiment", ""), ds.attrs.get("run_id", "")
    name = experiment + (f" ({run_id})" if run_id and run_id != "run" else "")
    line = _line(ds.attrs.get("config", ""), run_id or "run")
    return "\n".join(filter(None, [name, line]))


def _line(text: str, run_id: str) -> str:
    """What the line of run ``run_id`` of the experiment file ``text`` is, in words
    ("" where the text is not an experiment file this version reads)."""
    from types import SimpleNamespace

    from chainrun.config import parse_experiment
    from chainrun.errors import ChainrunError
    from chainrun.plotting.views import describe

    for fmt in ("toml", "yaml"):
        try:
            specs = parse_experiment(text, fmt, to_run=False).runs(to_run=False)
        except (ChainrunError, ValueError, TypeError):
            continue
        for spec in specs:
            if spec.run_id == run_id:
                run = SimpleNamespace(line=spec.line, units=spec.units,
                                      parameters={"config_resolved": spec.config})
                return describe(run, spec.overrides, width=90)
    return ""


def draw_spectrum(ds) -> Figure:
    """The figure of spectrum Dataset ``ds``: modes, and the dispersion relation with
    its band edges for a periodic line, titled by the experiment and run it is of.
    Call inside ``chainrun.plotting.style()``."""
    units = _units(ds)
    periodic = "dispersion" in ds
    values = [ds["omega"].values] + ([ds["dispersion"].values] if periodic else [])
    omega = np.concatenate([np.ravel(v) for v in values])
    label, scaled = axis_label(r"angular frequency $\omega$", "angular_frequency", units,
                               omega)
    if not periodic:
        figure = Figure(layout="constrained")
        axes = figure.add_subplot()
        _modes(axes, ds, scaled, label)
        axes.set_ylim(0.0, None)
        _hertz(axes, scaled, omega, units)
        axes.set_title(f"{ds['mode'].size} normal modes of the line at rest")
        if _name(ds):
            figure.suptitle(_name(ds), fontsize="medium")
        return figure
    figure = Figure(figsize=(8.4, 3.6), layout="constrained")
    left, right = figure.subplots(1, 2, sharey=True, width_ratios=(1.4, 1.0))
    _bands(left, ds, scaled)
    _modes(left, ds, scaled, label)
    left.set_title(f"{ds['mode'].size} normal modes of the line at rest")
    _bands(right, ds, scaled)
    q = ds["q"].values
    for b, branch in enumerate(ds["branch"].values):
        right.plot(q, scaled(ds["dispersion"].sel(branch=branch).values),
                   color=OKABE_ITO[(b + 1) % len(OKABE_ITO)], gid=f"dispersion/{branch}")
    for edge in np.concatenate((ds["band_bottom"].values, ds["band_top"].values)):
        right.axhline(scaled(edge), color="0.35", linestyle="--", linewidth=0.6,
                      gid="band_edge")
    right.set_xlim(0.0, np.pi)
    right.set_xticks([0.0, np.pi / 2, np.pi], ["0", r"$\pi/2$", r"$\pi$"])
    right.set_xlabel("wavenumber $q$ (rad per cell)")
    period = int(ds.attrs.get("period", ds["branch"].size))
    right.set_title(f"infinite line, {period} ball{'s' * (period != 1)} per cell")
    left.set_ylim(0.0, None)
    _hertz(right, scaled, omega, units)
    handles = [left.get_lines()[0], Patch(label="pass band", **_BAND)]
    if any(a.get_gid().startswith("gap/") for a in left.patches):
        handles.append(Patch(label="band gap", **_GAP))
    left.legend(handles=handles, loc="lower right", frameon=True, facecolor="white",
                edgecolor="0.6", framealpha=1.0)
    if _name(ds):
        figure.suptitle(_name(ds), fontsize="medium")
    return figure
