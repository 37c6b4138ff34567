"""``pipefollow vision``: the detector's report and the camera model calibrated from it; camera options."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import click

from pipefollow.cli.common import SEED, UserError, command_line, guard, writable_folder


@click.group()
def vision() -> None:
    """The vision camera: how good its pipe detector is, and a camera model calibrated from it."""


REPORT_COLUMNS = (
    "turbidity", "burial", "blur", "noise", "snow", "frames_in_view", "frames_without_pipe", "detection_rate",
    "false_detection_rate", "median_error_cm", "p90_error_cm", "gross_error_rate", "rms_m",
)  # fmt: skip


@vision.command()
@click.option(
    "--out",
    "out_dir",
    default="vision-report",
    show_default=True,
    help="Folder of report.csv, samples.png and report.provenance.json (where and by what code "
    "they were computed; the committed ones: --out docs/vision).",
)
@click.option(
    "--pipes",
    type=click.IntRange(1, 100),
    default=100,
    show_default=True,
    help="Held-out pipes to drive along.",
)
@click.option(
    "--frames",
    type=click.IntRange(min=100),
    default=2000,
    show_default=True,
    help="Poses sampled along them.",
)
@click.option(
    "--seed", type=SEED, default=0, show_default=True, help="Seed of the poses, images and detections."
)
@guard
def report(out_dir, pipes, frames, seed):
    """Detection rate, false detections and end-point error per turbidity and burial level.

    Frames are rendered at poses sampled along the heuristic's trajectories on the held-out suite
    (ideal camera, 60 s per pipe); false detections are counted on the same poses without the pipe.
    """
    from pipefollow.evaluation.vision import detector_report, sample_figure
    from pipefollow.files.atomic import write_text_atomic
    from pipefollow.files.machine import write_output_provenance
    from pipefollow.perception.detector import require_cv2
    from pipefollow.sim.suites import get_suite

    try:
        require_cv2()
    except ImportError as e:
        raise UserError(str(e)) from None
    folder = writable_folder(out_dir, "--out")
    rows, pipe_list, frame_list = detector_report(get_suite("heldout"), pipes, frames, seed=seed)
    write_text_atomic(folder / "report.csv", _csv(rows))
    sample_figure(pipe_list, frame_list, folder / "samples.png", seed=seed)
    write_output_provenance(folder / "report.csv", command_line())  # report.provenance.json
    click.echo(_table(rows))
    click.echo(f"report: {folder / 'report.csv'}; sample frames: {folder / 'samples.png'}")


@vision.command()
@click.option(
    "--report",
    "report_path",
    default="vision-report/report.csv",
    show_default=True,
    help="The report.csv of 'pipefollow vision report' (the committed one: docs/vision/report.csv).",
)
@click.option(
    "--out",
    "out_path",
    default=None,
    help="Write the calibration as JSON here (and where and by what code it was computed beside it, "
    "as NAME.provenance.json).",
)
@guard
def calibrate(report_path, out_path):
    """Fit the simulator's camera noise and miss probability to the detector, per turbidity.

    Prints, for each turbidity, the --camera-noise and --miss-prob that make the ideal camera
    miss and err like the detector (gross errors, which the Gaussian model lacks, are listed apart).
    """
    from pipefollow.evaluation.vision import calibrate as fit
    from pipefollow.files.atomic import write_text_atomic
    from pipefollow.files.machine import write_output_provenance

    rows = _read_report(Path(report_path))
    table = fit(rows)
    if out_path:
        write_text_atomic(out_path, json.dumps(table, indent=1) + "\n")
        write_output_provenance(out_path, command_line())
    lines = [f"{'turbidity':>9}  {'camera_noise':>12}  {'miss_prob':>9}  {'gross':>6}  options"]
    for r in table:
        lines.append(
            f"{r['turbidity']:9.3g}  {r['camera_noise']:12.4f}  {r['miss_prob']:9.4f}  "
            f"{r['gross_error_rate']:6.3f}"
            f"  --camera-noise {r['camera_noise']:g} --miss-prob {r['miss_prob']:g}"
        )
    click.echo("\n".join(lines))


def _csv(rows) -> str:
    import io

    buf = io.StringIO()
    writer = csv.DictWriter(buf, REPORT_COLUMNS, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    for r in rows:
        writer.writerow({k: (round(v, 5) if isinstance(v, float) else v) for k, v in r.items()})
    return buf.getvalue()


def _read_report(path: Path) -> list[dict]:
    """The rows of a report.csv; a one-line error naming the file if it is not one."""
    try:
        with path.open(encoding="utf-8", newline="") as f:
            rows = list(csv.DictReader(f))
    except FileNotFoundError:
        raise UserError(f"--report '{path}': no such file (run 'pipefollow vision report' first)") from None
    need = {"turbidity", "burial", "detection_rate", "gross_error_rate", "rms_m"}
    if not rows or not need <= set(rows[0]):
        raise UserError(
            f"--report '{path}': not a report of 'pipefollow vision report' (columns {sorted(need)})"
        )
    try:
        out = [{k: float(r[k]) for k in need} for r in rows]
    except ValueError as e:
        raise UserError(f"--report '{path}': {e}") from None
    if any(not math.isfinite(v) for r in out for k, v in r.items() if k in ("turbidity", "burial")):
        raise UserError(f"--report '{path}': a turbidity or burial that is not a number")
    return out


def _table(rows) -> str:
    names = ("turbidity", "burial", "in view", "found", "false", "median cm", "p90 cm", "gross")
    head = " ".join(f"{n:>{w}}" for n, w in zip(names, (9, 6, 7, 6, 6, 9, 7, 6), strict=True))
    lines = [head]
    for r in rows:
        lines.append(
            f"{r['turbidity']:9.3g} {r['burial']:6.2f} {r['frames_in_view']:7d} {r['detection_rate']:6.1%} "
            f"{r['false_detection_rate']:6.1%} {r['median_error_cm']:9.2f} {r['p90_error_cm']:7.1f} "
            f"{r['gross_error_rate']:6.1%}"
        )
    return "\n".join(lines)
