"""chainrun from Python: run an experiment, open a run file or a sweep, and measure
them, as xarray Datasets (``runs``: ``simulate``, ``open_run``, ``open_sweep``;
``measures``: ``pulses``, ``transmission``, ``spectrum``)."""

from chainrun.api.measures import pulses, spectrum, transmission
from chainrun.api.runs import open_run, open_sweep, simulate

__all__ = ["open_run", "open_sweep", "pulses", "simulate", "spectrum", "transmission"]
