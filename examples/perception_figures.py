"""The perception page's figures of the sonar and the tracker.

    python examples/perception_figures.py --out docs/vision

Writes ``sonar_profiles.png`` (look-ahead multibeam profiles over a straight pipe, flat and rough
seabed, lying on it and half buried: the beams, the fitted seabed, the true section and the
detection) and ``tracker_episode.png`` (the heuristic through the camera and the tracker on one
pipe of ``--suite``: top view with the detections and the tracked line, and the pipe's lateral
offset 1.5 m ahead, true against tracked with the tracker's ±2σ), with
``pipefollow.evaluation.perception_figures``, and prints what each shows. The camera frames with
truth and detection are ``samples.png`` of ``pipefollow vision report``. A few seconds.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from pipefollow.evaluation.perception_figures import (
    SONAR_CASES,
    sonar_profiles,
    tracker_episode,
    tracker_figure,
)
from pipefollow.files.machine import script_command, write_output_provenance


def main() -> None:
    """Draw both figures into ``--out``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("perception-figures"))
    ap.add_argument("--suite", default="heldout-sharp")
    ap.add_argument("--pipe", type=int, default=7, help="index of the pipe in --suite")
    ap.add_argument("--water", default="moderate")
    ap.add_argument("--seed", type=int, default=0, help="seed of the pings and of the episode's noise")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    fixes = sonar_profiles(args.out / "sonar_profiles.png", seed=args.seed)
    write_output_provenance(args.out / "sonar_profiles.png", script_command())
    for (title, _, _), fix in zip(SONAR_CASES, fixes, strict=True):
        found = f"found at {fix.lateral:+.3f} m" if fix.found else "not found"
        print(f"{title}: {found}, SNR {fix.snr:.1f}")
    run = tracker_episode(args.suite, args.pipe, args.water, noise_seed=args.seed)
    title = f"{run.pipe.name}, {args.water} water"
    stats = tracker_figure(run, args.out / "tracker_episode.png", title)
    write_output_provenance(args.out / "tracker_episode.png", script_command())
    print(
        f"{title}: "
        + ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in stats.items())
    )


if __name__ == "__main__":
    main()
