"""Replacing a file atomically: the commands that rewrite the user's files (``cosleec analyse
--fix --write``, ``cosleec fmt --in-place``).

The new text goes to a temporary file beside the old one, is flushed to disk, takes the old
file's permissions (and owner, when allowed), then is renamed over it: a crash or a full disk
leaves the old file or the new one, never half of one, and no temporary file behind. A
symbolic link stays one: its target is rewritten.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


def replace_file(path: Path, text: str) -> None:
    """Write ``text`` (UTF-8, line endings as given) over ``path`` atomically; OSError when
    it cannot, with ``path`` untouched."""
    path = path.resolve()
    info = path.stat()
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(text.encode("utf-8"))
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, info.st_mode & 0o7777)
        if (info.st_uid, info.st_gid) != (os.getuid(), os.getgid()):
            with contextlib.suppress(PermissionError):  # kept when allowed (root), as editors do
                os.chown(tmp, info.st_uid, info.st_gid)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


__all__ = ["replace_file"]
