"""The closed-loop table: every controller through every sensor, in every water, on three suites.

    python examples/closed_loop_table.py --policies /work/policies-vision \
        --out docs/vision/closed_loop_sensors [--jobs 2]

Controllers: the heuristic, LOS (Δ = 1.5 m), CACLA and supervised CACLA (the README's recipe:
5,000 episodes of 90 s on random:mixed) and PPO (100,000 steps on random:mixed, the extra
``deep``), all trained on the ideal camera, and PPO trained the same way through the sensor it
meets in murky water (``--camera vision --sensor fused --water turbid``; the paper's learners
trained so gain nothing: docs/decisions.md), the learned ones from ``--policies`` (trained
there if missing, as ``examples/vision_table.py`` trains them). Sensors: ``ideal`` (the exact
camera), ``raw`` (the rendered camera's detector alone, ``camera="vision-raw"``), ``tracker``
(the detector and the pipe tracker, ``camera="vision"``), ``sonar`` (the look-ahead multibeam
alone), ``fused`` (the tracked camera, the sonar's detections where it finds none), and ``fls`` and
``fused-fls`` (the same two with the forward-looking imaging sonar). Waters:
the presets ``clear``, ``moderate`` and ``turbid``, and ``half-buried`` (clear water, ``burial``
0.5: half the pipe's width under sand for the camera, half its diameter for the sonar,
``perception.sensor``). The ideal camera sees through any water: one cell per suite (water
``any``). Suites: ``heldout``, ``heldout-hard`` and ``heldout-sharp``, 100 pipes × 60 s each,
noise seed 0: one deterministic episode per pipe, every controller meeting the same noise on the
same pipe.

Each row is compared, paired per pipe, with the heuristic through the same sensor in the same
water (``vs_same``) and with the heuristic on the ideal camera (``vs_ideal``), with bootstrap 95 %
intervals (``pipefollow benchmark --sensor S --camera C --water W`` prints both); a row in another
water than clear also with the same controller through the same sensor in clear water
(``vs_clear``: what the water costs it; for ``half-buried``, what the sand does). ``lost_pipes``
counts the episodes with the pipe in view at fewer than 80 % of the decisions; ``turned_back``
those that followed the pipe backwards for ≥ 3 m; success is today's
(``pipefollow.evaluation.success``).

Resumable: every cell (suite, sensor, water, controller) is stored in ``--cells`` as it finishes
(written atomically) with the hash of the sources of the modules the episodes run (the
benchmark's imports) and of its policy file; a run skips
the cells stored by the same code and policy and recomputes the others, so after a code change it
recomputes everything without being told. ``--suites``, ``--sensors``, ``--waters`` and
``--controllers`` restrict what is computed (the reference cells are added: the heuristic's, and
each controller's in clear water); the CSV
always holds every row whose cells the store has for today's code. ``--jobs N`` runs N cells at a
time in separate processes.

Run time (2 cores): all 255 cells in 328 s with ``--jobs 2`` and nothing else running, 11 minutes
with ``--jobs 1`` beside other work; the 306 cells with the sensor-trained PPO in 442–688 s with
``--jobs 2`` beside other processes; the 450 with the imaging sonar's two sensors in 828 s with
``--jobs 2`` (docs/decisions.md, "Every controller through every sensor");
plus about 6 minutes to train the four policies when ``--policies`` lacks them.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import io
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from pipefollow.evaluation.benchmark import load_controller, run_episodes, summarize
from pipefollow.files.atomic import write_text_atomic
from pipefollow.sim import episode as ep
from pipefollow.sim.suites import get_suite, min_length_for

SECONDS = 60.0
NOISE_SEED = 0
SUITES = ("heldout", "heldout-hard", "heldout-sharp")
CONTROLLERS = {  # key → label in the table
    "heuristic": "heuristic",
    "los": "LOS (Δ = 1.5 m)",
    "cacla": "CACLA",
    "supervised-cacla": "supervised CACLA",
    "ppo": "PPO",
    "ppo-fused-turbid": "PPO trained through the fused sensor in turbid water",
}
# the options PPO's sensor-trained row trains with (``pipefollow train``; the other rows: the ideal camera)
FUSED_TURBID = ("--camera", "vision", "--sensor", "fused", "--water", "turbid")
SENSORS = {  # key → (label, camera, sensor)
    "ideal": ("ideal camera", "ideal", "camera"),
    "raw": ("camera, detector alone", "vision-raw", "camera"),
    "tracker": ("camera + tracker", "vision", "camera"),
    "sonar": ("sonar", "ideal", "sonar"),
    "fused": ("camera + tracker + sonar", "vision", "fused"),
    "fls": ("imaging sonar", "ideal", "fls"),
    "fused-fls": ("camera + tracker + imaging sonar", "vision", "fused-fls"),
}
WATERS = {  # key → the environment's water
    "clear": {"preset": "clear"},
    "moderate": {"preset": "moderate"},
    "turbid": {"preset": "turbid"},
    "half-buried": {"preset": "clear", "burial": 0.5},
}
ANY_WATER = "any"  # the ideal camera's one water
COLUMNS = (
    "suite", "sensor", "water", "controller", "label", "n_pipes", "mean_return", "ci95_low", "ci95_high",
    "success_rate", "pipe_in_view", "turned_back", "lost_pipes", "vs_same", "vs_same_low", "vs_same_high",
    "vs_ideal", "vs_ideal_low", "vs_ideal_high", "vs_clear", "vs_clear_low", "vs_clear_high",
)  # fmt: skip
CLEAR_WATER = "clear"  # the water every other is compared with (``vs_clear``)


def waters_of(sensor: str, waters) -> list[str]:
    """The waters a sensor's cells are measured in (the ideal camera: one, ``any``)."""
    return [ANY_WATER] if sensor == "ideal" else list(waters)


def camera_of(sensor: str, water: str) -> dict | None:
    """The environment's camera arguments of a cell (None: the ideal camera)."""
    _, camera, kind = SENSORS[sensor]
    if sensor == "ideal":
        return None
    out = {"camera": camera, "water": dict(WATERS[water])}
    if kind != "camera":
        out["sensor"] = kind
    return out


def file_hash(path: str | Path) -> str:
    """The first 16 hex digits of a file's SHA-256."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]


def code_hash() -> str:
    """The hash of the sources of every module the episodes can run (``pipefollow.files.sources``)."""
    from pipefollow.files.sources import imported_modules, source_hash

    return source_hash(imported_modules("pipefollow.evaluation.benchmark"))


def cell_path(cells: Path, suite: str, sensor: str, water: str, controller: str) -> Path:
    """Where a cell's statistics are stored."""
    return cells / suite / f"{sensor}-{water}" / f"{controller}.json"


def stored(path: Path, stamp: dict) -> dict | None:
    """The cell stored at ``path`` if it was computed with ``stamp``; None otherwise."""
    try:
        cell = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return cell if cell.get("stamp") == stamp else None


def run_cell(job: tuple) -> tuple[str, float]:
    """Compute one cell and store it (a worker's task): its path and the seconds it took."""
    path, suite, sensor, water, spec, stamp = job
    t = time.perf_counter()
    pipes = get_suite(suite).pipes(100, min_length_for(SECONDS))
    res, _ = run_episodes(load_controller(spec), pipes, SECONDS, noise_seed=NOISE_SEED,
                          camera=camera_of(sensor, water))  # fmt: skip
    cell = {"stamp": stamp, "stat_names": list(ep.STAT_NAMES), "pipes": [p.name for p in pipes],
            "stats": res.tolist()}  # fmt: skip
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, json.dumps(cell) + "\n")
    return str(path), time.perf_counter() - t


def specs_of(policies: Path | None) -> dict[str, str]:
    """Each controller's ``load_controller`` spec; the learned policies trained if missing."""
    specs = {"heuristic": "heuristic", "los": "los"}
    if policies is not None:
        from vision_table import train, train_ppo  # the same folder layout and recipes

        specs["cacla"] = train(policies / "plain", 2010, 0.0, 0.0)
        specs["supervised-cacla"] = train(policies / "supervised", 2010, 0.0, 0.0, supervised=True)
        specs["ppo"] = train_ppo(policies / "ppo", 0)
        specs["ppo-fused-turbid"] = train_ppo(policies / "ppo-fused-turbid", 0, *FUSED_TURBID)
    return specs


def stamp_of(spec: str, code: str) -> dict:
    """A cell's stamp: the code's hash and, for a learned policy, its file's."""
    return {"code": code, "policy": None if spec in ("heuristic", "los") else file_hash(spec)}


def row_of(cells: Path, suite, sensor, water, controller, specs, code, pipes) -> dict | None:
    """The CSV row of one cell and its references (None if one of them is not stored)."""

    def load(s, w, c):
        cell = stored(cell_path(cells, suite, s, w, c), stamp_of(specs[c], code))
        return None if cell is None else np.array(cell["stats"])

    res = load(sensor, water, controller)
    same = load(sensor, water, "heuristic")
    ideal = load("ideal", ANY_WATER, "heuristic")
    if res is None or same is None or ideal is None:
        return None
    refs = {}
    if controller != "heuristic":
        refs["vs_same"] = same[:, ep.STAT_RETURN]
    if (sensor, controller) != ("ideal", "heuristic"):
        refs["vs_ideal"] = ideal[:, ep.STAT_RETURN]
    if water not in (CLEAR_WATER, ANY_WATER):
        clear = load(sensor, CLEAR_WATER, controller)
        if clear is not None:
            refs["vs_clear"] = clear[:, ep.STAT_RETURN]
    s = summarize(res, pipes, controller=controller, suite=suite, seed=NOISE_SEED, references=refs)
    row = {
        "suite": suite, "sensor": sensor, "water": water, "controller": controller,
        "label": CONTROLLERS[controller], "n_pipes": s["n_episodes"], "mean_return": s["mean_return"],
        "ci95_low": s["ci95_mean"][0], "ci95_high": s["ci95_mean"][1], "success_rate": s["success_rate"],
        "pipe_in_view": s["mean_pipe_in_view"], "turned_back": s["turned_back"],
        "lost_pipes": s["lost_pipes"],
    }  # fmt: skip
    for key in ("vs_same", "vs_ideal", "vs_clear"):
        d = s.get(key)
        row[key] = None if d is None else d["mean_diff"]
        row[key + "_low"] = None if d is None else d["ci95_diff"][0]
        row[key + "_high"] = None if d is None else d["ci95_diff"][1]
    return row


def fmt(v):
    """Four decimals in the CSV; an empty cell for no value."""
    if v is None:
        return ""
    return round(v, 4) if isinstance(v, float) else v


def choose(text: str | None, allowed, name: str) -> list[str]:
    """A comma-separated choice among ``allowed`` (all of them when None); a one-line error otherwise."""
    if text is None:
        return list(allowed)
    chosen = [t.strip() for t in text.split(",") if t.strip()]
    bad = [t for t in chosen if t not in allowed]
    if bad or not chosen:
        sys.exit(f"closed_loop_table: --{name} {text!r}: choose from {', '.join(allowed)}")
    return chosen


def main() -> None:
    """Compute the missing cells, then write the CSV and its provenance."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--policies",
        type=Path,
        default=None,
        help="folder of the learned policies (trained if missing); without it: heuristic and LOS",
    )
    ap.add_argument("--cells", type=Path, default=Path("runs/closed-loop-cells"), help="the cell store")
    ap.add_argument("--out", type=Path, default=None, help="folder of table.csv and provenance.json")
    ap.add_argument("--jobs", type=int, default=1, help="cells computed at a time (processes)")
    ap.add_argument("--suites", help=f"comma-separated, of {', '.join(SUITES)} [all]")
    ap.add_argument("--sensors", help=f"comma-separated, of {', '.join(SENSORS)} [all]")
    ap.add_argument("--waters", help=f"comma-separated, of {', '.join(WATERS)} [all]")
    ap.add_argument("--controllers", help=f"comma-separated, of {', '.join(CONTROLLERS)} [all]")
    args = ap.parse_args()  # fmt: skip
    suites = choose(args.suites, SUITES, "suites")
    sensors = choose(args.sensors, SENSORS, "sensors")
    waters = choose(args.waters, WATERS, "waters")
    controllers = choose(args.controllers, CONTROLLERS, "controllers")
    if args.jobs < 1:
        sys.exit(f"closed_loop_table: --jobs {args.jobs}: must be at least 1")
    specs = specs_of(args.policies)
    missing = [c for c in controllers if c not in specs]
    if missing:
        sys.exit(f"closed_loop_table: {', '.join(missing)} need --policies FOLDER")
    code = code_hash()
    wanted = []
    for suite in suites:
        for sensor in sensors:
            for water in waters_of(sensor, waters):
                for c in dict.fromkeys(["heuristic", *controllers]):  # the reference first
                    wanted.append((suite, sensor, water, c))
                    if water not in (CLEAR_WATER, ANY_WATER):  # vs_clear's reference
                        wanted.append((suite, sensor, CLEAR_WATER, c))
            wanted += [(suite, "ideal", ANY_WATER, "heuristic")]  # the second reference
    wanted = list(dict.fromkeys(wanted))
    jobs = []
    for suite, sensor, water, c in wanted:
        path = cell_path(args.cells, suite, sensor, water, c)
        stamp = stamp_of(specs[c], code)
        if stored(path, stamp) is None:
            jobs.append((str(path), suite, sensor, water, specs[c], stamp))
    print(f"{len(wanted) - len(jobs)} of {len(wanted)} cells stored; computing {len(jobs)}", flush=True)
    start = time.perf_counter()
    if args.jobs == 1:
        done = (run_cell(j) for j in jobs)
        for k, (path, sec) in enumerate(done, 1):
            print(f"[{k}/{len(jobs)}] {path}: {sec:.1f} s", flush=True)
    elif jobs:
        with ProcessPoolExecutor(args.jobs, mp_context=get_context("spawn")) as pool:
            futures = [pool.submit(run_cell, j) for j in jobs]
            for k, f in enumerate(as_completed(futures), 1):
                path, sec = f.result()
                print(f"[{k}/{len(jobs)}] {path}: {sec:.1f} s", flush=True)
    print(f"computed {len(jobs)} cells in {time.perf_counter() - start:.0f} s", flush=True)
    if args.out:
        write_table(args, specs, code)


def write_table(args, specs: dict, code: str) -> None:
    """``table.csv`` of every row the store has for today's code, and ``provenance.json``."""
    from pipefollow.files.machine import script_command, write_provenance

    rows = []
    for suite in SUITES:
        pipes = get_suite(suite).pipes(100, min_length_for(SECONDS))
        for sensor in SENSORS:
            for water in waters_of(sensor, WATERS):
                for c in CONTROLLERS:
                    if c in specs:
                        row = row_of(args.cells, suite, sensor, water, c, specs, code, pipes)
                        rows += [row] if row else []
    out = io.StringIO()
    w = csv.DictWriter(out, COLUMNS, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: fmt(r[k]) for k in COLUMNS})
    args.out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(args.out / "table.csv", out.getvalue())
    write_provenance(args.out, script_command())
    print(f"{len(rows)} rows: {args.out / 'table.csv'}", flush=True)


if __name__ == "__main__":
    main()
