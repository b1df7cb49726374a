#!/usr/bin/env python3
"""Test of examples/results/ate_spread.py on a short rendered sequence (written by cge_sim).

The oracle: for the start_offset family each run's frame count and its cut rgb.txt / depth.txt are
checked against the sequence's own lists; for the depth_sigma family the weights are recomputed here
from the default run's summary.json; for both the table's statistics are recomputed from each run's
own summary.json with this file's arithmetic, and the time per frame from each run's timings.csv
(median and 95th percentile of total_ms - segmentation_ms, computed here). The comparison with the
peer's TrackRGBD median is checked on hand-made runs with known ratios (the peer is not built here),
and a broken timings.csv must be refused naming its file and line. Bad arguments must exit with
code 2 and name the argument, leaving a non-empty --out untouched.

Usage: test_ate_spread.py --script ate_spread.py --tools DIR_WITH_cge_slam_cge_eval --sim cge_sim --work DIR
"""
import argparse
import csv
import importlib.util
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
    # Depth stamped 10 ms before colour, as a real Kinect's often is: the start_offset family must
    # keep the depth frame that pairs with the first colour frame it keeps.
    depth_list = sequence / "depth.txt"
    depth_list.write_text("".join(
        line + "\n" if line.startswith("#") or not line.strip()
        else f"{float(line.split()[0]) - 0.01:.6f} {' '.join(line.split()[1:])}\n"
        for line in depth_list.read_text().splitlines()))

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
                         (["--family", "seeds", "--out", str(work / "a")], "--family"),
                         (["--runs", "12", "--out", str(work / "a")], "--runs"),  # 11 of 20 frames skipped
                         (["--configs", "none,fast", "--out", str(work / "a")], "--configs"),
                         (["--configs", "ymk_yolo", "--out", str(work / "a")], "--model"),
                         (["--variant", "a", "--out", str(work / "a")], "--variant"),
                         (["--variant", "a b=--mode none", "--out", str(work / "a")], "--variant"),
                         (["--variant", "a=--out /tmp/x", "--out", str(work / "a")], "--out"),
                         (["--variant", "a=--orb-spread '2", "--out", str(work / "a")], "--variant"),
                         (["--variant", "a=", "--variant", "a=--mode none", "--out", str(work / "a")], "--variant"),
                         (["--out", str(occupied)], "--force")):
        done = spread(*extra)
        check(done.returncode == 2, f"{extra}: exit code {done.returncode}, expected 2")
        check(named in done.stderr, f"{extra}: the message does not name {named}: {done.stderr}")
    broken = work / "broken"
    shutil.copytree(sequence, broken)
    lines = (broken / "rgb.txt").read_text().splitlines()
    lines[5] = "1.2.3 rgb/x.png"
    (broken / "rgb.txt").write_text("\n".join(lines) + "\n")
    done = subprocess.run([sys.executable, str(args.script), "--tools", str(args.tools), "--dataset", str(broken),
                           "--out", str(work / "a")], capture_output=True, text=True)
    check(done.returncode == 2 and f"{broken / 'rgb.txt'}:6:" in done.stderr,
          f"a bad time stamp in rgb.txt line 6: exit code {done.returncode}, {done.stderr}")
    check(not (work / "a").exists(), "a refused run created its --out")
    check(sorted(p.name for p in occupied.iterdir()) == ["keep.txt"], "a refused run touched a non-empty --out")
    done = subprocess.run([sys.executable, str(args.script), "--tools", str(work), "--dataset", str(sequence),
                           "--out", str(work / "a")], capture_output=True, text=True)
    check(done.returncode == 2 and "cge_slam" in done.stderr, f"a --tools without cge_slam: {done.stderr}")

    def data_lines(path: Path) -> list:
        return [line for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]

    def check_times(config: dict) -> None:
        medians, ratios = [], []
        for run in config["runs"]:
            with open(Path(run["out"]) / "timings.csv", newline="") as f:
                totals = sorted(float(r["total_ms"]) - float(r["segmentation_ms"]) for r in csv.DictReader(f))
            n = len(totals)
            median = totals[n // 2] if n % 2 else (totals[n // 2 - 1] + totals[n // 2]) / 2
            k = 0.95 * (n - 1)
            p95 = totals[int(k)] * (1 - (k - int(k))) + totals[min(int(k) + 1, n - 1)] * (k - int(k))
            check(math.isclose(run["total_median_ms"], median, rel_tol=1e-12), f"{config['name']}: median time")
            check(math.isclose(run["total_p95_ms"], p95, rel_tol=1e-9), f"{config['name']}: p95 {run['total_p95_ms']} vs {p95}")
            check(math.isclose(run["p95_over_median"], p95 / median, rel_tol=1e-9), f"{config['name']}: p95 / median")
            medians.append(median)
            ratios.append(p95 / median)
        t = config["time"]
        check(math.isclose(t["total_median_ms"]["max"], max(medians), rel_tol=1e-12), f"{config['name']}: max median")
        check(t["runs_over_3x"] == sum(1 for r in ratios if r > 3), f"{config['name']}: runs over 3x")
        check("over_peer_median" not in t, f"{config['name']}: a peer ratio without --orbslam2")

    def check_statistics(out: Path, config: dict, ates: list, keyframes: list) -> None:
        mean = sum(ates) / 3
        sd = math.sqrt(sum((a - mean) ** 2 for a in ates) / 2)
        ate = config["ate_rmse_m"]
        check(math.isclose(ate["mean"], mean, rel_tol=1e-12), f"{config['name']}: mean {ate['mean']} vs {mean}")
        check(math.isclose(ate["sd"], sd, rel_tol=1e-9, abs_tol=1e-15), f"{config['name']}: sd {ate['sd']} vs {sd}")
        check(ate["min"] == min(ates) and ate["max"] == max(ates), f"{config['name']}: min/max")
        check(config["keyframes"]["mean"] == sum(keyframes) / 3, f"{config['name']}: keyframes")
        row = f"| cge_slam {config['name']} | 3 | {1000 * mean:.1f} mm |"
        check(row in (out / "spread.txt").read_text(), f"spread.txt has no row starting '{row}'")

    # The start_offset family (the default), three runs: round i skips the first i frames.
    rgb = data_lines(sequence / "rgb.txt")
    depth = data_lines(sequence / "depth.txt")
    out = work / "offsets"
    done = spread("--runs", "3", "--jobs", "2", "--out", str(out))
    check(done.returncode == 0, f"the start_offset run failed: {done.stderr}")
    result = json.loads((out / "spread.json").read_text())
    check(result["family"] == "start_offset" and result["start_offsets"] == [0, 2], f"family {result.get('family')}")
    for config in result["configurations"]:
        ates, keyframes = [], []
        for offset, run in enumerate(config["runs"]):
            summary = json.loads((Path(run["out"]) / "summary.json").read_text())
            check(run["start_offset"] == offset, f"{config['name']}: run {offset} has offset {run['start_offset']}")
            check(summary["frames"] == len(rgb) - offset,
                  f"{config['name']}: offset {offset} ran {summary['frames']} frames, expected {len(rgb) - offset}")
            if offset == 0:
                check(summary["source"] == str(sequence.resolve()), f"offset 0 ran on {summary['source']}")
            else:
                cut = Path(summary["source"])
                check(data_lines(cut / "rgb.txt") == rgb[offset:], f"offset {offset}: rgb.txt is not the list cut")
                first = float(rgb[offset].split()[0])
                kept = [line for line in depth if float(line.split()[0]) >= first - 0.02]
                check(data_lines(cut / "depth.txt") == kept, f"offset {offset}: depth.txt is not the list cut")
                check((cut / "groundtruth.txt").resolve() == (sequence / "groundtruth.txt").resolve(),
                      f"offset {offset}: groundtruth.txt is not the sequence's")
            ates.append(summary["ate"]["rmse_m"])
            keyframes.append(summary["keyframes"])
        check_statistics(out, config, ates, keyframes)
        check_times(config)
    check("| cge_slam --mode none |" in (out / "spread.txt").read_text().split("serial total median")[1],
          "spread.txt has no time row for mode none")

    # The time summary against a peer, on hand-made runs: our medians 10, 20, 30 ms against the
    # peer's 20, 10, 40 ms (ratios 0.5, 2.0, 0.75; one round over), a round whose peer time is missing
    # left out; p95 / median 2.0, 3.5, 1.0 (one run over 3x).
    spec = importlib.util.spec_from_file_location("ate_spread", args.script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    runs = [{"total_median_ms": 10.0, "p95_over_median": 2.0}, {"total_median_ms": 20.0, "p95_over_median": 3.5},
            {"total_median_ms": 30.0, "p95_over_median": 1.0}, {"total_median_ms": 5.0, "p95_over_median": 1.5}]
    peers = [{"track_median_ms": 20.0}, {"track_median_ms": 10.0}, {"track_median_ms": 40.0}, {"error": "log missing"}]
    t = module.time_summary(runs, peers)
    check(t["rounds_compared"] == 3 and t["rounds_over"] == 1, f"rounds {t['rounds_compared']} / over {t['rounds_over']}")
    check(math.isclose(t["over_peer_median"]["mean"], (0.5 + 2.0 + 0.75) / 3, rel_tol=1e-12)
          and t["over_peer_median"]["min"] == 0.5 and t["over_peer_median"]["max"] == 2.0, f"ratios {t['over_peer_median']}")
    check(t["runs_over_3x"] == 1, f"runs over 3x: {t['runs_over_3x']}")
    broken_timings = work / "timings.csv"
    broken_timings.write_text("frame,segmentation_ms,features_ms,tracking_ms,local_mapping_ms,total_ms\n"
                              "0,0,1,1,0,2\n1,0,x,1,0,2\n")
    try:
        module.serial_times(broken_timings)
        fail("a timings.csv with 'x' for a time was read")
    except RuntimeError as e:
        check(f"{broken_timings}:3:" in str(e), f"the error does not name line 3: {e}")
    broken_timings.write_text("frame,total_ms\n0,2\n")
    try:
        module.serial_times(broken_timings)
        fail("a timings.csv without segmentation_ms was read")
    except RuntimeError as e:
        check(f"{broken_timings}:1:" in str(e) and "segmentation_ms" in str(e), f"the missing column: {e}")

    # An A/B of our own settings: one configuration, two variants, alternating within each round; the
    # variant's flags reach cge_slam (its summary.json says which RANSAC ran).
    out = work / "variants"
    done = spread("--runs", "2", "--configs", "none", "--variant", "a=", "--variant",
                  "b=--tracking-ransac-solver epnp", "--out", str(out))
    check(done.returncode == 0, f"the variant run failed: {done.stderr}")
    result = json.loads((out / "spread.json").read_text())
    names = [c["name"] for c in result["configurations"]]
    check(names == ["--mode none [a]", "--mode none [b]"], f"variant configurations {names}")
    for config, solver in zip(result["configurations"], ("rigid", "epnp")):
        for run in config["runs"]:
            summary = json.loads((Path(run["out"]) / "summary.json").read_text())
            check(summary["mapping_settings"]["tracking_ransac_solver"] == solver,
                  f"{config['name']}: ran {summary['mapping_settings']['tracking_ransac_solver']}, expected {solver}")
            check(summary["mode"] == "none", f"{config['name']}: mode {summary['mode']}")
        check_times(config)
    for label in ("a", "b"):
        check((out / "runs" / f"none_{label}_1").is_dir() and (out / "runs" / f"none_{label}_2").is_dir(),
              f"the runs of variant {label} are not in runs/none_{label}_1 and _2")
    check("| cge_slam --mode none [b] | 2 |" in (out / "spread.txt").read_text(), "spread.txt has no row for variant b")

    # The depth_sigma family, three runs of each configuration: the even grid over 0.9 .. 1.1 is
    # 0.9, 1.0, 1.1; the default (1.0) runs first.
    out = work / "spread"
    done = spread("--family", "depth_sigma", "--runs", "3", "--jobs", "2", "--out", str(out))
    check(done.returncode == 0, f"the depth_sigma run failed: {done.stderr}")
    result = json.loads((out / "spread.json").read_text())
    check(result["family"] == "depth_sigma", f"family {result.get('family')}")
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
        check_statistics(out, config, ates, keyframes)
    check("| ORB-SLAM2 |" not in (out / "spread.txt").read_text(), "a peer row without --orbslam2")
    print("ate_spread.py: arguments, offsets, weights and statistics as expected")
    return 0


if __name__ == "__main__":
    sys.exit(main())
