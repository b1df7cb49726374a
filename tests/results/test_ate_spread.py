#!/usr/bin/env python3
"""Test of examples/results/ate_spread.py on a short rendered sequence (written by cge_sim).

The oracle: the family's weights are recomputed here from the default run's summary.json, and the
table's statistics from each run's own summary.json with this file's arithmetic; bad arguments must
exit with code 2 and name the argument, leaving a non-empty --out untouched.

Usage: test_ate_spread.py --script ate_spread.py --tools DIR_WITH_cge_slam_cge_eval --sim cge_sim --work DIR
"""
import argparse
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path


def fail(message: str) -> None:
    print(f"FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def check(condition: bool, message: str) -> None:
    if not condition:
        fail(message)


def main() -> int:
    parser = argparse.ArgumentParser()
    for name in ("--script", "--tools", "--sim", "--work"):
        parser.add_argument(name, required=True, type=Path)
    args = parser.parse_args()
    work = args.work
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    sequence = work / "sequence"
    subprocess.run([str(args.sim), "--preset", "walking_xyz", "--frames", "20", "--seed", "3", "--out", str(sequence)],
                   check=True, capture_output=True)

    def spread(*extra: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, str(args.script), "--tools", str(args.tools), "--dataset",
                               str(sequence), *extra], capture_output=True, text=True)

    # Bad arguments: exit 2, the argument named, nothing written.
    occupied = work / "occupied"
    occupied.mkdir()
    (occupied / "keep.txt").write_text("mine\n")
    for extra, named in ((["--runs", "0", "--out", str(work / "a")], "--runs"),
                         (["--jobs", "17", "--out", str(work / "a")], "--jobs"),
                         (["--model", str(work / "none.onnx"), "--out", str(work / "a")], "--model"),
                         (["--orbslam2", str(work / "no_peer"), "--out", str(work / "a")], "--orbslam2"),
                         (["--out", str(occupied)], "--force")):
        done = spread(*extra)
        check(done.returncode == 2, f"{extra}: exit code {done.returncode}, expected 2")
        check(named in done.stderr, f"{extra}: the message does not name {named}: {done.stderr}")
    check(not (work / "a").exists(), "a refused run created its --out")
    check(sorted(p.name for p in occupied.iterdir()) == ["keep.txt"], "a refused run touched a non-empty --out")
    done = subprocess.run([sys.executable, str(args.script), "--tools", str(work), "--dataset", str(sequence),
                           "--out", str(work / "a")], capture_output=True, text=True)
    check(done.returncode == 2 and "cge_slam" in done.stderr, f"a --tools without cge_slam: {done.stderr}")

    # Three runs of each configuration: the even grid over 0.9 .. 1.1 is 0.9, 1.0, 1.1; the default
    # (1.0) runs first.
    out = work / "spread"
    done = spread("--runs", "3", "--jobs", "2", "--out", str(out))
    check(done.returncode == 0, f"the run failed: {done.stderr}")
    result = json.loads((out / "spread.json").read_text())
    configs = result["configurations"]
    check([c["name"] for c in configs] == ["--mode none", "--mode YMK --segmentation none"],
          f"configurations {[c['name'] for c in configs]}")
    default = None
    for config in configs:
        runs = config["runs"]
        check(len(runs) == 3, f"{config['name']}: {len(runs)} runs")
        sigmas = []
        ates = []
        keyframes = []
        for run in runs:
            summary = json.loads((Path(run["out"]) / "summary.json").read_text())
            sigmas.append(summary["mapping_settings"]["tracking_depth_sigma"])
            ates.append(summary["ate"]["rmse_m"])
            keyframes.append(summary["keyframes"])
        if default is None:
            default = sigmas[0]
        check(sigmas[0] == default == result["default_tracking_depth_sigma"], f"default weight {sigmas}")
        for got, factor in zip(sigmas[1:], (0.9, 1.1)):
            check(math.isclose(got, default * factor, rel_tol=1e-5), f"weight {got}, expected {default} x {factor}")
        mean = sum(ates) / 3
        sd = math.sqrt(sum((a - mean) ** 2 for a in ates) / 2)
        ate = config["ate_rmse_m"]
        check(math.isclose(ate["mean"], mean, rel_tol=1e-12), f"{config['name']}: mean {ate['mean']} vs {mean}")
        check(math.isclose(ate["sd"], sd, rel_tol=1e-9, abs_tol=1e-15), f"{config['name']}: sd {ate['sd']} vs {sd}")
        check(ate["min"] == min(ates) and ate["max"] == max(ates), f"{config['name']}: min/max")
        check(config["keyframes"]["mean"] == sum(keyframes) / 3, f"{config['name']}: keyframes")
        row = f"| cge_slam {config['name']} | 3 | {1000 * mean:.1f} mm |"
        check(row in (out / "spread.txt").read_text(), f"spread.txt has no row starting '{row}'")
    check("| ORB-SLAM2 |" not in (out / "spread.txt").read_text(), "a peer row without --orbslam2")
    print("ate_spread.py: arguments, weights and statistics as expected")
    return 0


if __name__ == "__main__":
    sys.exit(main())
