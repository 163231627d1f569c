"""Reading an experiment file's text: TOML or YAML, within limits of size, nesting and
expanded aliases that keep any text quick to refuse, with syntax errors reported by
line and column; then ``chainrun.config.experiment.validate``.
"""

from __future__ import annotations

import functools
import os
import re
import sys
import tomllib

from chainrun.config.experiment import Experiment, validate
from chainrun.errors import ConfigError, one_line, show_value

#: File extensions and the format each one is read as.
FORMATS = {".toml": "toml", ".yaml": "yaml", ".yml": "yaml"}


def _syntax_line(exc: Exception, text: str, fmt: str) -> str:
    """A parser error as ``line L: message``."""
    if fmt == "toml":
        message = str(exc)
        found = re.search(r"\s*\(at line (\d+), column (\d+)\)", message)
        if found:
            rest = message[: found.start()] + message[found.end() :]
            return f"line {found.group(1)}: {rest.strip()} (column {found.group(2)})"
        found = re.search(r"\s*\(at end of document\)", message)
        if found:
            rest = message[: found.start()] + message[found.end() :]
            return f"line {max(1, len(text.splitlines()))}: {rest.strip()} (at end of document)"
        return " ".join(message.split())
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or " ".join(str(exc).split())
    context = getattr(exc, "context", None)
    reason = f"{problem} ({context})" if context else problem
    if mark is None:
        return reason
    if text[mark.index:mark.index + 1] == "\t":  # PyYAML's own text names no rule
        indent = text[text.rfind("\n", 0, mark.index) + 1:mark.index].strip(" \t") == ""
        reason = ("a tab: YAML does not allow tabs for indentation; indent with spaces"
                  if indent else "a tab where YAML allows only spaces")
    return f"line {mark.line + 1}: {reason} (column {mark.column + 1})"


#: Most characters an experiment file may have. PyYAML reads about 150 kB a second,
#: tomllib about 1.6 MB: a file at the limit takes a minute and five seconds. Long
#: lists belong in a data file (``{file = "masses.npy"}``).
MAX_TEXT = 8 * 2**20
#: Deepest nesting of YAML flow collections read (PyYAML takes time quadratic in it).
MAX_DEPTH = 100
#: Most values (scalars, lists and tables) a YAML document may hold, counting an
#: alias (``*a``) as the whole value it stands for at every use, merge keys (``<<``)
#: included: ten lines of nested aliases stand for billions of values, which every
#: later stage would walk.
MAX_VALUES = 1_000_000


def _too_deep(text: str) -> int:
    """The line where ``[`` and ``{`` first nest more than ``MAX_DEPTH`` deep, else 0.

    Brackets are counted wherever they are, quoted or not: an overestimate that only
    a file with a hundred unclosed brackets in its strings could trip.
    """
    if text.count("[") + text.count("{") <= MAX_DEPTH:
        return 0
    depth = 0
    line = 1
    for char in text:
        if char in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                return line
        elif char in "]}":
            depth = max(0, depth - 1)
        elif char == "\n":
            line += 1
    return 0


def _value_error(exc: Exception) -> str:
    text = " ".join(str(exc).split())
    if "integer string conversion" in text:
        return f"an integer of more than {sys.get_int_max_str_digits()} digits"
    return text or type(exc).__name__


def _expanded_size(root, fail) -> None:
    """Check the size of a composed YAML document with its aliases expanded.

    Walks the node graph once (an alias is the node it names, shared), counting each
    node's values with every use of a shared node; calls ``fail(node, reason)`` at the
    first node that holds more than ``MAX_VALUES``, or that contains itself.
    """
    size: dict[int, int] = {}
    entered: set[int] = set()
    stack = [(root, False)]
    while stack:
        node, leaving = stack.pop()
        value = node.value if isinstance(node.value, list) else []
        children = [c for item in value for c in (item if isinstance(item, tuple) else (item,))]
        if leaving:
            total = 1 + sum(size[id(c)] for c in children)
            if total > MAX_VALUES:
                fail(node, f"more than {MAX_VALUES} values, counting each alias as the "
                           "whole value it stands for")
            size[id(node)] = total
            continue
        if id(node) in size:
            continue
        entered.add(id(node))
        stack.append((node, True))
        for child in children:
            if id(child) in entered and id(child) not in size:
                fail(child, "an alias inside the value it names: a value cannot contain "
                            "itself")
            if id(child) not in size:
                stack.append((child, False))


@functools.cache
def _yaml():
    """PyYAML and ``_YamlLoader``, imported and built on the first YAML file read.

    ``_YamlLoader`` is ``yaml.SafeLoader`` that refuses a document holding more than
    ``MAX_VALUES`` values once its aliases are expanded, or a value that contains
    itself, before it builds anything (``_expanded_size``); and whose failures to
    convert a value name their place. PyYAML converts ``2001-13-45`` (a date),
    ``!!int x`` or an integer of 5000 digits with plain ``int()`` or ``datetime``;
    their ``ValueError`` carries no line.
    """
    import yaml

    class _YamlLoader(yaml.SafeLoader):
        def construct_document(self, node):
            def fail(at, reason):
                raise yaml.constructor.ConstructorError(None, None, reason, at.start_mark)

            _expanded_size(node, fail)
            return super().construct_document(node)

        def construct_object(self, node, deep=False):
            try:
                return super().construct_object(node, deep=deep)
            except (ValueError, TypeError, OverflowError) as exc:
                value = f"{show_value(node.value)}: " if isinstance(node.value, str) else ""
                raise yaml.constructor.ConstructorError(
                    None, None, f"cannot read {value}{_value_error(exc)}", node.start_mark
                ) from None

    return yaml, _YamlLoader


def parse_experiment(text: str, fmt: str, source: str = "<string>", *,
                     to_run: bool = True) -> Experiment:
    """The experiment described by ``text``.

    Parameters
    ----------
    text : str
        The whole experiment file.
    fmt : {"toml", "yaml"}
        Its format (``"yml"`` is taken as ``"yaml"``).
    source : str
        Where the text came from, for error messages.
    to_run : bool
        False for an experiment whose lines are only analysed at rest (``chainrun
        spectrum``): a line without a terminal state then needs no ``solver.t_end``
        (pass the same to ``Experiment.runs``).

    Returns
    -------
    Experiment
        Validated, with ``source_text == text``.

    Raises
    ------
    ConfigError
        With every problem found, one line each.
    """
    fmt = {"yml": "yaml"}.get(fmt, fmt)
    if fmt not in ("toml", "yaml"):
        raise ConfigError(source, [f"unknown format {fmt!r} (expected 'toml' or 'yaml')"])
    if len(text) > MAX_TEXT:
        raise ConfigError(source, [f"more than {MAX_TEXT} characters, too long for an "
                                   "experiment file (give long lists as data files, "
                                   "{file = ...})"])
    if fmt == "toml":
        load, syntax_error = tomllib.loads, tomllib.TOMLDecodeError
    else:
        deep = _too_deep(text)
        if deep:
            raise ConfigError(source, [f"line {deep}: nested more than {MAX_DEPTH} levels deep"])
        yaml, loader = _yaml()
        load, syntax_error = functools.partial(yaml.load, Loader=loader), yaml.YAMLError
    try:
        data = load(text)
    except syntax_error as exc:
        raise ConfigError(source, [one_line(_syntax_line(exc, text, fmt))]) from None
    except RecursionError:
        raise ConfigError(source, ["nested too deeply to read"]) from None
    except ValueError as exc:  # tomllib converting a value, e.g. an integer of 5000 digits
        raise ConfigError(source, [one_line(f"cannot read a value ({_value_error(exc)})")]) from None
    try:
        experiment = validate(data, source, to_run)
    except RecursionError:  # YAML aliases can nest without end
        raise ConfigError(source, ["nested too deeply to check"]) from None
    experiment._source_text = text  # private attributes are not frozen
    experiment._source = source
    return experiment


def load_experiment(path: str | os.PathLike[str], *, to_run: bool = True) -> Experiment:
    """Read and validate the experiment file at ``path`` (``.toml``, ``.yaml`` or ``.yml``);
    ``to_run`` as for ``parse_experiment``.

    Raises
    ------
    ConfigError
        If the file is missing, unreadable, of an unknown type, or invalid; the error
        lists every problem found.
    """
    source = os.fspath(path)
    suffix = os.path.splitext(source)[1].lower()
    if suffix not in FORMATS:
        what = (" (a run file or analysis file: an experiment file is expected here)"
                if suffix == ".h5" else "")
        raise ConfigError(
            source, [f"unknown file type {suffix or '(none)'!r}{what} (expected .toml, "
                     ".yaml or .yml)"]
        )
    try:
        with open(source, encoding="utf-8-sig") as handle:  # a BOM (Windows editors) is dropped
            text = handle.read(MAX_TEXT + 1)  # parse_experiment refuses a longer one
    except FileNotFoundError:
        raise ConfigError(source, ["no such file"]) from None
    except IsADirectoryError:
        raise ConfigError(source, ["is a folder, not a file"]) from None
    except UnicodeDecodeError as exc:
        raise ConfigError(source, [f"not UTF-8 text (byte {exc.start})"]) from None
    except OSError as exc:
        raise ConfigError(source, [f"cannot read: {exc.strerror}"]) from None
    return parse_experiment(text, FORMATS[suffix], source, to_run=to_run)
