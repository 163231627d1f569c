"""A previous version of chainrun beside this one: which revision, and its checkout.

The bench's section ``previous`` and ``benchmarks.same_answers`` run another revision
of chainrun in the same run as this one. This module owns choosing that revision
(``resolve_against``) and checking it out into a temporary git worktree that is removed
at the end, also on an error, an interrupt or a TERM signal (``checkout``).
"""

from __future__ import annotations

import contextlib
import os
import subprocess
from pathlib import Path

from benchmarks.harness import ROOT, log

#: The environment variable naming the previous section's revision (as --against does).
AGAINST_ENV = "CHAINRUN_BENCH_AGAINST"
#: The default previous version is the solver before the latest change under this path.
SOLVER_PATH = "chainrun/solver"


def git(root: Path, *args: str) -> str:
    """``git -C root args``; its output, stripped. RuntimeError (with git's message)
    when it fails."""
    r = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)}: {(r.stderr or r.stdout).strip()}")
    return r.stdout.strip()


def resolve_against(rev: str | None, root: Path = ROOT, environ=None) -> dict:
    """The revision the previous section compares with, as a commit.

    ``rev`` (``--against``), else ``$CHAINRUN_BENCH_AGAINST``, else the solver as it
    was before its latest change: with uncommitted changes under ``chainrun/solver``,
    HEAD; otherwise the first parent of the newest commit on HEAD's first-parent
    history that changed it (a merge counts as one change). Returns dict(commit,
    asked, why, subject); ValueError when it cannot be resolved.
    """
    environ = os.environ if environ is None else environ
    asked, source = rev, "--against"
    if not asked:
        asked, source = environ.get(AGAINST_ENV) or None, f"${AGAINST_ENV}"
    try:
        if asked:
            commit = git(root, "rev-parse", "--verify", "--quiet", f"{asked}^{{commit}}")
            why = f"{asked} ({source})"
        elif git(root, "status", "--porcelain", "--", SOLVER_PATH):
            commit = git(root, "rev-parse", "--verify", "HEAD")
            why = f"HEAD: {SOLVER_PATH}/ has uncommitted changes"
        else:
            last = git(root, "log", "--first-parent", "-n", "1", "--format=%H", "HEAD",
                       "--", SOLVER_PATH)
            if not last:
                raise ValueError(f"no commit changed {SOLVER_PATH}/: name a revision "
                                 f"with --against or ${AGAINST_ENV}")
            try:
                commit = git(root, "rev-parse", "--verify", "--quiet", f"{last}^1")
            except RuntimeError:
                raise ValueError(f"{last[:12]}, the latest change to {SOLVER_PATH}/, has "
                                 f"no parent: name a revision with --against") from None
            why = (f"{last[:12]}^, the solver before its latest change "
                   f"(\"{git(root, 'log', '-1', '--format=%s', last)}\")")
        subject = git(root, "log", "-1", "--format=%s", commit)
    except RuntimeError as exc:
        raise ValueError(f"cannot resolve the previous version"
                         f"{f' {asked!r}' if asked else ''}: {exc}") from None
    return {"commit": commit, "asked": asked, "why": why, "subject": subject}


def solver_changes_uncommitted(root: Path = ROOT) -> bool:
    return bool(git(root, "status", "--porcelain", "--", SOLVER_PATH))


@contextlib.contextmanager
def checkout(commit: str, tree: Path, root: Path = ROOT):
    """``commit`` checked out (detached) into the folder ``tree`` for the ``with``
    block, and removed after it however it ends."""
    try:
        git(root, "worktree", "add", "--detach", str(tree), commit)
        yield tree
    finally:
        if tree.exists():
            try:
                git(root, "worktree", "remove", "--force", str(tree))
            except RuntimeError as exc:
                log(f"  could not remove the worktree {tree}: {exc}; "
                    f"`git worktree prune` forgets it once the folder is gone")
