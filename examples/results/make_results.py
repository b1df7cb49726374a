#!/usr/bin/env python3
"""Regenerates docs/RESULTS.md: the paper's tables and figures, measured on the synthetic presets.

Renders every synthetic preset with a fixed seed (cge_sim), runs every mode of the reference
pipeline on it (cge_slam), evaluates the runs (cge_eval), studies the entropy measures on the loop
scenes (cge_loop_study), and writes RESULTS.md with its PNG figures. Given the ORB-SLAM2 peer
(--orbslam2, the folder the peer kit's build.sh made), it also runs the original ORB-SLAM2 on the
walking and sitting presets and on the real TUM slice, alternating with our runs where times are
compared. On the real slice it also measures the ATE over families of runs (ate_spread.py), since
one run of our deterministic pipeline is one draw. The suite only calls the command-line tools and
reads the files they write, so every number here can be reproduced by hand with the commands
listed in RESULTS.md.

Usage (docs/RESULTS.md):
    make_results.py --tools BUILD/examples --out docs [--work BUILD/results] [--quick]
                    [--orbslam2 PEER_DIR [--orbslam2-run run.sh] [--orbslam2-runs 3]] [--real-data DIR|none]
                    [--spread-runs 9]

--quick runs short sequences: it checks that the suite works (CI), its numbers mean little.
Exit codes: 0 success, 1 a tool failed (its command and message are printed), 2 bad arguments.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import platform
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import ate_spread  # noqa: E402  (beside this file)
import results_peer  # noqa: E402
import results_stamps  # noqa: E402
import results_plots  # noqa: E402
import results_report  # noqa: E402

# The peer kit and the real TUM slice live beside the project, in ../shared, when it is there.
PROJECT_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_REAL_DATA = PROJECT_ROOT.parent / "shared" / "data" / "tum_fr1_rpy_300"

WALKING_PRESETS = ["walking_xyz", "walking_halfsphere", "walking_rpy", "walking_static"]
LOW_DYNAMIC_PRESETS = ["sitting_xyz"]
TRAJECTORY_PRESETS = WALKING_PRESETS + LOW_DYNAMIC_PRESETS  # every mode runs on these
# The real slice has no people and no masks: our pipeline without dynamic handling, and YMK with
# segmentation none (only the keyframe selector acts), as docs/REAL_DATA.md runs it.
REAL_DATA_MODES = ["none", "YMK"]
# Per-frame stages of cge_slam that ORB-SLAM2's TrackRGBD also covers (ORB extraction, tracking,
# the keyframe decision); its local mapping and loop closing run in threads of their own.
TRACKING_STAGES = ["features", "dynamic_filter", "tracking", "keyframe"]
LOOP_PRESETS = ["loop_dynamic", "loop_structure_change"]
MODES = ["none", "Y", "YM", "YMK"]
# Loop scorings compared in Table 6: BoW only (ORB-SLAM2-like), the paper's CGE ranking, ours.
LOOP_SCORINGS = ["bow_only", "cge", "combined"]


@dataclass(frozen=True)
class Plan:
    """Sequence lengths and seeds of one suite run."""

    walking_frames: int
    loop_frames: int  # the loop scenes' length: 751 frames hold their 8 revisits (docs/SIMULATION.md)
    vocabulary_frames: int
    study_step: int  # every study_step-th frame of a loop scene enters the entropy study
    seed: int = 1


FULL = Plan(walking_frames=300, loop_frames=751, vocabulary_frames=20, study_step=3)
QUICK = Plan(walking_frames=30, loop_frames=91, vocabulary_frames=5, study_step=6)


class ToolError(RuntimeError):
    pass


class Runner:
    """Runs the tools, logs every command (the log is part of the results) and times the steps."""

    def __init__(self, tools: Path, work: Path, verbose: bool):
        self.tools = tools
        self.work = work
        self.verbose = verbose
        self.commands: list[str] = []
        # (absolute prefix, as shown) for the command log: the work folder is shown relative.
        self.aliases: list[tuple[str, str]] = [(str(work) + "/", "")]
        self.reuse = False  # --reuse: read back runs an earlier suite run made with the same tools and inputs
        self.reused: list[str] = []
        self.rendered: set[Path] = set()

    def shown(self, argv: list[str]) -> str:
        text = " ".join(argv)
        for prefix, alias in self.aliases:
            text = text.replace(prefix, alias)
        return text

    def log(self, shown: str, log: list[str] | None = None) -> None:
        (self.commands if log is None else log).append(shown)
        if self.verbose:
            print(f"  $ {shown}", flush=True)

    def tool(self, name: str) -> str:
        path = self.tools / name
        if not path.is_file() or not os.access(path, os.X_OK):
            raise ToolError(f"{path}: not found or not executable (build the tools first)")
        return str(path)

    def run(self, name: str, *args: str, capture_json: bool = False, log: list[str] | None = None) -> dict | str:
        """Runs one tool; its command goes to `log` (a parallel task's own list) or the runner's."""
        argv = [self.tool(name), *map(str, args)]
        self.log(self.shown([name, *map(str, args)]), log)
        result = subprocess.run(argv, capture_output=True, text=True)
        if result.returncode != 0:
            tail = "\n".join(result.stderr.strip().splitlines()[-15:])
            raise ToolError(f"command failed with exit code {result.returncode}: {' '.join(argv)}\n{tail}")
        if capture_json:
            return json.loads(result.stdout)
        return result.stdout

    def parallel(self, tasks: list, jobs: int) -> list:
        """Runs independent tasks (each takes its command log) `jobs` at a time; every tool is single
        threaded, so each run has a core of its own. Results and the command log keep the tasks'
        order whatever order they finish in; the first failure (in task order) is raised."""
        logs: list[list[str]] = [[] for _ in tasks]
        with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
            futures = [pool.submit(task, log) for task, log in zip(tasks, logs)]
            results = [f.result() for f in futures]
        for log in logs:
            self.commands.extend(log)
        return results


def name_value_lines(text: str) -> dict[str, float]:
    """Parses the tools' `name value` lines (numbers only; other lines are ignored)."""
    values = {}
    for line in text.splitlines():
        parts = line.split()
        if len(parts) == 2:
            try:
                values[parts[0]] = float(parts[1])
            except ValueError:
                pass
    return values


def read_json(path: Path) -> dict:
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def read_csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def render(runner: Runner, preset: str, frames: int, seed: int) -> Path:
    """Renders a preset once; a folder an earlier suite run rendered with the same cge_sim and
    arguments is reused (the renderer is deterministic: same arguments, same bytes)."""
    out = runner.work / "sequences" / f"{preset}_{frames}_s{seed}"
    args = ["--preset", preset, "--frames", str(frames), "--seed", str(seed), "--out", str(out), "--force"]
    if out in runner.rendered:
        return out
    stamp = results_stamps.make(Path(runner.tool("cge_sim")), args, [])
    if results_stamps.matches(out, stamp) and (out / "rgb.txt").is_file():
        runner.log(runner.shown(["cge_sim", *args]))
    else:
        runner.run("cge_sim", *args)
        results_stamps.write(out, stamp)
    runner.rendered.add(out)
    return out


def slam(runner: Runner, log: list[str], sequence: Path, out: Path, *flags: str) -> dict:
    """One cge_slam run; with --reuse, a run an earlier suite run made with the same cge_slam, arguments
    and inputs is read back instead."""
    args = ["--dataset", str(sequence), "--out", str(out), "--force", *map(str, flags)]
    inputs = [sequence] + [Path(str(f)) for f in flags
                           if Path(str(f)).is_absolute() and Path(str(f)).is_file()]  # e.g. the vocabulary
    stamp = results_stamps.make(Path(runner.tool("cge_slam")), args, inputs)
    if runner.reuse and results_stamps.matches(out, stamp) and (out / "summary.json").is_file():
        shown = runner.shown(["cge_slam", *args])
        runner.log(shown, log)
        runner.reused.append(shown)
        return read_json(out / "summary.json")
    runner.run("cge_slam", *args, log=log)
    results_stamps.write(out, stamp)
    return read_json(out / "summary.json")


def walking_runs(runner: Runner, plan: Plan, jobs: int) -> dict:
    """Every walking and sitting preset in every mode; maps and aligned trajectories for the figures."""
    sequences = {preset: render(runner, preset, plan.walking_frames, plan.seed) for preset in TRAJECTORY_PRESETS}

    def one(preset: str, mode: str, log: list[str]) -> dict:
        sequence = sequences[preset]
        out = runner.work / "runs" / preset / mode
        map_flags = ["--map"] if preset == "walking_xyz" else []
        summary = slam(runner, log, sequence, out, "--mode", mode, "--seed", str(plan.seed), *map_flags)
        run = {"summary": summary}
        aligned = out / "aligned.csv"
        runner.run("cge_eval", "ate", sequence / "groundtruth.txt", out / "trajectory.txt", "--aligned-out", aligned,
                   "--force", log=log)
        run["aligned"] = read_csv(aligned)
        if map_flags:
            run["map_eval"] = runner.run("cge_eval", "map", out / "map.ot", "--sequence", sequence, "--trajectory",
                                         out / "trajectory.txt", "--keyframes", out / "keyframes.txt", "--json",
                                         capture_json=True, log=log)
        return run

    keys = [(preset, mode) for preset in TRAJECTORY_PRESETS for mode in MODES]
    runs = dict(zip(keys, runner.parallel([partial(one, *key) for key in keys], jobs)))
    for (preset, mode), run in runs.items():
        print(f"  {preset:20s} {mode:4s} ate {fmt_m(run['summary'].get('ate', {}).get('rmse_m'))}", flush=True)
    return runs


def median(values: list[float]) -> float | None:
    ordered = sorted(values)
    n = len(ordered)
    if n == 0:
        return None
    return ordered[n // 2] if n % 2 else 0.5 * (ordered[n // 2 - 1] + ordered[n // 2])


def tracking_median_ms(timings: Path) -> float | None:
    """Median over frames of the TRACKING_STAGES' summed time per frame (timings.csv)."""
    per_frame = [sum(float(row[f"{stage}_ms"]) for stage in TRACKING_STAGES) for row in read_csv(timings)]
    return median(per_frame)


def our_timed_run(runner: Runner, log: list[str], dataset: Path, out: Path, mode: str, flags: list[str]) -> dict:
    runner.run("cge_slam", "--dataset", dataset, "--out", out, "--force", "--mode", mode, *flags, log=log)
    summary = read_json(out / "summary.json")
    return {"summary": summary, "tracking_median_ms": tracking_median_ms(out / "timings.csv"),
            "total_median_ms": summary.get("stages", {}).get("total", {}).get("median_ms"),
            "trajectory": (out / "trajectory.txt").read_bytes()}


def peer_run(runner: Runner, peer: results_peer.Peer, dataset: Path, out: Path, log: list[str] | None = None) -> dict:
    """One ORB-SLAM2 run, read back and evaluated; a failed run is recorded, not raised."""
    argv = ["bash", str(peer.run_script), str(dataset), str(out)]
    runner.log("ORB_PEER=PEER " + runner.shown(argv), log)
    _, result = results_peer.run_peer(peer, dataset, out)
    if result.returncode != 0:
        tail = (result.stderr.strip().splitlines() or ["no message"])[-1]
        return {"error": f"run.sh exit {result.returncode}: {tail}"}

    def evaluate(kind: str, estimate: Path) -> dict:
        return runner.run("cge_eval", kind, dataset / "groundtruth.txt", estimate, "--json", capture_json=True,
                          log=log)

    return results_peer.read_peer_run(out, evaluate)


def compare_on(runner: Runner, peer: results_peer.Peer | None, rounds: int, name: str, folder: Path,
               modes: list[str], flags: list[str], grid_trajectories: dict[str, Path], commands: list[str]) -> dict:
    """Rounds of (ORB-SLAM2, then ours in each mode) on one sequence; with --reuse, the rounds an earlier
    suite run made with the same tools and inputs are read back instead (they were measured together)."""
    folder_out = runner.work / "runs" / name
    folder_out.mkdir(parents=True, exist_ok=True)
    extra = {"rounds": rounds, "modes": modes, "flags": flags,
             "grid": {m: results_stamps.file_digest(p) for m, p in grid_trajectories.items() if p.is_file()}}
    inputs = [folder]
    if peer is not None:
        extra["peer"] = {"rgbd_tum": results_stamps.file_digest(peer.folder / results_peer.RGBD_TUM),
                         "run.sh": results_stamps.file_digest(peer.run_script)}
        inputs += sorted(peer.folder.glob("*.txt"))  # its vocabulary
    stamp = results_stamps.make(Path(runner.tool("cge_slam")), [name], inputs, extra)
    saved = folder_out / "compared.json"
    if runner.reuse and results_stamps.matches(folder_out, stamp) and saved.is_file():
        result = read_json(saved)
        commands.extend(result["commands"])
        runner.reused.append(f"{name}: ORB-SLAM2 and our timed rounds")
        print(f"  {name:20s} reused (same tools and inputs)", flush=True)
        return result
    log: list[str] = []
    peer_results, ours = [], {m: [] for m in modes}
    for i in range(1, rounds + 1):
        if peer is not None:
            run = peer_run(runner, peer, folder, folder_out / f"orbslam2_{i}", log)
            peer_results.append(run)
            print(f"  {name:20s} ORB-SLAM2 run {i}: " + (run["error"] if "error" in run else
                  f"ate {fmt_m(run.get('ate_rmse_m'))}, {run.get('keyframes')} keyframes, TrackRGBD median "
                  f"{run.get('track_median_ms', float('nan')):.1f} ms"), flush=True)
        for mode in modes:
            ours[mode].append(our_timed_run(runner, log, folder, folder_out / f"timed_{mode}_{i}", mode, flags))
    result = {"peer": {"runs": peer_results, "summary": results_peer.summarise(peer_results)}
              if peer is not None else None, "ours": {}, "commands": log}
    for mode in modes:
        timed = ours[mode]
        reference = timed[0]["trajectory"]
        same = all(t["trajectory"] == reference for t in timed)
        if mode in grid_trajectories:
            same = same and grid_trajectories[mode].read_bytes() == reference
        for t in timed:
            del t["trajectory"]  # bytes only for the check above
        result["ours"][mode] = {"runs": timed, "same_trajectory": same, "summary": timed[0]["summary"]}
    saved.write_text(json.dumps(result), encoding="utf-8")
    results_stamps.write(folder_out, stamp)
    commands.extend(log)
    return result


def compared_runs(runner: Runner, plan: Plan, peer: results_peer.Peer | None, peer_runs: int,
                  real_data: Path | None, jobs: int) -> dict:
    """ORB-SLAM2 and our pipeline on the same sequences, alternating on each sequence (peer, then ours,
    per round), so that both see the same machine load when their times are compared; `jobs`
    sequences at a time. Ours is deterministic: its repeated runs differ only in time, which
    `same_trajectory` checks, against the table runs too."""
    datasets = []  # (name, folder, our modes, our extra flags)
    if peer is not None:
        for preset in TRAJECTORY_PRESETS:
            datasets.append((preset, render(runner, preset, plan.walking_frames, plan.seed), ["YMK"],
                             ["--seed", str(plan.seed)]))
    if real_data is not None:
        datasets.append((real_data.name, real_data, REAL_DATA_MODES, ["--segmentation", "none", "--seed",
                                                                      str(plan.seed)]))
    rounds = peer_runs if peer is not None else 1
    result: dict = {"peer": {}, "ours": {}, "rounds": rounds}
    tasks = []
    for name, folder, modes, flags in datasets:
        grid = {m: runner.work / "runs" / name / m / "trajectory.txt" for m in modes
                if name in TRAJECTORY_PRESETS}
        tasks.append(partial(compare_on, runner, peer, rounds, name, folder, modes, flags, grid))
    for (name, _, _, _), one in zip(datasets, runner.parallel(tasks, jobs)):
        if one["peer"] is not None:
            result["peer"][name] = one["peer"]
        for mode, entry in one["ours"].items():
            result["ours"][(name, mode)] = entry
    return result


def real_data_spread(runner: Runner, real_data: Path, peer: results_peer.Peer | None, runs: int,
                     jobs: int) -> dict:
    """ate_spread.py on the real slice: our modes none and YMK and ORB-SLAM2 over its default family
    (start offsets), alternating round by round (a single run of ours is a single draw)."""
    out = runner.work / "spread"
    argv = ["--tools", str(runner.tools), "--dataset", str(real_data), "--out", str(out), "--runs", str(runs),
            "--jobs", str(jobs), "--force"]
    if peer is not None:
        argv += ["--orbslam2", str(peer.folder), "--orbslam2-run", str(peer.run_script)]
    shown = [a.replace(str(runner.tools), "BUILD/examples") for a in argv]  # as the other tools are shown
    runner.log(runner.shown(["python3", "examples/results/ate_spread.py", *shown]))
    if ate_spread.main(argv) != 0:
        raise ToolError(f"ate_spread.py {' '.join(argv)} failed (its message is above)")
    return json.loads((out / "spread.json").read_text(encoding="utf-8"))


def loop_runs(runner: Runner, plan: Plan, vocabulary: Path, jobs: int) -> dict:
    """Each loop scene with each loop scoring (mode YMK, pose graph + bundle adjustment), and the
    precision-recall curve over the acceptance threshold of each run's accepted loops."""
    sequences = {preset: render(runner, preset, plan.loop_frames, plan.seed) for preset in LOOP_PRESETS}

    def one(preset: str, scoring: str, log: list[str]) -> dict:
        sequence = sequences[preset]
        out = runner.work / "runs" / preset / scoring
        summary = slam(runner, log, sequence, out, "--mode", "YMK", "--seed", str(plan.seed), "--vocabulary",
                       vocabulary, "--loop-scoring", scoring, "--loop-correction", "pgo+ba")
        evaluation = runner.run("cge_eval", "loops", sequence / "loops.txt", out / "loops.csv", "--json",
                                capture_json=True, log=log)
        score_column = "bow_score" if scoring == "bow_only" else "cge_score"
        curve_file = out / "pr_curve.csv"
        runner.run("cge_eval", "loops", sequence / "loops.txt", out / "loops.csv", "--score", score_column,
                   "--curve", curve_file, "--force", log=log)
        return {"summary": summary, "loops": evaluation, "curve": read_csv(curve_file)}

    keys = [(preset, scoring) for preset in LOOP_PRESETS for scoring in LOOP_SCORINGS]
    runs = dict(zip(keys, runner.parallel([partial(one, *key) for key in keys], jobs)))
    for (preset, scoring), run in runs.items():
        e = run["loops"]
        print(f"  {preset:22s} {scoring:9s} precision {e.get('precision')} query recall {e.get('query_recall')}",
              flush=True)
    return runs


def entropy_study(runner: Runner, plan: Plan, jobs: int) -> dict:
    sequences = {preset: render(runner, preset, plan.loop_frames, plan.seed) for preset in LOOP_PRESETS}

    def one(preset: str, log: list[str]) -> dict:
        out = runner.work / "study" / preset
        printed = runner.run("cge_loop_study", "--dataset", sequences[preset], "--out", out, "--force", "--step",
                             plan.study_step, log=log)
        return {"values": name_value_lines(str(printed)), "pairs": read_csv(out / "pairs.csv")}

    return dict(zip(LOOP_PRESETS, runner.parallel([partial(one, p) for p in LOOP_PRESETS], jobs)))


def fmt_m(value) -> str:
    return "n/a" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.4f} m"


def machine_description() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tools", required=True, type=Path, help="folder of the built tools (BUILD/examples)")
    parser.add_argument("--out", required=True, type=Path,
                        help="where RESULTS.md and results/*.png are written (docs/ for the published ones)")
    parser.add_argument("--work", type=Path, help="scratch folder for sequences and runs (default: OUT/../results-work)")
    parser.add_argument("--quick", action="store_true", help="short sequences: checks the suite, not the method")
    parser.add_argument("--jobs", type=int, default=min(os.cpu_count() or 1, 4),
                        help="tool runs at a time (each is single threaded; default: cores, at most 4)")
    parser.add_argument("--verbose", action="store_true", help="print every command")
    parser.add_argument("--orbslam2", type=Path, metavar="PEER_DIR",
                        help="the ORB-SLAM2 peer (the folder the peer kit's build.sh made); without it the "
                             "ORB-SLAM2 columns say 'not run'")
    parser.add_argument("--orbslam2-run", type=Path, default=results_peer.DEFAULT_RUN_SCRIPT, metavar="RUN_SH",
                        help=f"the peer kit's run.sh (default: {results_peer.DEFAULT_RUN_SCRIPT})")
    parser.add_argument("--orbslam2-runs", type=int, default=None,
                        help="ORB-SLAM2 runs per sequence (it is not deterministic; default 3, 1 with --quick)")
    parser.add_argument("--spread-runs", type=int, default=9,
                        help="runs per family of the ATE spread on the real slice (ate_spread.py; our modes none "
                             "and YMK and ORB-SLAM2 when given; 0: skip; default 9, about 3 minutes with ORB-SLAM2)")
    parser.add_argument("--real-data", default=None, metavar="DIR|none",
                        help="a real TUM folder our pipeline (and the peer) also run on; default "
                             f"{DEFAULT_REAL_DATA} when it exists, none with --quick")
    parser.add_argument("--reuse", action="store_true",
                        help="read back runs of an earlier suite run in the same --work folder that were made "
                             "with the same tools, arguments and inputs (their times are from then)")
    args = parser.parse_args()

    plan = QUICK if args.quick else FULL
    if args.jobs < 1:
        print("make_results.py: --jobs must be at least 1", file=sys.stderr)
        return 2
    peer_runs = args.orbslam2_runs if args.orbslam2_runs is not None else (1 if args.quick else 3)
    if peer_runs < 1:
        print("make_results.py: --orbslam2-runs must be at least 1", file=sys.stderr)
        return 2
    if not 0 <= args.spread_runs <= 50:
        print("make_results.py: --spread-runs must lie in 0 .. 50", file=sys.stderr)
        return 2
    peer = None
    if args.orbslam2 is not None:
        problem = results_peer.check_peer(args.orbslam2.resolve(), args.orbslam2_run.resolve())
        if problem:
            print(f"make_results.py: {problem}", file=sys.stderr)
            return 2
        peer = results_peer.Peer(args.orbslam2.resolve(), args.orbslam2_run.resolve())
    if args.real_data is None:
        real_data = None if args.quick or not DEFAULT_REAL_DATA.is_dir() else DEFAULT_REAL_DATA
    elif args.real_data == "none":
        real_data = None
    else:
        real_data = Path(args.real_data).resolve()
        missing = [f for f in ("rgb.txt", "depth.txt", "groundtruth.txt") if not (real_data / f).is_file()]
        if missing:
            print(f"make_results.py: --real-data {args.real_data}: no {', '.join(missing)} (a TUM RGB-D folder)",
                  file=sys.stderr)
            return 2
    out = args.out.resolve()
    work = (args.work or out.parent / "results-work").resolve()
    if work == out or work == out / "results":
        print("make_results.py: --work must be a folder of its own, not OUT or OUT/results", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    work.mkdir(parents=True, exist_ok=True)
    runner = Runner(args.tools.resolve(), work, args.verbose)
    runner.reuse = args.reuse
    if peer is not None:
        runner.aliases.append((str(peer.run_script), "run.sh"))
    if real_data is not None:
        shown = "../shared/data/" + real_data.name if real_data == DEFAULT_REAL_DATA.resolve() else str(real_data)
        runner.aliases.insert(0, (str(real_data), shown))

    started = time.monotonic()
    load_at_start = os.getloadavg()[0]
    steps: dict[str, float] = {}
    try:
        t = time.monotonic()
        print("vocabulary", flush=True)
        vocabulary = work / "vocabulary.txt"
        runner.run("cge_vocab", "--preset", "walking_xyz", "--frames", plan.vocabulary_frames, "--preset-seed",
                   plan.seed, "-L", "3", "--out", vocabulary, "--force")
        steps["vocabulary"] = time.monotonic() - t

        t = time.monotonic()
        print("walking presets x modes", flush=True)
        walking = walking_runs(runner, plan, args.jobs)
        steps["walking runs"] = time.monotonic() - t

        t = time.monotonic()
        if peer is not None or real_data is not None:
            print("ORB-SLAM2 and ours, alternating" if peer is not None else "real data", flush=True)
        compared = compared_runs(runner, plan, peer, peer_runs, real_data, args.jobs)
        steps["ORB-SLAM2 and compared runs"] = time.monotonic() - t

        spread = None
        if real_data is not None and args.spread_runs > 0:
            t = time.monotonic()
            print(f"ATE spread on the real slice ({args.spread_runs} runs each)", flush=True)
            spread = real_data_spread(runner, real_data, peer, args.spread_runs, min(args.jobs, 16))
            steps["real-data ATE spread"] = time.monotonic() - t

        t = time.monotonic()
        print("loop scenes x loop scorings", flush=True)
        loops = loop_runs(runner, plan, vocabulary, args.jobs)
        steps["loop runs"] = time.monotonic() - t

        t = time.monotonic()
        print("entropy study", flush=True)
        study = entropy_study(runner, plan, args.jobs)
        steps["entropy study"] = time.monotonic() - t
    except ToolError as e:
        print(f"make_results.py: {e}", file=sys.stderr)
        return 1

    t = time.monotonic()
    figures_dir = out / "results"
    figures_dir.mkdir(exist_ok=True)
    figures = results_plots.make_all(figures_dir, walking, loops, study, TRAJECTORY_PRESETS, MODES, LOOP_PRESETS,
                                     LOOP_SCORINGS, compared["peer"])
    steps["figures"] = time.monotonic() - t
    steps["total"] = time.monotonic() - started

    context = results_report.Context(
        plan=plan, quick=args.quick, walking=walking, loops=loops, study=study, figures=figures,
        figures_prefix=figures_dir.name, steps=steps, jobs=args.jobs,
        machine=f"{machine_description()}; load average (1 min) {load_at_start:.1f} at the start of the suite, "
                f"{os.getloadavg()[0]:.1f} at its end",
        commands=runner.commands, walking_presets=WALKING_PRESETS, modes=MODES, loop_presets=LOOP_PRESETS,
        loop_scorings=LOOP_SCORINGS, low_dynamic_presets=LOW_DYNAMIC_PRESETS, compared=compared,
        peer_ran=peer is not None, real_data=real_data.name if real_data is not None else None,
        real_data_modes=REAL_DATA_MODES, tracking_stages=TRACKING_STAGES, reused=runner.reused,
        real_data_spread=spread)
    report = out / "RESULTS.md"
    tmp = report.with_suffix(".md.tmp")
    tmp.write_text(results_report.render(context), encoding="utf-8")
    tmp.replace(report)
    print(f"wrote {report} and {len(figures)} figures in {figures_dir} ({steps['total']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
