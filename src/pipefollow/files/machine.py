"""Where a result was computed: the machine, numba's CPU target and the package versions.

Results do not depend on the CPU (``learners.sums`` fixes every sum's order), so this record does
not decide whether a run folder may be resumed (the code stamp of ``experiments.store`` does); it
is written beside the results so that a reader can see where they came from, and so that a claim
of portability can be checked.
"""

from __future__ import annotations

import platform
from importlib import metadata
from pathlib import Path

PACKAGES = ("pipefollow", "numpy", "numba", "llvmlite", "scipy", "gymnasium")


def numba_target() -> str:
    """The CPU target numba compiles for: ``NUMBA_CPU_NAME`` if set, otherwise the host's own."""
    from llvmlite import binding
    from numba import config

    return config.CPU_NAME or binding.get_host_cpu_name()


def package_versions() -> dict[str, str]:
    """Installed versions of the packages that compute results (``"-"`` for one not installed)."""
    out = {}
    for name in PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "-"
    return out


def machine_stamp() -> dict:
    """The machine and software a result was computed with, as JSON-ready values."""
    return {
        "numba_cpu_target": numba_target(),
        "host_cpu": _host_cpu(),
        "platform": platform.platform(),
        "machine": platform.machine(),
        "python": platform.python_version(),
        "packages": package_versions(),
    }


PROVENANCE_FILE = "provenance.json"


def script_command(argv: list[str] | None = None) -> str:
    """A script's command as it was run (``python examples/x.py --out …``), for :func:`provenance`."""
    import shlex
    import sys

    return shlex.join(["python", *(sys.argv if argv is None else argv)])


def provenance(command: str) -> dict:
    """What a stored output was computed by: the command, the UTC date, the code and the machine.

    The code is the package's version and a hash of all its sources (``files.sources``), so two
    outputs with the same stamp were computed by the same code.
    """
    import datetime

    import pipefollow
    from pipefollow.files.sources import package_modules, source_hash

    return {
        "command": command,
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "code": {"version": pipefollow.__version__, "sources": source_hash(package_modules())},
        "machine": machine_stamp(),
    }


def provenance_path(output) -> Path:
    """Where the provenance of a stored output lives: ``X.provenance.json`` beside a file ``X.ext``.

    A folder's own record (:func:`write_provenance`) covers every output in it that has no record of
    its own; a file beside others made by other commands (``docs/vision/``) has its own record.
    """
    output = Path(output)
    return output.with_name(output.stem + ".provenance.json")


def write_provenance(folder, command: str) -> None:
    """``folder/provenance.json``: :func:`provenance` of ``command``, written atomically."""
    _write_record(Path(folder) / PROVENANCE_FILE, command)


def write_output_provenance(output, command: str) -> Path:
    """The record of one stored output file (:func:`provenance_path`), written atomically; its path."""
    path = provenance_path(output)
    _write_record(path, command)
    return path


def provenance_record_path(output) -> Path | None:
    """The record that says where a stored output was computed, or None if it has none.

    For a file: its own record (:func:`provenance_path`), else its folder's ``provenance.json``; for
    a folder: its ``provenance.json``.
    """
    output = Path(output)
    if output.is_dir():
        candidates = [output / PROVENANCE_FILE]
    else:
        candidates = [provenance_path(output), output.parent / PROVENANCE_FILE]
    return next((p for p in candidates if p.is_file()), None)


def _write_record(path, command: str) -> None:
    import json

    from pipefollow.files.atomic import write_text_atomic

    write_text_atomic(path, json.dumps(provenance(command), indent=1) + "\n")


def describe_provenance(record: dict) -> str:
    """One line for a page: the command, the date, the code stamp and the machine."""
    code = record.get("code", {})
    return (
        f"`{record.get('command', '?')}` on {record.get('date', '?')}, pipefollow "
        f"{code.get('version', '?')} (sources {code.get('sources', '?')}); "
        + describe(record.get("machine", {}))
    )


def describe(stamp: dict) -> str:
    """One line for a report: numba's CPU target, the host, the platform, Python and the package versions."""
    versions = ", ".join(f"{k} {v}" for k, v in stamp.get("packages", {}).items())
    return (
        f"{stamp.get('host_cpu', '?')} ({stamp.get('platform', '?')}), numba's CPU target "
        f"{stamp.get('numba_cpu_target', '?')}, Python {stamp.get('python', '?')}; {versions}"
    )


def _host_cpu() -> str:
    """The processor's model name (Linux: /proc/cpuinfo), else what ``platform`` says."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()
