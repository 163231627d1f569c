"""The bench's sections: each a module with ``run(ctx) -> RESULT``.

A section measures one thing (``benchmarks/README.md``, "What is measured") within the
bounds of ``ctx.mode`` and returns a typed result (a dataclass, ``RESULT`` of its
module) that renders itself: ``lines()``, its part of the report, and ``to_json()``,
what the results file keeps, from which ``RESULT.from_json`` gives it back.
``benchmarks.run`` runs the sections asked for, in the order of ``SECTIONS``.
"""

from __future__ import annotations

import importlib
from dataclasses import asdict, fields

from benchmarks.harness import jsonable

#: The sections, in the order they run, and the module of each.
SECTIONS = {
    "compile": "benchmarks.sections.compilation",
    "peers": "benchmarks.sections.peers",
    "scaling": "benchmarks.sections.scaling",
    "targets": "benchmarks.sections.targets",
    "k80": "benchmarks.sections.k80",
    "steered": "benchmarks.sections.steered",
    "memory": "benchmarks.sections.memory",
    "general": "benchmarks.sections.general",
    "previous": "benchmarks.sections.previous",
    "lammps": "benchmarks.against_lammps",
}


def module(name: str):
    """The module of the section ``name``."""
    return importlib.import_module(SECTIONS[name])


class Result:
    """What a section measured: its fields, its lines of the report, its JSON."""

    def lines(self) -> list[str]:
        raise NotImplementedError

    def to_json(self) -> dict:
        return jsonable(asdict(self))

    @classmethod
    def from_json(cls, data: dict):
        return cls(**{f.name: data[f.name] for f in fields(cls) if f.name in data})
