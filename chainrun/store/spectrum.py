"""Spectrum files: the linear spectrum of one run's line at rest.

A *spectrum file* holds ``chainrun.analysis.spectrum``'s Dataset written as a flat
netCDF-4 file, every coordinate a dimension scale, so ``xarray.open_dataset(path,
engine="h5netcdf")`` reads it as well as ``read_spectrum``. The tree is drawn in
``docs/schema.md``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

import chainrun
from chainrun import atomic
from chainrun.errors import StoreError
from chainrun.store import _h5
from chainrun.store._h5 import SPECTRUM_FORMAT

#: Attributes h5py keeps for dimension scales, not the Dataset's.
_SCALE_ATTRS = ("CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST", "_Netcdf4Dimid")


def _attribute(path: Path, where: str, value: Any) -> Any:
    """An attribute value HDF5 holds as it is: a str, int, float or bool scalar."""
    if isinstance(value, (np.generic,)):
        value = value.item()
    if not isinstance(value, (str, bool, int, float)):
        raise StoreError(f"{path}: attribute {where} is not a str, int, float or bool")
    return value


def write_spectrum(path, ds) -> None:
    """Write the spectrum Dataset ``ds`` (``chainrun.analysis.spectrum.line_spectrum``)
    atomically (a temporary name, then a rename).

    Each coordinate becomes a dimension scale and each data variable a dataset with its
    dimensions attached; the Dataset's attributes are the file's root attributes, beside
    ``format``, ``format_version``, ``created`` and the creator's name and version.
    """
    path = Path(path)
    temp = atomic.temp_name(path)
    h5 = _h5.create(path, temp, "spectrum file")
    try:
        _h5.stamp(h5, SPECTRUM_FORMAT)
        h5.attrs["creator_name"] = "chainrun"
        h5.attrs["creator_version"] = chainrun.__version__
        for key, value in ds.attrs.items():
            h5.attrs[key] = _attribute(path, f"@{key}", value)
        scales = {}
        for name in ds.dims:
            coord = ds[name]
            scales[name] = _h5.scale(h5, name, coord.values, coord.attrs.get("long_name", name))
            for key, value in coord.attrs.items():
                scales[name].attrs[key] = _attribute(path, f"{name}@{key}", value)
        for name, var in ds.data_vars.items():
            dset = _h5.array(h5, str(name), var.values, [scales[d] for d in var.dims],
                          var.attrs.get("long_name", str(name)))
            for key, value in var.attrs.items():
                dset.attrs[key] = _attribute(path, f"{name}@{key}", value)
        _h5.commit(h5, temp, path)
    except BaseException:
        _h5.discard(h5, temp)
        raise


def read_spectrum(path):
    """The spectrum file at ``path`` as an ``xarray.Dataset``, after checking its format.

    Raises
    ------
    StoreError
        If the file is missing, not a chainrun spectrum file, of another format version,
        or damaged.
    """
    import xarray as xr

    name = os.fspath(path)
    with _h5.open_read(name) as h5:
        _h5.check_open(h5, name, SPECTRUM_FORMAT)
        try:
            coords, data = {}, {}
            for key, item in h5.items():
                attrs = {k: _h5.py(v) for k, v in item.attrs.items() if k not in _SCALE_ATTRS}
                if item.is_scale:
                    coords[key] = (key, item[()], attrs)
                else:
                    dims = tuple(item.dims[i][0].name.lstrip("/") for i in range(item.ndim))
                    data[key] = (dims, item[()], attrs)
            attrs = {k: _h5.py(v) for k, v in h5.attrs.items()}
        except (KeyError, OSError, RuntimeError, IndexError) as exc:
            raise StoreError(f"{name}: damaged spectrum file ({_h5.h5_reason(exc)})") from None
    return xr.Dataset(data, coords=coords, attrs=attrs)
