"""The package's imports run one way: config -> solver -> store -> analysis -> plotting.

Each part may import only the parts below it (docs/design.md: data flows one way, one home
per stage); the command line sits on top. Read from the source, so a lazy import
inside a function counts as much as one at the top of a file.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: rank of each part: a part imports only parts of lower rank (or itself)
RANK = {
    "chainrun.errors": 0, "chainrun.atomic": 0, "chainrun._gc": 0,
    "chainrun.materials": 0,  # data only
    "chainrun.units": 0,
    "chainrun.paths": 0,  # names of folders and files only
    "chainrun.interrupt": 0,  # the signals' handler and its flag
    "chainrun.solver": 1, "chainrun.generators": 1, "chainrun.check": 1,
    "chainrun.config": 2, "chainrun.limits": 2, "chainrun.artefacts": 2,
    "chainrun.store": 3,
    "chainrun.runner": 4, "chainrun.analysis": 4,
    "chainrun.plotting": 5,
    "chainrun.cli": 6, "chainrun.api": 6,
    "chainrun": 7, "chainrun.__main__": 7,
}
#: outside libraries a part must not use (the solver never touches files, the
#: analysis draws nothing, only the store touches HDF5)
FORBIDDEN = {
    "chainrun.solver": {"h5py", "click", "matplotlib", "pydantic", "yaml", "dask"},
    "chainrun.config": {"h5py", "click", "matplotlib"},
    "chainrun.generators": {"h5py", "click", "matplotlib", "pydantic", "yaml"},
    "chainrun.materials": {"numpy", "h5py", "click", "matplotlib", "pydantic"},
    "chainrun.analysis": {"click", "matplotlib", "h5py"},
    "chainrun.plotting": {"click", "h5py", "scipy"},
    "chainrun.runner": {"click", "matplotlib"},
    "chainrun.paths": {"numpy", "h5py", "click", "matplotlib", "pydantic"},
}
#: the modules of the store, in layers: each imports only those of lower layers (the
#: shared HDF5 helpers under every kind of file; the run files' reader on their writer's
#: list of observables); the store computes nothing of a line's physics
STORE_LAYERS = {
    "chainrun.store._h5": 0,
    "chainrun.store.run_writer": 1, "chainrun.store.index": 1,
    "chainrun.store.analysis": 1, "chainrun.store.spectrum": 1,
    "chainrun.store.run_reader": 2,
    "chainrun.store": 3,
}
#: arrows the ranks allow but the design does not: plotting draws what is stored and
#: computes nothing (no solver, no analysis, no runs)
EXTRA = {("chainrun.plotting", "chainrun.runner"), ("chainrun.plotting", "chainrun.analysis"),
         ("chainrun.plotting", "chainrun.solver")}


def _part(module: str) -> str | None:
    """The part ``module`` belongs to: itself or its nearest package named in RANK.

    The package ``chainrun`` is a part of its own (its ``__init__``), not a home for
    every module under it: a module neither named in RANK nor inside a package named
    there belongs to no part (None).
    """
    while module not in RANK:
        module = module.rpartition(".")[0]
        if module in ("", "chainrun"):
            return None
    return module


def _target_part(target: str) -> str | None:
    """The part an imported name belongs to; ``chainrun.X``, where X is no module
    of its own, is a name from the package's ``__init__``."""
    part = _part(target)
    if part is None and target.rpartition(".")[0] == "chainrun" and target not in _modules():
        return "chainrun"
    return part


def _modules() -> list[str]:
    """Every module of the package, by its dotted name (a package by its own)."""
    names = []
    for path in sorted((ROOT / "chainrun").rglob("*.py")):
        rel = path.relative_to(ROOT).with_suffix("")
        names.append(".".join(rel.parts[:-1] if rel.name == "__init__" else rel.parts))
    return names


def _imports():
    for name in _modules():
        parts = name.split(".")
        path = ROOT.joinpath(*parts).with_suffix(".py")
        if not path.exists():
            path = ROOT.joinpath(*parts, "__init__.py")
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                targets = [f"{node.module}.{a.name}" for a in node.names]
            else:
                continue
            for target in targets:
                yield name, target


def test_every_module_belongs_to_a_part():
    modules = _modules()
    assert "chainrun.units" in modules and "chainrun.solver._loop" in modules
    homeless = [name for name in modules if _part(name) is None]
    assert not homeless, f"modules in no part of RANK: {homeless}"


def test_the_part_of_a_module_is_its_own_or_its_package():
    assert _part("chainrun") == "chainrun"
    assert _part("chainrun.units") == "chainrun.units"
    assert _part("chainrun.solver._loop") == "chainrun.solver"
    assert _part("chainrun.newmodule") is None
    assert _part("chainrun.newpackage.module") is None


def test_imports_name_modules_of_a_part():
    unknown = {(name, target) for name, target in _imports()
               if target.split(".")[0] == "chainrun" and _target_part(target) is None}
    assert not unknown, sorted(unknown)


def test_imports_point_down_the_pipeline():
    wrong = set()
    for name, target in _imports():
        src = _part(name)
        if src is None:
            continue  # a module in no part: test_every_module_belongs_to_a_part
        if target.split(".")[0] != "chainrun":
            if target.split(".")[0] in FORBIDDEN.get(src, ()):
                wrong.add((name, target))
            continue
        if target in ("chainrun", "chainrun.__version__"):
            continue  # the version, for the files' provenance
        dst = _target_part(target)
        if dst != src and (RANK[dst] >= RANK[src] or (src, dst) in EXTRA):
            wrong.add((name, target))
    assert not wrong, sorted(wrong)


def test_the_store_is_layered_and_writes_no_physics_of_its_own():
    assert set(STORE_LAYERS) == {m for m in _modules() if _part(m) == "chainrun.store"}
    wrong = set()
    for name, target in _imports():
        if name not in STORE_LAYERS:
            continue
        # what a file holds comes from its writer's caller; only RunData derives
        # energies from what it read
        if target.startswith("chainrun.solver.physics") and name != "chainrun.store.run_reader":
            wrong.add((name, target))
        inner = target if target in STORE_LAYERS else target.rpartition(".")[0]
        if inner in STORE_LAYERS and inner != name and STORE_LAYERS[inner] >= STORE_LAYERS[name]:
            wrong.add((name, target))
    assert not wrong, sorted(wrong)


#: the modules of chainrun.config, each importing only those before it: problems are
#: worded, drives and tables checked, lines built, sweeps expanded, runs specified and
#: their doubtful values found, the whole file validated, its text read (and the
#: package re-exports the public names)
CONFIG_ORDER = ["problems", "drives", "schema", "line", "sweeps", "run", "doubts",
                "experiment", "text"]


def test_the_config_package_imports_one_way():
    modules = [name for name in _modules() if name.startswith("chainrun.config.")]
    assert sorted(modules) == sorted(f"chainrun.config.{m}" for m in CONFIG_ORDER)
    wrong = set()
    for name, target in _imports():
        if not name.startswith("chainrun.config.") or not target.startswith("chainrun.config."):
            continue
        src, dst = name.split(".")[2], target.split(".")[2]
        if CONFIG_ORDER.index(dst) >= CONFIG_ORDER.index(src):
            wrong.add((name, target))
    assert not wrong, sorted(wrong)


def test_line_building_stays_out_of_the_kernels():
    from chainrun.solver._jit import kernel_sources

    assert "build.py" not in {path.name for path in kernel_sources()}
    importers = {name for name, target in _imports()
                 if target.startswith("chainrun.solver.build")}
    assert all(not name.startswith("chainrun.solver") for name in importers), importers


#: the solver's modules in layers (docs/design.md, "The solver's layers"): each imports
#: only modules of lower layers. The kernels (0-9, ``_loop`` on top) are compiled into
#: one library and import nothing of the Python side but ``drive``'s constants; the
#: Python side describes a line (``model``, ``build``), its formulas (``physics``,
#: ``restitution``) and results (``result``), and drives the kernels (``_driver``) for
#: the package's one entry point (``chainrun.solver``: ``simulate``)
SOLVER_LAYERS = {
    "_jit": 0,
    "_state": 1, "drive": 1,
    "_forces": 2, "_compression": 2, "_drive": 2, "model": 2, "_codegen": 2,
    "_generated": 3, "physics": 3, "restitution": 3, "result": 3,
    "_steppers": 4, "_pair_damped": 4, "build": 4, "_setup": 4,
    "_events": 5, "_pairs": 5, "_projection": 5,
    "_heap": 6, "_output": 6,
    "_clusters": 7, "_stepping": 7,
    "_binary": 8, "_settle": 8,
    "_loop": 9,
    "_driver": 10,
    "": 11,  # the package itself
}
#: the Python side: no kernel is compiled from these
SOLVER_PYTHON_SIDE = {"model", "physics", "restitution", "result", "build", "_codegen",
                      "_setup", "_driver", ""}


def _solver_module(dotted: str) -> str | None:
    """The solver module a dotted name lives in ("" for the package's own names)."""
    if dotted != "chainrun.solver" and not dotted.startswith("chainrun.solver."):
        return None
    rest = dotted.removeprefix("chainrun.solver").removeprefix(".").split(".")[0]
    return rest if rest in SOLVER_LAYERS else ""


def test_the_solver_is_layered():
    modules = {_solver_module(m) for m in _modules() if _solver_module(m) is not None}
    assert modules == set(SOLVER_LAYERS)
    wrong = set()
    for name, target in _imports():
        src, dst = _solver_module(name), _solver_module(target)
        if src is None or dst is None or src == dst:
            continue
        if SOLVER_LAYERS[dst] >= SOLVER_LAYERS[src]:
            wrong.add((name, target))
    assert not wrong, sorted(wrong)


def test_the_kernels_are_compiled_from_the_kernel_modules_alone():
    from chainrun.solver._jit import kernel_sources

    compiled = {path.stem for path in kernel_sources()}
    assert "_loop" in compiled and not compiled & SOLVER_PYTHON_SIDE
    # every module below _loop that is not on the Python side is compiled into it
    assert compiled == {m for m, layer in SOLVER_LAYERS.items()
                        if layer <= SOLVER_LAYERS["_loop"]} - SOLVER_PYTHON_SIDE
