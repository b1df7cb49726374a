"""The ORB-SLAM2 peer of the results suite: runs it on a TUM folder and reads what it leaves.

ORB-SLAM2 (GPLv3) stays an outside program: the suite calls the peer kit's run.sh (which runs
rgbd_tum from the folder its build.sh made) and reads its output files, nothing else. It runs
three threads and is not deterministic, so each sequence gets several runs, summarised by mean,
minimum and maximum.
"""
from __future__ import annotations

import math
import os
import re
import statistics
import subprocess
from dataclasses import dataclass
from pathlib import Path

# The peer kit's run.sh where it sits beside the checkout (../shared).
DEFAULT_RUN_SCRIPT = Path(__file__).resolve().parents[2].parent / "shared" / "peers" / "orbslam2" / "run.sh"

# Where build.sh puts the RGB-D example inside its destination folder.
RGBD_TUM = Path("ORB_SLAM2") / "Examples" / "RGB-D" / "rgbd_tum"

# rgbd_tum prints "median tracking time: 0.0994008" and "mean tracking time: ..." in seconds.
_TIME_LINE = re.compile(r"^(median|mean) tracking time:\s*([0-9.eE+-]+)\s*$")


@dataclass(frozen=True)
class Peer:
    """The folder build.sh made and the run.sh that runs it."""

    folder: Path
    run_script: Path


def check_peer(folder: Path, run_script: Path) -> str | None:
    """None when the peer can run, else what is missing (for a usage error before any run)."""
    if not folder.is_dir():
        return f"--orbslam2 {folder}: not a folder (give the folder the peer kit's build.sh made)"
    binary = folder / RGBD_TUM
    if not binary.is_file() or not os.access(binary, os.X_OK):
        return f"--orbslam2 {folder}: {RGBD_TUM} is missing or not executable (run the peer kit's build.sh)"
    if not run_script.is_file():
        return f"--orbslam2-run {run_script}: not found (the peer kit's run.sh)"
    return None


def parse_tracking_times(log_text: str) -> dict[str, float]:
    """{'median_ms': .., 'mean_ms': ..} from rgbd_tum's standard output (the lines it has)."""
    times = {}
    for line in log_text.splitlines():
        m = _TIME_LINE.match(line.strip())
        if m:
            value = float(m.group(2))
            if math.isfinite(value):
                times[f"{m.group(1)}_ms"] = value * 1000.0
    return times


def count_poses(path: Path) -> int:
    """Pose lines of a TUM trajectory file (comments and blank lines skipped)."""
    with open(path, encoding="utf-8") as f:
        return sum(1 for line in f if line.strip() and not line.lstrip().startswith("#"))


def run_peer(peer: Peer, dataset: Path, out: Path) -> tuple[list[str], subprocess.CompletedProcess]:
    """Runs run.sh DATASET OUT with ORB_PEER set; returns the argv and the finished process."""
    argv = ["bash", str(peer.run_script), str(dataset), str(out)]
    env = dict(os.environ, ORB_PEER=str(peer.folder))
    return argv, subprocess.run(argv, capture_output=True, text=True, env=env)


def read_peer_run(out: Path, evaluate) -> dict:
    """What one finished peer run left in OUT: trajectory counts, TrackRGBD times and, through
    evaluate(kind, estimate) -> dict (cge_eval ate|rpe --json), ATE and RPE. A run whose files are
    missing or cannot be evaluated gets an 'error' instead of numbers."""
    trajectory = out / "CameraTrajectory.txt"
    keyframes = out / "KeyFrameTrajectory.txt"
    log = out / "orbslam2.log"
    for path in (trajectory, keyframes, log):
        if not path.is_file():
            return {"error": f"{path.name} missing"}
    run: dict = {"tracked_frames": count_poses(trajectory), "keyframes": count_poses(keyframes)}
    run.update({f"track_{k}": v for k, v in parse_tracking_times(log.read_text(encoding="utf-8")).items()})
    try:
        ate = evaluate("ate", trajectory)
    except RuntimeError as e:  # the evaluation refused the trajectory (too few poses, ...)
        run["error"] = last_line(e)
        return run
    run["ate_rmse_m"] = ate.get("ate_rmse_m")
    run["ate_std_m"] = ate.get("ate_std_m")
    try:  # a trajectory shorter than the RPE's time step has no RPE, its ATE still counts
        rpe = evaluate("rpe", trajectory)
        run["rpe_translation_rmse_m"] = rpe.get("rpe_trans_rmse_m")
        run["rpe_rotation_rmse_deg"] = rpe.get("rpe_rot_rmse_deg")
    except RuntimeError as e:
        run["rpe_error"] = last_line(e)
    return run


def last_line(error: Exception) -> str:
    lines = str(error).strip().splitlines()
    return lines[-1] if lines else "evaluation failed"


def spread(values: list) -> dict | None:
    """Mean, sample standard deviation (0 for one number), minimum and maximum of the finite numbers
    among values; None when there are none."""
    numbers = [float(v) for v in values
               if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(float(v))]
    if not numbers:
        return None
    return {"mean": sum(numbers) / len(numbers), "sd": statistics.stdev(numbers) if len(numbers) > 1 else 0.0,
            "min": min(numbers), "max": max(numbers), "count": len(numbers)}


SUMMARISED = ("ate_rmse_m", "ate_std_m", "rpe_translation_rmse_m", "rpe_rotation_rmse_deg", "keyframes",
              "tracked_frames", "track_median_ms", "track_mean_ms")


def summarise(runs: list[dict]) -> dict:
    """Per-quantity spread over the runs that produced numbers, plus how many runs failed."""
    good = [r for r in runs if "error" not in r]
    summary = {key: spread([r.get(key) for r in good]) for key in SUMMARISED}
    summary["runs"] = len(runs)
    summary["failed"] = len(runs) - len(good)
    summary["errors"] = [r["error"] for r in runs if "error" in r]
    return summary
