"""Fixtures the regression tests share."""

from __future__ import annotations

import pytest

from helpers import build


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """``built(name)``: the analysis of a fast artefact (``helpers.FAST``), built once per
    test process; ``built.results`` is its results folder."""
    results = tmp_path_factory.mktemp("results")
    cache = {}

    def get(name: str):
        if name not in cache:
            cache[name] = build(name, results)
        return cache[name]

    get.results = results
    return get
