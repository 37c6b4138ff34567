"""Checks of output file names given on the command line, made before any long work."""

from __future__ import annotations

import os
from pathlib import Path


class OutputError(ValueError):
    """An output file that cannot be written as asked; the message names the option and the file."""


def image_formats() -> dict[str, str]:
    """File suffix (without the dot) → description of the image formats Matplotlib writes."""
    from matplotlib.backend_bases import FigureCanvasBase

    return dict(FigureCanvasBase.get_supported_filetypes())


def check_output_file(path: str | os.PathLike, option: str, suffixes: tuple[str, ...]) -> str:
    """Check that ``path`` has one of ``suffixes`` and that its folder can exist; returns the suffix.

    Raises:
        OutputError: an unknown suffix, the path is a folder, or a parent is a file.
    """
    p = Path(path)
    suffix = p.suffix.lower().lstrip(".")
    if suffix not in suffixes:
        known = ", ".join(f".{x}" for x in suffixes)
        if not suffix:
            raise OutputError(f"{option} '{p}': has no suffix to tell the file type; use one of {known}")
        raise OutputError(f"{option} '{p}': '.{suffix}' is not a known file type; use one of {known}")
    if p.is_dir():
        raise OutputError(f"{option} '{p}': is a folder")
    for parent in p.parents:
        if parent.exists():
            if not parent.is_dir():
                raise OutputError(f"{option} '{p}': '{parent}' is a file, not a folder")
            break
    return suffix


def first_missing(path: str | os.PathLike) -> Path | None:
    """The outermost folder of ``path`` (itself included) that does not exist yet, or None."""
    p = Path(path)
    missing = None
    for candidate in [p, *p.parents]:
        if candidate.exists():
            break
        missing = candidate
    return missing


def remove_empty_folders(path: str | os.PathLike, up_to: Path | None) -> None:
    """Remove ``path`` and its parents up to ``up_to`` (included) while they are empty folders.

    Undoes the folders a command made (``up_to`` is what :func:`first_missing` said before it
    made them) when the command fails before writing anything into them.
    """
    if up_to is None:
        return
    p = Path(path)
    for folder in [p, *p.parents]:
        try:
            folder.rmdir()  # only an empty folder goes
        except OSError:
            return
        if folder == up_to:
            return
