"""``chainrun analyze``: turn run files into analysis files, one per artefact of the paper."""

from __future__ import annotations

from pathlib import Path

import click

from chainrun.cli.common import fail
from chainrun.errors import ChainrunError
from chainrun.paths import RESULTS


@click.command()
@click.argument("names", nargs=-1)
@click.option("--all", "all_", is_flag=True, help="Every artefact, in the registry's order.")
@click.option("-r", "--results", type=click.Path(file_okay=False, path_type=Path),
              default=RESULTS, show_default=True,
              help="Results folder: runs are read from RESULTS/runs/<experiment>/, analysis "
                   "files written to RESULTS/analysis/<name>.h5.")
@click.option("--check", is_flag=True,
              help="Also analyse the check runs in RESULTS/check/runs/ (chainrun simulate "
                   "--check-outdir) into RESULTS/check/analysis/ and store each value's "
                   "spread: how far it moves when the runs' tolerance is cut tenfold.")
def analyze(names: tuple[str, ...], all_: bool, results: Path, check: bool):
    """Derive the quantities of the paper's artefacts NAMES from their run files.

    Each artefact (a figure, a table, or a set of printed numbers; `chainrun plot
    --list` shows them) reads the runs of its experiments, simulated beforehand with
    `chainrun simulate configs/<experiment>.toml -o RESULTS/runs/<experiment>`, and
    the analysis files it needs. It writes RESULTS/analysis/<name>.h5: the arrays its
    figure draws, the named values the comparison table uses, the settings that
    produced them and the sha256 of every file read.

    With --check, the same experiments simulated again at a tenth of their tolerance
    (`chainrun simulate configs/<experiment>.toml -o RESULTS/runs/<experiment>
    --check-outdir RESULTS/check/runs/<experiment>`) are analysed the same way, and
    each value is stored with its spread, |value - check value|; the comparison
    tables print no digit beyond it. `make figures` does this.

    \b
    Examples:
      chainrun analyze fig05
      chainrun analyze sec5a fig10 fig11
      chainrun analyze --all              # every artefact, in order
      chainrun analyze --all --check      # with spreads, as `make figures` does
    """
    from chainrun import artefacts
    from chainrun.analysis import analyze as analyze_artefact

    if all_:
        names = tuple(a.name for a in artefacts.ARTEFACTS)
    if not names:
        fail("name at least one artefact, or give --all (see `chainrun plot --list`)")
    known = {a.name for a in artefacts.ARTEFACTS}
    for name in names:
        if name not in known and Path(name).exists():
            fail(f"{name}: analyze derives the paper's artefacts (chainrun plot --list); a "
                 f"run file or output folder of your own is read by `chainrun info {name}` "
                 f"(its summary and pulses), drawn by `chainrun plot {name}`, and measured "
                 f"from Python by chainrun.pulses and chainrun.transmission")
        try:
            path = analyze_artefact(name, results=results, check=check)
        except ChainrunError as exc:
            fail(str(exc))
        click.echo(f"{name}: {path}")
