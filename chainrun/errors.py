"""The exceptions chainrun raises at its edges.

Library code raises these; the command line turns them into one-line messages and a
non-zero exit status, never a traceback.
"""


class ChainrunError(Exception):
    """Base class of every error chainrun reports to a user."""


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


class SolverError(ChainrunError):
    """A run that ended in a named failure (see ``chainrun.solver.Outcome``)."""
