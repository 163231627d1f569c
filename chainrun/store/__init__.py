"""The files chainrun writes: the one part of chainrun that reads and writes HDF5.

This package owns the on-disk formats, each drawn in ``docs/schema.md`` with its
version:

- run files (``run_writer``: ``RunWriter``; ``run_reader``: ``read_run``,
  ``RunData``, ``run_config_hash``): one run each, in H5MD;
- index files (``index``): the table of an experiment's runs, linking to each;
- analysis files (``analysis``): what ``chainrun analyze`` derives for an artefact;
- spectrum files (``spectrum``): the linear spectrum of a run's line;

and ``_h5`` what they share: the format stamps and ``check_format``, atomic creation
(a temporary name, then a rename: ``chainrun.atomic``), dimension scales, and chunked,
compressed datasets. The store computes nothing about a line: what it writes comes
from its caller.
"""

from __future__ import annotations

from chainrun.store._h5 import (
    ANALYSIS_FORMAT,
    ANALYSIS_FORMAT_VERSION,
    BALL_CHUNK,
    INDEX_FORMAT,
    INDEX_FORMAT_VERSION,
    RUN_FORMAT,
    RUN_FORMAT_VERSION,
    SPECTRUM_FORMAT,
    SPECTRUM_FORMAT_VERSION,
    check_format,
)
from chainrun.store.analysis import (
    ANALYSIS_INPUT_COLUMNS,
    AnalysisData,
    file_sha256,
    read_analysis,
    write_analysis,
)
from chainrun.store.index import INDEX_COLUMNS, read_index, write_index
from chainrun.store.run_reader import RunData, Snapshots, read_run, run_config_hash
from chainrun.store.run_writer import H5MD_VERSION, OBSERVABLES, RunWriter
from chainrun.store.spectrum import read_spectrum, write_spectrum

__all__ = [
    "ANALYSIS_FORMAT",
    "ANALYSIS_FORMAT_VERSION",
    "ANALYSIS_INPUT_COLUMNS",
    "AnalysisData",
    "BALL_CHUNK",
    "H5MD_VERSION",
    "INDEX_COLUMNS",
    "INDEX_FORMAT",
    "INDEX_FORMAT_VERSION",
    "OBSERVABLES",
    "RUN_FORMAT",
    "RUN_FORMAT_VERSION",
    "RunData",
    "RunWriter",
    "SPECTRUM_FORMAT",
    "SPECTRUM_FORMAT_VERSION",
    "Snapshots",
    "check_format",
    "file_sha256",
    "read_analysis",
    "read_index",
    "read_run",
    "run_config_hash",
    "write_analysis",
    "write_index",
    "write_spectrum",
]
