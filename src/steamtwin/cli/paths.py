"""Output paths checked before a command starts its work.

Policy, the same for every command: a missing parent folder is created; a file output that is
an existing folder, a folder output that is an existing file, or a location that cannot be
written is refused at once with the path and the reason, never by a traceback after minutes of
work.
"""

from __future__ import annotations

import os
from pathlib import Path

from steamtwin.errors import SteamtwinError

__all__ = ["OutputPathError", "prepare_output_file", "prepare_output_folder"]


class OutputPathError(SteamtwinError, ValueError):
    """An output path cannot be written; the message names the option and the path."""


def prepare_output_file(path: Path, option: str) -> Path:
    """Check that ``path`` can be written as a file (its parent folder is created if missing).

    ``option`` is the CLI option naming the path (e.g. ``"--out"``) for the message.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputPathError(f"{option} {path}: is a folder; give a file name")
    _make_folder(path.parent, option, path)
    if path.exists() and not os.access(path, os.W_OK):
        raise OutputPathError(f"{option} {path}: the file exists and is not writable")
    return path


def prepare_output_folder(path: Path, option: str) -> Path:
    """Create the output folder ``path`` if missing; refuse a file or an unwritable folder."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputPathError(f"{option} {path}: is a file; give a folder")
    _make_folder(path, option, path)
    return path


def _make_folder(folder: Path, option: str, path: Path) -> None:
    folder = folder if str(folder) else Path(".")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        raise OutputPathError(
            f"{option} {path}: {folder} (or a folder above it) is a file, not a folder"
        ) from None
    except OSError as error:
        raise OutputPathError(f"{option} {path}: cannot create folder {folder}: "
                              f"{error.strerror or error}") from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise OutputPathError(f"{option} {path}: folder {folder} is not writable")
