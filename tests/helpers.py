"""What several test files share: running the real ``chainrun simulate`` on a config."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner

from chainrun.cli import main


def simulate_text(folder: Path, text: str, name: str = "experiment") -> Path:
    """Write the experiment ``text`` into ``folder`` as ``<name>.toml``, run ``chainrun
    simulate`` on it into ``folder/out`` and return that output folder."""
    config = folder / f"{name}.toml"
    config.write_text(text)
    out = folder / "out"
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out
