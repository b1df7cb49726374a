#!/usr/bin/env python3
"""CI check of the results suite: runs make_results.py --quick into a folder of its own and checks
that the report was written whole, that its figures exist, and that its numbers are the runs'.

    check_results_quick.py --suite examples/results/make_results.py --tools BUILD/examples --work DIR
"""
import argparse
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

SECTIONS = [
    "## The setting, and what differs from the paper's",
    "## Trajectory error per sequence and mode",
    "## Keyframes against ORB-SLAM2",
    "## Dynamic features that survive filtering",
    "## Time per stage",
    "## Semantic map scores",
    "## Loop closing: precision and recall",
    "## The entropy measures: collapse and separation",
    "## How these numbers were made",
]


def fail(message: str) -> None:
    print(f"check_results_quick: {message}", file=sys.stderr)
    sys.exit(1)


def table_row(report: str, *cells: str) -> list[str]:
    """The cells of the first table row that starts with the given cells."""
    for line in report.splitlines():
        parts = [p.strip() for p in line.strip().strip("|").split("|")]
        if line.startswith("|") and parts[: len(cells)] == list(cells):
            return parts
    fail(f"no table row starting with {cells}")
    return []


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--suite", required=True)
    parser.add_argument("--tools", required=True)
    parser.add_argument("--work", required=True, type=Path)
    args = parser.parse_args()

    shutil.rmtree(args.work, ignore_errors=True)  # this test's own folder from an earlier run
    out, work = args.work / "docs", args.work / "work"
    base = [sys.executable, args.suite, "--tools", args.tools]

    # A work folder that is the output folder is refused before anything runs.
    refused = subprocess.run(base + ["--out", str(out), "--work", str(out), "--quick"], capture_output=True, text=True)
    if refused.returncode != 2 or "--work" not in refused.stderr:
        fail(f"--work equal to --out: exit {refused.returncode}, expected 2 with a message\n{refused.stderr}")
    if (out / "RESULTS.md").exists():
        fail("a refused run wrote RESULTS.md")

    run = subprocess.run(base + ["--out", str(out), "--work", str(work), "--quick"], capture_output=True, text=True)
    if run.returncode != 0:
        fail(f"make_results.py --quick: exit {run.returncode}\n--- stdout ---\n{run.stdout}\n--- stderr ---\n{run.stderr}")
    report = (out / "RESULTS.md").read_text(encoding="utf-8")
    for section in SECTIONS:
        if section not in report:
            fail(f"RESULTS.md lacks the section '{section}'")
    if "**Quick run**" not in report:
        fail("a quick run's report does not say it is one")

    figures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report)
    if not figures:
        fail("RESULTS.md references no figure")
    for name in figures:
        path = out / name
        if not path.is_file() or path.read_bytes()[:8] != b"\x89PNG\r\n\x1a\n":
            fail(f"figure {name} is missing or not a PNG")

    # The report's numbers are the runs' own: ATE (with its SD) and keyframes of some runs, read back.
    # Columns: sequence, ORB-SLAM2, none, Y, YM, YMK.
    column = {"none": 2, "Y": 3, "YM": 4, "YMK": 5}
    ate_section = report.split("### ATE RMSE [mm]")[1]
    sd_section = report.split("### ATE RMSE / standard deviation")[1]
    for preset, mode in (("walking_xyz", "YMK"), ("walking_static", "none"), ("sitting_xyz (low-dynamic)", "YM")):
        folder = preset.split()[0]
        summary = json.loads((work / "runs" / folder / mode / "summary.json").read_text(encoding="utf-8"))
        row = table_row(ate_section, preset)
        expected = f"{summary['ate']['rmse_m'] * 1000:.1f}"
        if row[column[mode]] != expected:
            fail(f"ATE of {preset} {mode}: report {row[column[mode]]}, summary.json {expected}")
        expected = f"{expected} / {summary['ate']['std_m'] * 1000:.1f}"
        if table_row(sd_section, preset)[column[mode]] != expected:
            fail(f"ATE / SD of {preset} {mode}: report {table_row(sd_section, preset)[column[mode]]}, expected {expected}")
    kf_section = report.split("## Keyframes against ORB-SLAM2")[1]
    summary = json.loads((work / "runs" / "walking_xyz" / "YMK" / "summary.json").read_text(encoding="utf-8"))
    kf_row = table_row(kf_section, "walking_xyz")
    if kf_row[5] != str(summary["keyframes"]):
        fail(f"YMK keyframes of walking_xyz: report {kf_row[5]}, summary.json {summary['keyframes']}")
    # Without the peer, its columns and targets say so instead of holding numbers.
    if table_row(ate_section, "walking_xyz")[1] != "not run" or kf_row[1] != "not run":
        fail("without --orbslam2 the ORB-SLAM2 columns do not say 'not run'")
    if table_row(report.split("### Target: YMK's ATE")[1], "walking_xyz")[5] != "not run":
        fail("without --orbslam2 the ATE target is not marked 'not run'")
    print(f"results suite (quick): {len(SECTIONS)} sections, {len(figures)} figures, numbers match the runs")


if __name__ == "__main__":
    main()
