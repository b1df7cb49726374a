#!/usr/bin/env python3
"""Regenerates docs/RESULTS.md: the paper's tables and figures, measured on the synthetic presets.

Renders every synthetic preset with a fixed seed (cge_sim), runs every mode of the reference
pipeline on it (cge_slam), evaluates the runs (cge_eval), studies the entropy measures on the loop
scenes (cge_loop_study), and writes RESULTS.md with its PNG figures. The suite only calls the
command-line tools and reads the files they write, so every number here can be reproduced by hand
with the commands listed in RESULTS.md.

Usage (docs/RESULTS.md):
    make_results.py --tools BUILD/examples --out docs [--work BUILD/results] [--quick]

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
import results_plots  # noqa: E402  (beside this file)
import results_report  # noqa: E402

WALKING_PRESETS = ["walking_xyz", "walking_halfsphere", "walking_rpy", "walking_static"]
LOOP_PRESETS = ["loop_dynamic", "loop_structure_change"]
MODES = ["none", "Y", "YM", "YMK"]
# Loop scorings compared in Table 6: BoW only (ORB-SLAM2-like), the paper's CGE ranking, ours.
LOOP_SCORINGS = ["bow_only", "cge", "combined"]


@dataclass(frozen=True)
class Plan:
    """Sequence lengths and seeds of one suite run."""

    walking_frames: int
    loop_frames: int  # not a multiple of the 3 laps, so that no lap repeats another's poses
    vocabulary_frames: int
    study_step: int  # every study_step-th frame of a loop scene enters the entropy study
    seed: int = 1


FULL = Plan(walking_frames=300, loop_frames=451, vocabulary_frames=20, study_step=3)
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

    def tool(self, name: str) -> str:
        path = self.tools / name
        if not path.is_file() or not os.access(path, os.X_OK):
            raise ToolError(f"{path}: not found or not executable (build the tools first)")
        return str(path)

    def run(self, name: str, *args: str, capture_json: bool = False, log: list[str] | None = None) -> dict | str:
        """Runs one tool; its command goes to `log` (a parallel task's own list) or the runner's."""
        argv = [self.tool(name), *map(str, args)]
        shown = " ".join([name, *map(str, args)]).replace(str(self.work) + "/", "")
        (self.commands if log is None else log).append(shown)
        if self.verbose:
            print(f"  $ {shown}", flush=True)
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
    out = runner.work / "sequences" / f"{preset}_{frames}_s{seed}"
    if (out / "rgb.txt").is_file() and (out / "loops.txt").is_file():
        return out  # the renderer is deterministic: same arguments, same bytes
    runner.run("cge_sim", "--preset", preset, "--frames", frames, "--seed", seed, "--out", out, "--force")
    return out


def slam(runner: Runner, log: list[str], sequence: Path, out: Path, *flags: str) -> dict:
    runner.run("cge_slam", "--dataset", sequence, "--out", out, "--force", *flags, log=log)
    return read_json(out / "summary.json")


def walking_runs(runner: Runner, plan: Plan, jobs: int) -> dict:
    """Every walking preset in every mode; maps and aligned trajectories for the figures."""
    sequences = {preset: render(runner, preset, plan.walking_frames, plan.seed) for preset in WALKING_PRESETS}

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

    keys = [(preset, mode) for preset in WALKING_PRESETS for mode in MODES]
    runs = dict(zip(keys, runner.parallel([partial(one, *key) for key in keys], jobs)))
    for (preset, mode), run in runs.items():
        print(f"  {preset:20s} {mode:4s} ate {fmt_m(run['summary'].get('ate', {}).get('rmse_m'))}", flush=True)
    return runs


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
    args = parser.parse_args()

    plan = QUICK if args.quick else FULL
    if args.jobs < 1:
        print("make_results.py: --jobs must be at least 1", file=sys.stderr)
        return 2
    out = args.out.resolve()
    work = (args.work or out.parent / "results-work").resolve()
    if work == out or work == out / "results":
        print("make_results.py: --work must be a folder of its own, not OUT or OUT/results", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    work.mkdir(parents=True, exist_ok=True)
    runner = Runner(args.tools.resolve(), work, args.verbose)

    started = time.monotonic()
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
    figures = results_plots.make_all(figures_dir, walking, loops, study, WALKING_PRESETS, MODES, LOOP_PRESETS,
                                     LOOP_SCORINGS)
    steps["figures"] = time.monotonic() - t
    steps["total"] = time.monotonic() - started

    context = results_report.Context(
        plan=plan, quick=args.quick, walking=walking, loops=loops, study=study, figures=figures,
        figures_prefix=figures_dir.name, steps=steps, machine=machine_description(), jobs=args.jobs,
        commands=runner.commands, walking_presets=WALKING_PRESETS, modes=MODES, loop_presets=LOOP_PRESETS,
        loop_scorings=LOOP_SCORINGS)
    report = out / "RESULTS.md"
    tmp = report.with_suffix(".md.tmp")
    tmp.write_text(results_report.render(context), encoding="utf-8")
    tmp.replace(report)
    print(f"wrote {report} and {len(figures)} figures in {figures_dir} ({steps['total']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
