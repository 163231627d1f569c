"""What every chainrun command shares: exit codes and one-line errors."""

from __future__ import annotations

import sys

import click

EXIT_FAILED_RUNS = 1
EXIT_BAD_INPUT = 2


def fail(message: str, code: int = EXIT_BAD_INPUT):
    """Print ``chainrun: error: message`` on stderr and exit with ``code``."""
    click.echo(f"chainrun: error: {message}", err=True)
    sys.exit(code)
