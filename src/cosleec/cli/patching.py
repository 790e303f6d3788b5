"""``cosleec analyse --fix --write``: each file's patch set, written to the file.

Only the edits of the verified patch set change the file; comments, blank lines and the
author's layout stay byte for byte. Each file is replaced atomically (a temporary file
beside it, flushed to disk, then renamed over it, keeping its permissions), so a failure
leaves the file as it was. Nothing is written when a file of the run has errors (the user
asked for the run's fixes, and one file's are missing), and a file that changed since it
was read is left alone (its fixes were verified against the text read).
"""

from __future__ import annotations

import os
from pathlib import Path

from cosleec.cli.atomic import replace_file
from cosleec.errors import UserError
from cosleec.repair import RepairReport


def write_patch_sets(reports: list[RepairReport]) -> tuple[list[RepairReport], UserError | None]:
    """Write each file's non-empty patch set; the reports written, and the error that
    stopped the rest (None: all written)."""
    failed = [r.path for r in reports if r.failed]
    if failed:
        return [], UserError(
            f"--write wrote nothing: {failed[0]} has errors"
            + (f" (and {len(failed) - 1} more)" if failed[1:] else ""),
            hint="fix them (cosleec check FILE) or leave those files out, then run --fix --write again",
        )
    written: list[RepairReport] = []
    for r in reports:
        if r.plan is None or not r.plan.fixes:
            continue
        try:
            if Path(r.path).read_bytes() != r.source.encode("utf-8"):
                return written, UserError(
                    "--write left the file alone: it changed since it was analysed",
                    where=r.path,
                    hint="run cosleec analyse --fix --write on it again",
                )
            if not os.access(r.path, os.W_OK):
                return written, UserError(
                    "--write cannot write the file: it is read-only; the file is unchanged",
                    where=r.path,
                    hint="make it writable, or apply the diff (--fix) by hand",
                )
            replace_file(Path(r.path), r.plan.text)
        except OSError as e:
            return written, UserError(
                f"--write could not write the patch set: {e.strerror or e}; the file is unchanged",
                where=r.path,
                hint="make the file and its directory writable, or apply the diff (--fix) by hand",
            )
        written.append(r)
    return written, None


__all__ = ["write_patch_sets"]
