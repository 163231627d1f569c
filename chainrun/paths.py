"""Where chainrun puts what it writes: the one home of every output path.

::

    results/                            RESULTS, the results folder by default
      <name>/                           `chainrun simulate`'s folder for an experiment
        <run_id>.h5                     a run file (``run.h5`` without a sweep)
        index.h5                        the experiment's index file (INDEX_NAME)
        spectrum/                       `chainrun spectrum`'s folder
      runs/<experiment>/                `make figures`' run folders (``runs/gallery/<name>``)
      analysis/<artefact>.h5            the analysis files (`chainrun analyze`)

The experiment of ``configs/fig05.toml`` is simulated by ``make figures`` into
``results/runs/fig05/`` (``run_dir``), where ``chainrun analyze`` reads it; the
command alone writes ``results/<name>/`` (``outdir``). This module imports nothing:
the Makefile's rules are listed from it at once.
"""

from __future__ import annotations

from pathlib import Path

#: The results folder by default, relative to the working folder.
RESULTS = Path("results")
#: The index file of an output folder.
INDEX_NAME = "index.h5"


def outdir(name: str, results=RESULTS) -> Path:
    """The output folder of ``chainrun simulate`` for the experiment called ``name``."""
    return Path(results) / name


def spectrum_dir(name: str, results=RESULTS) -> Path:
    """The output folder of ``chainrun spectrum`` for the experiment called ``name``."""
    return outdir(name, results) / "spectrum"


def run_file(folder, spec) -> Path:
    """The run file of ``spec`` (anything with a ``run_id``) in an output folder."""
    return Path(folder) / f"{spec.run_id}.h5"


def index_file(folder) -> Path:
    """The index file of an output folder."""
    return Path(folder) / INDEX_NAME


def run_dir(experiment: str, results=RESULTS) -> Path:
    """The folder of an experiment's run files in ``make figures``' results:
    ``experiment`` is its config's path under ``configs/`` without the suffix."""
    return Path(results) / "runs" / experiment


def index_path(experiment: str, results=RESULTS) -> Path:
    """The index file of an experiment's runs in ``make figures``' results."""
    return index_file(run_dir(experiment, results))


def analysis_path(name: str, results=RESULTS) -> Path:
    """The analysis file of an artefact."""
    return Path(results) / "analysis" / f"{name}.h5"
