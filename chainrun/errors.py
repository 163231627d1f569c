"""The exceptions chainrun raises at its edges, and how a user's value is shown in them.

Library code raises these; the command line turns them into one-line messages and a
non-zero exit status, never a traceback.
"""

from __future__ import annotations

import difflib
import math
import reprlib
from typing import Any

_REPR = reprlib.Repr()  # bounded: YAML aliases can build huge or cyclic structures
_REPR.maxlevel, _REPR.maxstring, _REPR.maxother = 3, 60, 60
_REPR.maxlist = _REPR.maxtuple = _REPR.maxset = _REPR.maxdict = 8

#: Characters that end a line for ``str.splitlines``, and the other control characters.
_BREAKS = {c: repr(chr(c))[1:-1] for c in [*range(0x20), *range(0x7F, 0xA0), 0x2028, 0x2029]}


def one_line(text: str) -> str:
    """``text`` with line breaks and control characters written as escapes."""
    return text.translate(_BREAKS)


def suggest(word: str, choices) -> str:
    """`` (did you mean 'x'?)`` for the choice closest to a misspelled ``word``, else
    ""."""
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def show_value(value: Any) -> str:
    """A short one-line rendering of a user's value for a message.

    Bounded in time and length whatever the value: containers are shown a few
    levels and items deep (a YAML alias can make a list of billions of items out of a
    few lines, each shared), and integers too long to print by their size.
    """
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 190:
        digits = int((value.bit_length() - 1) * math.log10(2)) + 1
        text = f"{'-' if value < 0 else ''}<an integer of about {digits} digits>"
    elif isinstance(value, (str, bytes, int, float, type(None))):
        text = repr(value)
    else:
        try:
            text = _REPR.repr(value)
        except (RecursionError, ValueError):
            text = f"<{type(value).__name__}>"
    text = one_line(text)
    return text if len(text) <= 60 else text[:57] + "..."


class ChainrunError(Exception):
    """Base class of every error chainrun reports to a user."""


class ChainrunWarning(UserWarning):
    """A valid input that is probably not what was meant (a length in millimetres typed
    as metres), or a run whose numbers may not hold (its energy balance far off)."""


class ConfigError(ChainrunError):
    """An experiment file that cannot be used.

    Parameters
    ----------
    source : str
        The file (or other source) the problems were found in.
    problems : list of str
        One line per problem, each naming the key and the reason.
    """

    def __init__(self, source: str, problems: list[str]):
        self.source = source
        self.problems = list(problems)
        super().__init__(f"{source}: " + "; ".join(self.problems))


class StoreError(ChainrunError):
    """A run or analysis file that cannot be written or read as chainrun's format."""
