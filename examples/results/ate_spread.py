#!/usr/bin/env python3
"""ATE spread of cge_slam on a TUM folder over a family of runs, beside ORB-SLAM2's run-to-run spread.

Our pipeline is deterministic, so one run is one draw: on the real fr1/rpy slice a small change to
the input or to a setting with no true value moves mode YMK's ATE by several millimetres
(docs/REAL_DATA.md). ORB-SLAM2 is not deterministic (three threads), so its runs differ by themselves.
This script compares the two as distributions, over one of two families (--family):
- start_offset (default): round i starts both systems i frames into the sequence (rgb.txt and
  depth.txt cut, everything else linked, under OUT/datasets/); the same input for both, and a
  perturbation of the whole run (the first keyframe, every interval's phase);
- depth_sigma: our runs at the default and at other weights of the tracking refinement's depth term
  (--tracking-depth-sigma), spread evenly over 0.9x .. 1.1x of the run's own default (1/bf from
  camera.yaml on TUM data; read back from the default run's summary.json); the peer on the whole
  sequence each round. A milder perturbation: on the real slice it shows about half the spread.
Rounds alternate on the machine: round i runs the peer once, then every configuration (round 1: the
whole sequence at the default).

Usage:
  ate_spread.py --tools build/examples --dataset ../shared/data/tum_fr1_rpy_300 --out DIR
                [--family start_offset|depth_sigma] [--model ../shared/models/yolov8n-seg-320.onnx]
                [--orbslam2 PEER_DIR [--orbslam2-run run.sh]] [--runs 9] [--jobs 1] [--force]
                [--configs none,ymk,ymk_yolo,ymk_yolo_all] [--variant LABEL=FLAGS ...]
An A/B comparison of our own settings: --variant a= --variant b="--tracking-ransac-solver epnp" runs
every chosen configuration once per variant, with the variant's flags added, alternating within
each round (configuration 1 a, configuration 1 b, configuration 2 a, ...).
Writes DIR/spread.json (every run) and DIR/spread.txt (the tables, in Markdown), and prints the
tables: ATE and keyframes, then time per frame. Our time per frame is the serial total of every stage
but the segmentation network (timings.csv's total_ms - segmentation_ms): features, dynamic filter,
tracking, keyframe decision, local mapping, loop closing; its median over the frames of a run is set
beside the median TrackRGBD time of the peer's run in the same round (ORB extraction, tracking and
the keyframe decision; its local mapping and loop closing run in threads of their own). The 95th
percentile interpolates linearly between the order statistics. Exit code 2 for bad arguments
(named), 1 when a run fails or leaves a timings.csv that cannot be read (file and line named).
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import re
import shlex
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_peer  # noqa: E402  (beside this script)

LOWEST, HIGHEST = 0.9, 1.1  # the depth_sigma family's weights, as multiples of the default
FAMILIES = ("start_offset", "depth_sigma")
ASSOCIATION_GAP_S = 0.02  # TUM's associate.py: a depth frame pairs with a colour frame within this gap


class UsageError(Exception):
    pass


def configurations(model: Path | None) -> list[tuple[str, str, list[str]]]:
    """(folder name, shown name, cge_slam flags): the modes of the real-data targets, and YMK with
    YOLOv8-seg (our default, people only in the keyframe rule's semantic terms, and the paper's rule,
    --semantic-instances all) when a model is given."""
    configs = [("none", "--mode none", ["--mode", "none", "--segmentation", "none"]),
               ("ymk", "--mode YMK --segmentation none", ["--mode", "YMK", "--segmentation", "none"])]
    if model is not None:
        yolo = ["--mode", "YMK", "--segmentation", "yolo", "--model", str(model)]
        configs.append(("ymk_yolo", "--mode YMK --segmentation yolo", yolo))
        configs.append(("ymk_yolo_all", "the same, --semantic-instances all (the paper's rule)",
                        yolo + ["--semantic-instances", "all"]))
    return configs


CONFIG_KEYS = ("none", "ymk", "ymk_yolo", "ymk_yolo_all")
# Flags the script sets itself on every run of ours.
RESERVED_FLAGS = ("--dataset", "--out", "--force", "--tracking-depth-sigma")


def parse_variant(text: str) -> tuple[str, list[str]]:
    """LABEL=FLAGS -> (label, flags). Raises UsageError naming the problem."""
    label, sep, flags = text.partition("=")
    if not sep or not re.fullmatch(r"[A-Za-z0-9_.-]+", label):
        raise UsageError(f"--variant '{text}': give LABEL=FLAGS, LABEL of letters, digits, '_', '.', '-'")
    try:
        words = shlex.split(flags)
    except ValueError as e:
        raise UsageError(f"--variant '{text}': {e}") from None
    for word in words:
        if word.split("=")[0] in RESERVED_FLAGS:
            raise UsageError(f"--variant '{text}': {word.split('=')[0]} is set by the script")
    return label, words


def with_variants(configs: list[tuple[str, str, list[str]]], chosen: list[str] | None,
                  variants: list[tuple[str, list[str]]]) -> list[tuple[str, str, list[str]]]:
    """The chosen configurations (all when None), each once per variant (LABEL added to its folder
    key and its name, its flags after the configuration's), a configuration's variants adjacent."""
    picked = [c for c in configs if chosen is None or c[0] in chosen]
    if not variants:
        return picked
    return [(f"{key}_{label}", f"{name} [{label}]", flags + extra)
            for key, name, flags in picked for label, extra in variants]


def multipliers(runs: int) -> list[float]:
    """1.0 (the default) first, then the other points of an even grid of `runs` points over LOWEST ..
    HIGHEST (with an even count the grid misses 1.0, and its highest point is left out)."""
    if runs == 1:
        return [1.0]
    grid = [LOWEST + (HIGHEST - LOWEST) * i / (runs - 1) for i in range(runs)]
    others = [m for m in grid if not math.isclose(m, 1.0)]
    return [1.0] + others[:runs - 1]


def data_lines(path: Path) -> list[str]:
    return [line for line in path.read_text(encoding="utf-8").splitlines() if line.strip() and not line.startswith("#")]


def is_time_stamp(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def offset_dataset(dataset: Path, offset: int, folder: Path) -> Path:
    """`dataset` without its first `offset` colour frames. rgb.txt loses its first `offset` entries;
    depth.txt keeps the entries from ASSOCIATION_GAP_S before the first colour frame kept on, so the
    frames kept pair as before; every other entry of the folder is linked. Offset 0: `dataset` itself."""
    if offset == 0:
        return dataset
    folder.mkdir(parents=True, exist_ok=True)
    for entry in sorted(dataset.iterdir()):
        if entry.name not in ("rgb.txt", "depth.txt"):
            link = folder / entry.name
            if link.is_symlink() or link.exists():
                link.unlink()
            link.symlink_to(entry.resolve())

    def comments(path: Path) -> list[str]:
        return [line for line in path.read_text(encoding="utf-8").splitlines() if line.startswith("#")]

    rgb = data_lines(dataset / "rgb.txt")[offset:]
    first = float(rgb[0].split()[0])
    depth = [line for line in data_lines(dataset / "depth.txt") if float(line.split()[0]) >= first - ASSOCIATION_GAP_S]
    (folder / "rgb.txt").write_text("\n".join(comments(dataset / "rgb.txt") + rgb) + "\n", encoding="utf-8")
    (folder / "depth.txt").write_text("\n".join(comments(dataset / "depth.txt") + depth) + "\n", encoding="utf-8")
    return folder


def run_ours(tools: Path, dataset: Path, flags: list[str], sigma: str | None, out: Path) -> dict:
    argv = [str(tools / "cge_slam"), "--dataset", str(dataset), *flags, "--out", str(out), "--force"]
    if sigma is not None:
        argv += ["--tracking-depth-sigma", sigma]
    done = subprocess.run(argv, capture_output=True, text=True)
    if done.returncode != 0:
        tail = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise RuntimeError(f"{' '.join(argv)}: exit code {done.returncode}: {tail}")
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    ate = summary.get("ate") or {}
    if "rmse_m" not in ate:
        raise RuntimeError(f"{out}/summary.json: no ATE (does {dataset} have groundtruth.txt?)")
    run = {"tracking_depth_sigma": summary["mapping_settings"]["tracking_depth_sigma"],
           "frames": summary["frames"], "ate_rmse_m": ate["rmse_m"], "keyframes": summary["keyframes"],
           "out": str(out)}
    run.update(serial_times(out / "timings.csv"))
    return run


TIMED_STAGES = ("features", "tracking", "local_mapping")  # the stages reported on their own


def percentile(values: list[float], fraction: float) -> float:
    """Linear interpolation between the order statistics (numpy's default): position
    fraction * (n - 1) in the sorted values."""
    ordered = sorted(values)
    position = fraction * (len(ordered) - 1)
    low = math.floor(position)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (position - low)


def serial_times(timings: Path) -> dict:
    """From one run's timings.csv: the median and 95th percentile over frames of the serial total
    without the segmentation network (total_ms - segmentation_ms), their ratio, and the median of
    each of TIMED_STAGES. Raises RuntimeError naming the file (and line) when it cannot be read."""
    try:
        with open(timings, encoding="utf-8", newline="") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise RuntimeError(f"{timings}: {e.strerror}") from e
    if not rows:
        raise RuntimeError(f"{timings}: empty")
    header = rows[0]
    wanted = ["total_ms", "segmentation_ms"] + [f"{stage}_ms" for stage in TIMED_STAGES]
    missing = [name for name in wanted if name not in header]
    if missing:
        raise RuntimeError(f"{timings}:1: no column {', '.join(missing)}")
    column = {name: header.index(name) for name in wanted}
    totals: list[float] = []
    stages: dict[str, list[float]] = {stage: [] for stage in TIMED_STAGES}
    for number, row in enumerate(rows[1:], start=2):
        try:
            values = {name: float(row[index]) for name, index in column.items()}
        except (IndexError, ValueError):
            raise RuntimeError(f"{timings}:{number}: expected {len(header)} numbers, got '{','.join(row)}'") from None
        if not all(math.isfinite(v) and v >= 0 for v in values.values()):
            raise RuntimeError(f"{timings}:{number}: a time is negative or not finite")
        totals.append(values["total_ms"] - values["segmentation_ms"])
        for stage in TIMED_STAGES:
            stages[stage].append(values[f"{stage}_ms"])
    if not totals:
        raise RuntimeError(f"{timings}: no frames")
    median = statistics.median(totals)
    p95 = percentile(totals, 0.95)
    return {"total_median_ms": median, "total_p95_ms": p95, "p95_over_median": p95 / median if median > 0 else None,
            "stage_median_ms": {stage: statistics.median(v) for stage, v in stages.items()}}


def time_summary(runs: list[dict], peer_runs: list[dict] | None) -> dict:
    """Over one configuration's runs: the spread of the median serial total and of p95 / median,
    runs whose p95 is over 3x their median, and, when the peer ran, each round's ratio of our
    median to the peer's TrackRGBD median in the same round (rounds without a peer time left out)
    and the rounds where ours is the slower."""
    summary = {"total_median_ms": results_peer.spread([r.get("total_median_ms") for r in runs]),
               "p95_over_median": results_peer.spread([r.get("p95_over_median") for r in runs]),
               "runs_over_3x": sum(1 for r in runs if (r.get("p95_over_median") or 0) > 3),
               "stage_median_ms": {stage: results_peer.spread([r.get("stage_median_ms", {}).get(stage) for r in runs])
                                   for stage in TIMED_STAGES}}
    if peer_runs is not None:
        ratios = []
        for ours, peer in zip(runs, peer_runs):
            theirs = peer.get("track_median_ms")
            if isinstance(theirs, (int, float)) and theirs > 0 and isinstance(ours.get("total_median_ms"), float):
                ratios.append(ours["total_median_ms"] / theirs)
        summary["over_peer_median"] = results_peer.spread(ratios)
        summary["rounds_compared"] = len(ratios)
        summary["rounds_over"] = sum(1 for r in ratios if r > 1)
    return summary


def describe(result: dict) -> str:
    """One sentence on the family a result was measured over, for reports."""
    if result.get("family", "depth_sigma") == "start_offset":
        first, last = result.get("start_offsets", [0, result["runs"] - 1])
        peer = " and ORB-SLAM2" if result.get("orbslam2") else ""
        return (f"round i starts every configuration{peer} i frames into the sequence ({first} .. {last} frames "
                "skipped), so the runs of a round see the same input")
    low, high = result.get("weights", [LOWEST, HIGHEST])
    sigma = result.get("default_tracking_depth_sigma")
    shown = f" {sigma:.4g} 1/m" if isinstance(sigma, (int, float)) else ""
    return (f"our runs at the default and at other weights of the tracking's depth term "
            f"(`--tracking-depth-sigma`, evenly over {low:g}x-{high:g}x of the default{shown})")


def table(result: dict) -> str:
    peer = result.get("orbslam2")
    peer_mean = peer["ate_rmse_m"]["mean"] if peer and peer.get("ate_rmse_m") else None
    lines = ["| system | runs | ATE RMSE mean | sd | min - max | mean / ORB-SLAM2's | keyframes mean (min - max) |",
             "|---|---|---|---|---|---|---|"]

    def row(name: str, ate: dict, keyframes: dict) -> str:
        ratio = f"{ate['mean'] / peer_mean:.2f}x" if peer_mean else "-"
        return (f"| {name} | {ate['count']} | {1000 * ate['mean']:.1f} mm | {1000 * ate['sd']:.1f} mm | "
                f"{1000 * ate['min']:.1f} - {1000 * ate['max']:.1f} mm | {ratio} | "
                f"{keyframes['mean']:.1f} ({keyframes['min']:g} - {keyframes['max']:g}) |")

    if peer_mean:
        lines.append(row("ORB-SLAM2", peer["ate_rmse_m"], peer["keyframes"]))
    for config in result["configurations"]:
        lines.append(row(f"cge_slam {config['name']}", config["ate_rmse_m"], config["keyframes"]))
    return "\n".join(lines) + "\n"


def time_table(result: dict) -> str:
    """Time per frame, one row per configuration (and the peer's TrackRGBD median when it ran)."""
    peer = result.get("orbslam2")
    peer_times = results_peer.spread([r.get("track_median_ms") for r in peer["runs"]]) if peer else None

    def span(s: dict | None, digits: int = 1, unit: str = " ms") -> str:
        return f"{s['min']:.{digits}f}-{s['max']:.{digits}f}{unit}" if s else "-"

    lines = ["| system | serial total median | / ORB-SLAM2's TrackRGBD median, mean (min - max) | rounds over | "
             "p95 / median | runs over 3x | features median | tracking median | local mapping median |",
             "|---|---|---|---|---|---|---|---|---|"]
    if peer_times:
        lines.append(f"| ORB-SLAM2 (TrackRGBD) | {span(peer_times)} | 1.00x | - | - | - | - | - | - |")
    for config in result["configurations"]:
        t = config["time"]
        ratio = t.get("over_peer_median")
        ratio_cell = f"{ratio['mean']:.2f}x ({ratio['min']:.2f}-{ratio['max']:.2f})" if ratio else "-"
        over = f"{t['rounds_over']} of {t['rounds_compared']}" if ratio else "-"
        stages = [span(t["stage_median_ms"][stage]) for stage in TIMED_STAGES]
        lines.append(f"| cge_slam {config['name']} | {span(t['total_median_ms'])} | {ratio_cell} | {over} | "
                     f"{span(t['p95_over_median'], 2, '')} | {t['runs_over_3x']} | {' | '.join(stages)} |")
    return "\n".join(lines) + "\n"


def parse_arguments(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tools", required=True, type=Path, help="folder with cge_slam and cge_eval")
    parser.add_argument("--dataset", required=True, type=Path, help="TUM folder with groundtruth.txt")
    parser.add_argument("--out", required=True, type=Path, help="output folder (runs/, spread.json, spread.txt)")
    parser.add_argument("--family", choices=FAMILIES, default=FAMILIES[0],
                        help="start_offset: round i starts i frames in (default); depth_sigma: round i at another "
                             "weight of the tracking's depth term")
    parser.add_argument("--model", type=Path, help="YOLOv8-seg ONNX model: adds the two YMK yolo configurations")
    parser.add_argument("--orbslam2", type=Path, help="the folder the peer kit's build.sh made")
    parser.add_argument("--orbslam2-run", type=Path, default=results_peer.DEFAULT_RUN_SCRIPT, help="the peer kit's run.sh")
    parser.add_argument("--runs", type=int, default=9, help="runs per configuration (and of the peer), 1 .. 50")
    # One at a time by default: our times are serial per-frame times, and two of our runs at once
    # share the machine's caches and memory while the peer runs alone.
    parser.add_argument("--jobs", type=int, default=1, help="our runs at once within a round, 1 .. 16")
    parser.add_argument("--force", action="store_true", help="write into a non-empty --out")
    parser.add_argument("--configs", help=f"comma-separated subset of {','.join(CONFIG_KEYS)} (default: all; the "
                                          "two yolo ones need --model)")
    parser.add_argument("--variant", action="append", default=[], metavar="LABEL=FLAGS",
                        help="run each configuration once per variant, with FLAGS (cge_slam's) added; repeatable")
    args = parser.parse_args(argv)
    args.variants = [parse_variant(v) for v in args.variant]
    labels = [label for label, _ in args.variants]
    if len(set(labels)) != len(labels):
        raise UsageError(f"--variant: the labels {labels} repeat one")
    args.chosen = None
    if args.configs is not None:
        args.chosen = [c.strip() for c in args.configs.split(",") if c.strip()]
        unknown = [c for c in args.chosen if c not in CONFIG_KEYS]
        if unknown or not args.chosen:
            raise UsageError(f"--configs {args.configs}: give a comma-separated subset of {', '.join(CONFIG_KEYS)}")
        if args.model is None and any(c.startswith("ymk_yolo") for c in args.chosen):
            raise UsageError(f"--configs {args.configs}: the yolo configurations need --model")
    if not 1 <= args.runs <= 50:
        raise UsageError(f"--runs {args.runs}: give 1 .. 50")
    if not 1 <= args.jobs <= 16:
        raise UsageError(f"--jobs {args.jobs}: give 1 .. 16")
    for tool in ("cge_slam", "cge_eval"):
        if not (args.tools / tool).is_file():
            raise UsageError(f"--tools {args.tools}: no {tool} there (build the project first)")
    for name in ("rgb.txt", "depth.txt", "groundtruth.txt"):
        if not (args.dataset / name).is_file():
            raise UsageError(f"--dataset {args.dataset}: no {name} (a TUM RGB-D folder with ground truth)")
    if args.family == "start_offset":
        for name in ("rgb.txt", "depth.txt"):  # offset_dataset reads their time stamps
            path = args.dataset / name
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
                if line.strip() and not line.startswith("#") and not is_time_stamp(line.split()[0]):
                    raise UsageError(f"{path}:{number}: '{line.split()[0]}' is not a time stamp in seconds")
        frames = len(data_lines(args.dataset / "rgb.txt"))
        if args.runs - 1 > frames // 2:
            raise UsageError(f"--runs {args.runs}: the start_offset family would skip up to {args.runs - 1} of the "
                             f"{frames} frames of {args.dataset / 'rgb.txt'}; give at most {frames // 2 + 1} runs")
    if args.model is not None and not args.model.is_file():
        raise UsageError(f"--model {args.model}: not found")
    if args.orbslam2 is not None:
        problem = results_peer.check_peer(args.orbslam2.resolve(), args.orbslam2_run.resolve())
        if problem:
            raise UsageError(problem)
    if args.out.exists() and (not args.out.is_dir() or (any(args.out.iterdir()) and not args.force)):
        raise UsageError(f"--out {args.out}: exists and is not an empty folder (give --force to write into it)")
    return args


def main(argv: list[str]) -> int:
    try:
        args = parse_arguments(argv)
    except UsageError as e:
        print(f"ate_spread.py: {e}", file=sys.stderr)
        return 2
    tools, dataset = args.tools.resolve(), args.dataset.resolve()
    configs = with_variants(configurations(args.model.resolve() if args.model else None), args.chosen, args.variants)
    peer = (results_peer.Peer(args.orbslam2.resolve(), args.orbslam2_run.resolve())
            if args.orbslam2 is not None else None)
    runs_dir = args.out / "runs"
    runs_dir.mkdir(parents=True, exist_ok=True)
    by_offset = args.family == "start_offset"

    def evaluate(kind: str, estimate: Path) -> dict:
        done = subprocess.run([str(tools / "cge_eval"), kind, str(dataset / "groundtruth.txt"), str(estimate),
                               "--json"], capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(done.stderr)
        return json.loads(done.stdout)

    ours: dict[str, list[dict]] = {name: [] for _, name, _ in configs}
    peer_runs: list[dict] = []
    default_sigma = None
    try:
        for i, m in enumerate(multipliers(args.runs)):
            offset = i if by_offset else 0
            data = offset_dataset(dataset, offset, args.out / "datasets" / f"offset_{offset}")
            if peer is not None:
                out = runs_dir / f"orbslam2_{i + 1}"
                results_peer.run_peer(peer, data, out)
                peer_run = results_peer.read_peer_run(out, evaluate)
                peer_run["start_offset"] = offset
                peer_runs.append(peer_run)
            sigma = None if i == 0 or by_offset else f"{default_sigma * m:.6g}"
            tasks = [(name, flags, runs_dir / f"{key}_{i + 1}") for key, name, flags in configs]
            with ThreadPoolExecutor(max_workers=args.jobs) as pool:
                done = list(pool.map(lambda t: run_ours(tools, data, t[1], sigma, t[2]), tasks))
            for (name, _, _), run in zip(tasks, done):
                run["start_offset"] = offset
                run["multiplier"] = 1.0 if by_offset else m
                ours[name].append(run)
            if i == 0:
                default_sigma = done[0]["tracking_depth_sigma"]
            print(f"round {i + 1}: start offset {offset}, tracking depth sigma {done[0]['tracking_depth_sigma']:g}: " +
                  ", ".join(f"{name} {1000 * r['ate_rmse_m']:.1f} mm" for (name, _, _), r in zip(tasks, done)),
                  flush=True)
    except RuntimeError as e:
        print(f"ate_spread.py: {e}", file=sys.stderr)
        return 1

    result = {"dataset": str(args.dataset), "runs": args.runs, "family": args.family,
              "default_tracking_depth_sigma": default_sigma, "configurations": []}
    if by_offset:
        result["start_offsets"] = [0, args.runs - 1]
    else:
        result["weights"] = [LOWEST, HIGHEST]
    for _, name, flags in configs:
        runs = ours[name]
        result["configurations"].append({
            "name": name, "flags": flags, "runs": runs,
            "ate_rmse_m": results_peer.spread([r["ate_rmse_m"] for r in runs]),
            "keyframes": results_peer.spread([r["keyframes"] for r in runs]),
            "time": time_summary(runs, peer_runs if peer is not None else None)})
    if peer is not None:
        good = [r for r in peer_runs if "error" not in r]
        result["orbslam2"] = {"runs": peer_runs, "failed": len(peer_runs) - len(good)}
        if good:
            result["orbslam2"]["ate_rmse_m"] = results_peer.spread([r["ate_rmse_m"] for r in good])
            result["orbslam2"]["keyframes"] = results_peer.spread([r["keyframes"] for r in good])
    text = table(result) + "\n" + time_table(result)
    (args.out / "spread.json").write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    (args.out / "spread.txt").write_text(text, encoding="utf-8")
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
