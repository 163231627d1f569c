"""Plotting: figures and tables drawn from analysis files, and nothing computed anew.

This package owns the look of every output. ``render_run(path)`` draws the standard
views of any run file (``views``), ``render_spectrum(path)`` the figure of a spectrum
file (``spectrum``). ``render(name)`` reads the artefact's analysis
file (through ``chainrun.store``), asks the artefact's module (``chainrun.plotting.figNN``,
``table1``, ``comparison``) to draw it, and writes the outputs named in
``chainrun.artefacts``:

- a figure module has ``draw(data) -> matplotlib.figure.Figure``; the figure is saved as
  PNG and PDF with the shipped style ``chainrun.mplstyle`` and fixed metadata, so a
  rebuild gives the same bytes;
- a table module has ``write(data) -> dict`` from file suffix (".md", ".csv") to text.

pyplot is never used: figures are plain ``Figure`` objects, so no GUI backend or global
state is involved.
"""

from __future__ import annotations

import importlib
import math
from contextlib import contextmanager
from pathlib import Path

from chainrun import artefacts, atomic
from chainrun.errors import ChainrunError
from chainrun.store import AnalysisData, read_analysis

__all__ = ["STYLE", "draw", "render", "render_run", "render_spectrum", "render_sweep",
           "style"]

#: The one matplotlib style of chainrun, shipped in the package.
STYLE = Path(__file__).with_name("chainrun.mplstyle")

#: Metadata written into every file: nothing that changes from one build to the next.
PNG_METADATA = {"Software": None}
PDF_METADATA = {"Creator": "chainrun", "Producer": None, "CreationDate": None,
                "ModDate": None}


#: Line styles that go with the colour cycle of views: two curves differ in style as
#: well as in colour, in grey print and for colour-blind readers. Nine styles against
#: ten colours: the pairs repeat only after 90 curves, so the eleventh curve is not
#: the first one again. The dotted styles go with the cycle's dark colours (red, dark
#: grey), the light ones (grey, khaki) with dashes: a light dotted curve is faint.
LINESTYLES = ("-", "--", ":", "-.", (0, (5, 1)), (0, (3, 1, 1, 1)), (0, (5, 2, 1, 2)),
              (0, (8, 2)), (0, (1, 1)))


@contextmanager
def style(colour: bool = False):
    """Use chainrun's style (and only it) inside the block.

    The paper's figures are black and white, as the paper's are. ``colour`` gives the
    views of runs matplotlib's colour-blind-safe cycle ``petroff10`` (M. A. Petroff,
    "Accessible Color Sequences for Data Visualization", 2024), with line styles that
    make every curve of up to 90 one of its own (``LINESTYLES``), and tick labels as
    plain text rather than mathtext (the same look, and a third of a view's drawing
    time spared: ``chainrun plot`` of a sweep draws dozens).
    """
    import matplotlib
    import matplotlib.style
    from cycler import cycler

    with matplotlib.rc_context():
        matplotlib.rcdefaults()
        matplotlib.style.use(STYLE)
        if colour:
            colours = matplotlib.style.library["petroff10"]["axes.prop_cycle"].by_key()["color"]
            n = math.lcm(len(colours), len(LINESTYLES))
            colours = colours * (n // len(colours))
            styles = list(LINESTYLES) * (n // len(LINESTYLES))
            matplotlib.rcParams["axes.prop_cycle"] = (cycler(color=colours)
                                                      + cycler(linestyle=styles))
            matplotlib.rcParams["axes.formatter.use_mathtext"] = False
        yield


def _module(artefact: artefacts.Artefact):
    if artefact.plot is None:
        raise ChainrunError(f"{artefact.name} has no figure or table of its own (it only "
                            "feeds the comparison); see `chainrun plot --list`")
    return importlib.import_module(f"chainrun.plotting.{artefact.plot}")


def draw(name: str, data: AnalysisData):
    """The matplotlib Figure of figure artefact ``name``, drawn from ``data``.

    Must be called inside ``style()`` for the figure to look as saved.
    """
    return _module(artefacts.get(name)).draw(data)


def render(name: str, *, results="results") -> list[Path]:
    """Draw artefact ``name`` from its analysis file and write its outputs.

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    ChainrunError
        If the artefact is unknown, has no outputs, or its analysis file is missing.
    """
    try:
        artefact = artefacts.get(name)
    except KeyError as exc:
        raise ChainrunError(exc.args[0]) from None
    module = _module(artefact)
    source = artefacts.analysis_path(name, results)
    if not source.exists():
        raise ChainrunError(f"{source}: missing; run `chainrun analyze {name}` first")
    data = read_analysis(source)
    outputs = artefacts.output_paths(artefact, results)
    for path in outputs:
        path.parent.mkdir(parents=True, exist_ok=True)
    if artefact.kind == "figure":
        with style():
            _save(module.draw(data), outputs)
    else:
        texts = module.write(data)
        for path in outputs:
            text = texts[path.suffix]
            atomic.write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return outputs


def _save(figure, outputs: list[Path]) -> None:
    """Write ``figure`` to each path (PNG or PDF) atomically, with the fixed metadata."""
    for path in outputs:
        metadata = PNG_METADATA if path.suffix == ".png" else PDF_METADATA
        atomic.write(path, lambda tmp: figure.savefig(
            tmp, format=path.suffix[1:], metadata=metadata))


def render_run(path, views=None, *, out=None, log: bool = False) -> list[Path]:
    """Draw the standard views (``views.VIEWS``; by default every one the run has data
    for) of the run file at ``path``.

    Each view goes to ``<out>/<run file stem>-<view>.png`` and ``.pdf``; ``out``
    defaults to a ``figures`` folder beside the run file. Returns the files written.

    Raises
    ------
    ChainrunError
        If the file is not a run file, a view is unknown, or the run lacks the
        snapshots a view needs.
    """
    from chainrun.plotting.views import VIEWS, draw_view
    from chainrun.store import read_run

    path = Path(path)
    run = read_run(path)
    if views is None:  # every view the run has data for
        views = [v for v in VIEWS if v == "final"
                 or (v == "sensors" and run.sensor_balls.size)
                 or (v != "sensors" and run.times.size >= 2)]
    out = path.parent / "figures" if out is None else Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    with style(colour=True):
        for view in views:
            outputs = [out / f"{path.stem}-{view}{suffix}" for suffix in (".png", ".pdf")]
            _save(draw_view(run, view, log=log), outputs)
            written += outputs
    return written


#: The views of a sweep's folder as a whole (``render_sweep``).
SWEEP_VIEWS = ("sweep-final", "sweep-runs", "sweep-pulses", "ensemble", "transmission")


def render_sweep(folder, balls=(1, -1), *, out=None, log: bool = False,
                 ensemble=None, transmission=None, pulses=None, views=None) -> list[Path]:
    """Draw the sweep in ``folder`` (its index.h5), as PNG and PDF in ``out`` (default
    ``folder/figures``): a panel of final velocities per run (``sweep-runs``), and the
    final velocities of ``balls`` against each swept key (``sweep-final``); or, given
    the statistics of an ensemble (``chainrun.analysis.ensemble.Ensemble``: runs that
    differ only in their random seeds), its mean and spread (``ensemble``) instead of
    the latter; given the ``pulses`` of a sweep over one key
    (``chainrun.analysis.pulse_sweep.PulseSweep``), their wave speed, peak force and
    width against that key (``sweep-pulses``). Given the transmission curve of a sweep over a drive's frequency
    (``chainrun.transmission``), that curve against the line's bands
    (``transmission``) alone: the velocities where a driven run stops are a snapshot of
    its oscillation, not a result. ``views`` (names of ``SWEEP_VIEWS``) picks among
    those the sweep has. Returns the files written."""
    from chainrun.plotting.pulses import draw_sweep_pulses
    from chainrun.plotting.transmission import draw_transmission
    from chainrun.plotting.views import (
        describe,
        draw_ensemble,
        draw_sweep,
        draw_sweep_runs,
    )
    from chainrun.store import read_index, read_run

    folder = Path(folder)
    runs = [read_run(folder / str(row["file"])) for row in read_index(folder / "index.h5")]
    if transmission is not None:
        has = ["transmission"]
    else:
        has = ["ensemble" if ensemble is not None else "sweep-final", "sweep-runs"]
        if pulses is not None:
            has.append("sweep-pulses")
    wanted = has if views is None else [v for v in views if v in has]
    if views is not None and not wanted:
        raise ChainrunError(f"{folder}: this sweep has no view {', '.join(views)} (it has "
                            f"{', '.join(has)})")
    out = folder / "figures" if out is None else Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    with style(colour=True):
        for name in wanted:
            if name == "ensemble":
                figure = draw_ensemble(ensemble, runs[0])
            elif name == "sweep-final":
                figure = draw_sweep(runs, balls)
            elif name == "sweep-runs":
                figure = draw_sweep_runs(runs, log=log)
            elif name == "sweep-pulses":
                title = "\n".join([f"{runs[0].parameters.get('experiment', '')}: "
                                   f"{len(runs)} runs",
                                   describe(runs[0], [pulses.key], width=120)])
                figure = draw_sweep_pulses(pulses, title)
            else:
                keys = runs[0].parameters.get("overrides", {})
                title = "\n".join([runs[0].parameters.get("experiment", ""),
                                   describe(runs[0], keys, width=90)])
                figure = draw_transmission(transmission, title)
            outputs = [out / f"{name}{suffix}" for suffix in (".png", ".pdf")]
            _save(figure, outputs)
            written += outputs
    return written


def render_spectrum(path, *, out=None) -> list[Path]:
    """Draw the spectrum file at ``path`` (``chainrun.store.write_spectrum``): its
    modes and, for a periodic line, its dispersion relation and bands
    (``spectrum.draw_spectrum``), to ``<out>/<file stem>.png`` and ``.pdf`` (``out``
    defaults to the file's folder). Returns the files written.

    Raises
    ------
    ChainrunError
        If the file is not a spectrum file.
    """
    from chainrun.plotting.spectrum import draw_spectrum
    from chainrun.store import read_spectrum

    path = Path(path)
    ds = read_spectrum(path)
    out = path.parent if out is None else Path(out)
    out.mkdir(parents=True, exist_ok=True)
    outputs = [out / f"{path.stem}{suffix}" for suffix in (".png", ".pdf")]
    with style():
        _save(draw_spectrum(ds), outputs)
    return outputs
