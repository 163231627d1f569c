"""What every chainrun command shares: exit codes and one-line errors."""

from __future__ import annotations

import sys

import click

from chainrun import interrupt

EXIT_FAILED_RUNS = 1
EXIT_BAD_INPUT = 2
#: interrupted (SIGINT, or SIGTERM and SIGHUP, which the command group makes the same)
EXIT_INTERRUPTED = 130


def fail(message: str, code: int = EXIT_BAD_INPUT):
    """Print ``chainrun: error: message`` on stderr and exit with ``code``."""
    click.echo(f"chainrun: error: {message}", err=True)
    sys.exit(code)


class Commands(click.Group):
    """The command group: a command interrupted anywhere, even before it has begun its
    work (reading its inputs, importing the solver), says so in one line and exits 130,
    as one interrupted inside its work does (click would print "Aborted!")."""

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt:
            interrupt.clear()
            fail("interrupted", EXIT_INTERRUPTED)
