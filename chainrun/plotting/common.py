"""What the figure modules share: a blank figure, the paper's symbols, and drawing a series.

Every curve or set of markers drawn comes from one series of the analysis file
(``series/<name>/x`` and ``.../y``) and carries ``gid = "series/<name>"``, so the tests can
match each line on the axes with the arrays it was drawn from.
"""

from __future__ import annotations

from matplotlib.figure import Figure

from chainrun.store import AnalysisData

__all__ = ["MARKERS", "draw_series", "new_figure", "series_names"]

#: The paper's symbols, in the order its captions list them:
#: diamond, plus, square, cross, triangle, star.
MARKERS = (
    dict(marker="D", markerfacecolor="none", markersize=4.5),
    dict(marker="+", markersize=6),
    dict(marker="s", markerfacecolor="none", markersize=4.5),
    dict(marker="x", markersize=5),
    dict(marker="^", markerfacecolor="none", markersize=5),
    dict(marker="*", markersize=6),
)


def new_figure():
    """A figure with one axes, sized by the style."""
    figure = Figure()
    axes = figure.add_subplot()
    return figure, axes


def series_names(data: AnalysisData, role: str | None = None, group: str = "series") -> list[str]:
    """The series of the analysis file, in the order written, optionally of one role."""
    names = data.children(group)
    if role is None:
        return names
    return [n for n in names if data.attrs.get(f"{group}/{n}", {}).get("role") == role]


def draw_series(axes, data: AnalysisData, name: str, group: str = "series", **style):
    """Plot one series as stored; returns the Line2D."""
    key = f"{group}/{name}"
    attrs = data.attrs.get(key, {})
    style.setdefault("label", attrs.get("label", name))
    style.setdefault("color", "black")
    (line,) = axes.plot(data.arrays[f"{key}/x"], data.arrays[f"{key}/y"], gid=key, **style)
    return line


def draw_loss_waves(data: AnalysisData, ylabel: str, legend_loc: str,
                    legend_ncol: int = 1):
    """One quantity against n at the times balls 10, 20, 30 and 40 lose contact
    (figures 3 and 4), one line style per time."""
    figure, ax = new_figure()
    for name, style in zip(series_names(data, "data"), ("-", "--", "-.", ":")):
        draw_series(ax, data, name, linestyle=style)
    ax.set_xlabel(r"$n$")
    ax.set_ylabel(ylabel)
    ax.set_xlim(0.0, 50.0)
    ax.legend(loc=legend_loc, ncol=legend_ncol)
    return figure


def draw_displacement_waves(data: AnalysisData, n_max: float):
    """Displacements x_n against n at several times, each curve labelled with its
    time at the foot of its wave front (figures 8, 10 and 11)."""
    figure, ax = new_figure()
    names = series_names(data, "data")
    for name in names:
        draw_series(ax, data, name, linestyle="-")
    for name in names:
        x = data.arrays[f"series/{name}/x"]
        y = data.arrays[f"series/{name}/y"]
        foot = x[y > 1e-3].max()
        ax.annotate(data.attrs[f"series/{name}"]["label"].replace("t = ", "t="),
                    xy=(foot, 0.0), xytext=(1, 2), textcoords="offset points",
                    ha="left", va="bottom", fontsize=6, rotation=90)
    ax.set_xlabel(r"$n$")
    ax.set_ylabel(r"$x_n$")
    ax.set_xlim(0.0, n_max)
    ax.set_ylim(0.0, None)
    return figure
