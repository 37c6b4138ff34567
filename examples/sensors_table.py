"""The heuristic with each sensor: the held-out suite, ideal camera, vision, sonar and fused.

    python examples/sensors_table.py --csv docs/vision/sensors.csv
    python examples/sensors_table.py --rows fused      # the fused rows only (printed)

The heuristic runs one 60-s episode per held-out pipe (100) with each sensor in clear and turbid
water, and half buried (``burial`` 0.5, clear water), through the environment
(``pipefollow benchmark --controller heuristic --suite heldout --camera C --sensor S --water W``
gives each row's numbers); each row is compared with the heuristic on the ideal camera on the
same pipes (paired difference of the returns, bootstrap CI). Rows: ``ideal`` (the exact camera),
``vision`` (detector and tracker), ``sonar`` (the look-ahead multibeam alone), ``fused`` (the
vision camera's detections, the sonar's where it finds none, in one track that each ping's fix
also corrects), ``fused-ideal`` (the
exact camera, the sonar's view where it sees no pipe).
"""

from __future__ import annotations

import argparse
import csv
import io

from pipefollow.evaluation.benchmark import benchmark
from pipefollow.files.atomic import write_text_atomic
from pipefollow.files.machine import script_command, write_output_provenance
from pipefollow.learners.heuristic import Heuristic
from pipefollow.sim.suites import get_suite

COLUMNS = (
    "water", "burial", "sensor", "camera", "mean_return", "ci95_low", "ci95_high", "success_rate",
    "pipe_in_view", "turned_back", "loss_vs_ideal", "loss_ci95_low", "loss_ci95_high",
)  # fmt: skip

SENSORS = (  # (row name, sensor, camera)
    ("ideal", "camera", "ideal"),
    ("vision", "camera", "vision"),
    ("sonar", "sonar", "ideal"),
    ("fused", "fused", "vision"),
    ("fused-ideal", "fused", "ideal"),
)
WATERS = (("clear", 0.0), ("turbid", 0.0), ("clear", 0.5))


def main() -> None:
    """Print the table's rows and write the CSV."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--csv", default=None, help="write the table here")
    ap.add_argument("--pipes", type=int, default=None, help="the first N held-out pipes [all 100]")
    ap.add_argument("--noise-seed", type=int, default=0)
    names = [name for name, _, _ in SENSORS]
    ap.add_argument("--rows", nargs="+", choices=names, default=names, help="these sensors' rows only [all]")
    args = ap.parse_args()
    suite = get_suite("heldout")
    rows = []
    for water, burial in WATERS:
        for name, sensor, camera in SENSORS:
            if name not in args.rows:
                continue
            if name == "ideal" and (water, burial) != ("clear", 0.0):
                continue  # the exact camera sees through any water
            if name == "fused-ideal" and (water, burial) != ("clear", 0.0):
                continue  # the exact camera's view does not depend on the water
            cam = None
            if (sensor, camera) != ("camera", "ideal"):
                cam = {"camera": camera, "water": {"preset": water, "burial": burial}}
                if sensor != "camera":
                    cam["sensor"] = sensor
            run = benchmark(
                Heuristic(), suite, controller="heuristic", n_pipes=args.pipes, noise_seed=args.noise_seed,
                camera=cam,
            )  # fmt: skip
            s = run.summary
            zero = {"mean_diff": 0.0, "ci95_diff": [0.0, 0.0]}
            diff = s.get("vs_heuristic_ideal", zero)  # the heuristic's own row on the ideal camera: none
            row = {
                "water": water, "burial": burial, "sensor": name, "camera": camera,
                "mean_return": round(s["mean_return"], 2), "ci95_low": round(s["ci95_mean"][0], 2),
                "ci95_high": round(s["ci95_mean"][1], 2), "success_rate": round(s["success_rate"], 3),
                "pipe_in_view": round(s["mean_pipe_in_view"], 4),
                "turned_back": s["turned_back"],
                "loss_vs_ideal": round(-diff["mean_diff"], 2),
                "loss_ci95_low": round(-diff["ci95_diff"][1], 2),
                "loss_ci95_high": round(-diff["ci95_diff"][0], 2),
            }  # fmt: skip
            rows.append(row)
            print(",".join(str(row[c]) for c in COLUMNS), flush=True)
    if args.csv:
        out = io.StringIO()
        w = csv.DictWriter(out, COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        write_text_atomic(args.csv, out.getvalue())
        write_output_provenance(args.csv, script_command())  # X.provenance.json beside it


if __name__ == "__main__":
    main()
