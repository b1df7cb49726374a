#!/usr/bin/env python3
"""Unit tests of the results suite's ORB-SLAM2 path, without ORB-SLAM2: a fake peer output folder
read back and evaluated (against an ATE computed here with numpy), a fake run.sh that succeeds or
fails, the summaries, the report's tables with and without the peer, and the suite's refusals.

    test_results_suite.py --tools BUILD/examples --suite examples/results/make_results.py
"""
import argparse
import math
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import numpy as np

ARGS = None  # set in __main__


def suite_modules():
    sys.path.insert(0, str(Path(ARGS.suite).resolve().parent))
    import make_results  # noqa: E402
    import results_peer  # noqa: E402
    import results_report  # noqa: E402
    return make_results, results_peer, results_report


def write_tum(path: Path, stamps, positions) -> None:
    with open(path, "w", encoding="utf-8") as f:
        f.write("# timestamp tx ty tz qx qy qz qw\n")
        for t, p in zip(stamps, positions):
            f.write(f"{t:.6f} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} 0 0 0 1\n")


def ate_oracle(gt: np.ndarray, est: np.ndarray) -> tuple[float, float]:
    """RMSE and population SD of the position errors after the least-squares rigid alignment
    (Horn / Kabsch via SVD), written here independently of the C++ code."""
    mu_g, mu_e = gt.mean(axis=0), est.mean(axis=0)
    h = (est - mu_e).T @ (gt - mu_g)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    aligned = (r @ (est - mu_e).T).T + mu_g
    errors = np.linalg.norm(aligned - gt, axis=1)
    return float(np.sqrt(np.mean(errors ** 2))), float(np.std(errors))


ORBSLAM2_LOG = """Depth Threshold (Close/Far Points): 3.09294
-------
Start processing sequence ...
Images in the sequence: 300

median tracking time: 0.0254
mean tracking time: 0.031

Saving camera trajectory to CameraTrajectory.txt ...
"""


class PeerOutputs(unittest.TestCase):
    def setUp(self):
        self.make_results, self.peer, self.report = suite_modules()
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = Path(self.tmp.name)
        n = 60
        self.stamps = [1.0 + i / 30 for i in range(n)]
        self.gt = np.array([[0.02 * i, 0.3 * math.sin(i / 9), 0.1 * math.cos(i / 7)] for i in range(n)])
        rng = np.random.default_rng(7)
        self.est = self.gt + rng.normal(0, 0.01, self.gt.shape)
        self.dataset = self.dir / "dataset"
        self.dataset.mkdir()
        write_tum(self.dataset / "groundtruth.txt", self.stamps, self.gt)
        self.runner = self.make_results.Runner(Path(ARGS.tools).resolve(), self.dir / "work", False)

    def tearDown(self):
        self.tmp.cleanup()

    def evaluate(self, kind, estimate):
        return self.runner.run("cge_eval", kind, self.dataset / "groundtruth.txt", estimate, "--json",
                               capture_json=True)

    def fake_output(self, out: Path, keyframes: int, positions=None) -> None:
        out.mkdir(parents=True, exist_ok=True)
        positions = self.est if positions is None else positions
        write_tum(out / "CameraTrajectory.txt", self.stamps[: len(positions)], positions)
        write_tum(out / "KeyFrameTrajectory.txt", self.stamps[:keyframes], positions[:keyframes])
        (out / "orbslam2.log").write_text(ORBSLAM2_LOG, encoding="utf-8")

    def test_log_times_in_milliseconds(self):
        times = self.peer.parse_tracking_times(ORBSLAM2_LOG)
        self.assertAlmostEqual(times["median_ms"], 25.4, places=9)
        self.assertAlmostEqual(times["mean_ms"], 31.0, places=9)
        self.assertEqual(self.peer.parse_tracking_times("no times here\n"), {})

    def test_read_back_against_oracle(self):
        out = self.dir / "peer_1"
        self.fake_output(out, keyframes=7)
        run = self.peer.read_peer_run(out, self.evaluate)
        self.assertNotIn("error", run)
        rmse, sd = ate_oracle(self.gt, self.est)
        self.assertGreater(rmse, 0.005)  # the noise is not aligned away
        self.assertAlmostEqual(run["ate_rmse_m"], rmse, delta=1e-7)
        self.assertAlmostEqual(run["ate_std_m"], sd, delta=1e-7)
        self.assertEqual(run["keyframes"], 7)
        self.assertEqual(run["tracked_frames"], len(self.stamps))
        self.assertAlmostEqual(run["track_median_ms"], 25.4, places=9)
        self.assertTrue(run["rpe_translation_rmse_m"] > 0)

    def test_missing_file_and_refused_trajectory_are_errors(self):
        out = self.dir / "peer_missing"
        self.fake_output(out, keyframes=3)
        (out / "KeyFrameTrajectory.txt").unlink()
        self.assertIn("KeyFrameTrajectory.txt missing", self.peer.read_peer_run(out, self.evaluate)["error"])
        out = self.dir / "peer_short"
        self.fake_output(out, keyframes=2, positions=self.est[:2])  # 2 poses: cge_eval refuses an ATE
        run = self.peer.read_peer_run(out, self.evaluate)
        self.assertIn("error", run)
        self.assertNotIn("ate_rmse_m", run)

    def test_fake_run_script(self):
        peer_dir = self.dir / "peer_build"
        (peer_dir / self.peer.RGBD_TUM).parent.mkdir(parents=True)
        (peer_dir / self.peer.RGBD_TUM).write_text("#!/bin/sh\n", encoding="utf-8")
        (peer_dir / self.peer.RGBD_TUM).chmod(0o755)
        template = self.dir / "template"
        self.fake_output(template, keyframes=5)
        good = self.dir / "run_good.sh"
        good.write_text(f'[ -n "$ORB_PEER" ] || exit 9\nmkdir -p "$2"\ncp {template}/* "$2"/\n', encoding="utf-8")
        bad = self.dir / "run_bad.sh"
        bad.write_text('echo "run.sh: missing something" >&2\nexit 3\n', encoding="utf-8")
        self.assertIsNone(self.peer.check_peer(peer_dir, good))
        run = self.make_results.peer_run(self.runner, self.peer.Peer(peer_dir, good), self.dataset, self.dir / "o1")
        self.assertEqual(run.get("keyframes"), 5, run)
        failed = self.make_results.peer_run(self.runner, self.peer.Peer(peer_dir, bad), self.dataset, self.dir / "o2")
        self.assertEqual(failed, {"error": "run.sh exit 3: run.sh: missing something"})
        self.assertIn("not a folder", self.peer.check_peer(self.dir / "absent", good))
        self.assertIn("rgbd_tum", self.peer.check_peer(self.dir, good))


class Summaries(unittest.TestCase):
    def setUp(self):
        _, self.peer, _ = suite_modules()

    def test_mean_min_max_and_failures(self):
        runs = [{"ate_rmse_m": 0.4, "keyframes": 30}, {"ate_rmse_m": 0.7, "keyframes": 34},
                {"error": "run.sh exit 1: crashed"}, {"ate_rmse_m": 0.1, "keyframes": 32}]
        s = self.peer.summarise(runs)
        self.assertAlmostEqual(s["ate_rmse_m"]["mean"], 0.4)
        self.assertAlmostEqual(s["ate_rmse_m"]["sd"], 0.3)  # sample sd of 0.4, 0.7, 0.1
        self.assertEqual(self.peer.spread([0.5])["sd"], 0.0)
        self.assertEqual((s["ate_rmse_m"]["min"], s["ate_rmse_m"]["max"], s["ate_rmse_m"]["count"]), (0.1, 0.7, 3))
        self.assertEqual(s["keyframes"]["mean"], 32)
        self.assertEqual((s["runs"], s["failed"]), (4, 1))
        self.assertIsNone(s["track_median_ms"])
        self.assertIsNone(self.peer.spread([None, float("nan"), True]))


def walking_summary(ate_m: float, keyframes: int, std_m: float = 0.001) -> dict:
    return {"summary": {"ate": {"rmse_m": ate_m, "std_m": std_m}, "keyframes": keyframes, "frames": 300,
                        "tracked_frames": 300, "rpe": {"translation_rmse_m": 0.005, "rotation_rmse_deg": 0.1},
                        "stages": {"tracking": {"median_ms": 10.0, "mean_ms": 11.0}}}}


class ReportTables(unittest.TestCase):
    PRESETS = ["walking_xyz", "walking_static"]

    def setUp(self):
        _, self.peer, self.report = suite_modules()

    def context(self, peer_runs: dict | None):
        walking = {}
        for preset in self.PRESETS:
            for mode, ate, kf in (("none", 0.011, 250), ("Y", 0.006, 240), ("YM", 0.005, 240), ("YMK", 0.004, 40)):
                walking[(preset, mode)] = walking_summary(ate, kf)
        compared = {"peer": {}, "ours": {}, "rounds": 3}
        if peer_runs:
            for name, runs in peer_runs.items():
                compared["peer"][name] = {"runs": runs, "summary": self.peer.summarise(runs)}
        return self.report.Context(
            plan=type("Plan", (), {"seed": 1, "walking_frames": 300, "loop_frames": 451})(), quick=False,
            walking=walking, loops={}, study={}, figures={}, figures_prefix="results", steps={}, machine="test",
            jobs=1, commands=[], walking_presets=self.PRESETS, modes=["none", "Y", "YM", "YMK"], loop_presets=[],
            loop_scorings=[], compared=compared, peer_ran=peer_runs is not None)

    @staticmethod
    def row(text: str, section: str, first: str) -> list[str]:
        part = text.split(section, 1)[1]
        for line in part.splitlines():
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if line.startswith("|") and cells[0] == first:
                return cells
        raise AssertionError(f"no row {first} after {section}")

    def test_without_peer_every_orbslam2_cell_says_not_run(self):
        text = "\n".join(self.report.trajectory_section(self.context(None)) +
                         self.report.keyframe_section(self.context(None)))
        ate = self.row(text, "### ATE RMSE [mm]", "walking_xyz")
        self.assertEqual(ate[1], "not run")
        self.assertEqual(ate[5], "4.0")  # YMK, mm
        self.assertEqual(ate[6], "761.5")  # the paper's ORB-SLAM2 on real walking_xyz
        target = self.row(text, "### Target: YMK's ATE", "walking_xyz")
        self.assertEqual(target[5], "not run")
        kf = self.row(text, "## Keyframes against ORB-SLAM2", "walking_xyz")
        self.assertEqual((kf[1], kf[5], kf[7]), ("not run", "40", "not run"))
        self.assertIn("**not run**", "\n".join(self.report.setting(self.context(None))))

    def test_with_peer_columns_and_targets(self):
        peer = {"walking_xyz": [{"ate_rmse_m": 0.4, "ate_std_m": 0.2, "keyframes": 90},
                                {"ate_rmse_m": 0.6, "ate_std_m": 0.3, "keyframes": 110}],
                "walking_static": [{"ate_rmse_m": 0.1, "ate_std_m": 0.05, "keyframes": 79},
                                   {"error": "run.sh exit 1: boom"}]}
        text = "\n".join(self.report.trajectory_section(self.context(peer)) +
                         self.report.keyframe_section(self.context(peer)))
        self.assertEqual(self.row(text, "### ATE RMSE [mm]", "walking_xyz")[1], "500.0 [400.0-600.0]")
        self.assertEqual(self.row(text, "### ATE RMSE [mm]", "walking_static")[1], "100.0 (1 of 2 runs failed)")
        self.assertEqual(self.row(text, "### ATE RMSE / standard deviation", "walking_xyz")[1],
                         "500.0 [400.0-600.0] / 250.0 [200.0-300.0]")
        target = self.row(text, "### Target: YMK's ATE", "walking_xyz")
        self.assertEqual((target[3], target[4], target[5]), ("0.80 %", "1.00 %", "met"))
        target = self.row(text, "### Target: YMK's ATE", "walking_static")
        self.assertEqual((target[3], target[5]), ("4.00 %", "**not met**"))
        kf = self.row(text, "## Keyframes against ORB-SLAM2", "walking_xyz")
        self.assertEqual((kf[1], kf[6], kf[7]), ("100 [90-110]", "60.0 %", "met"))
        kf = self.row(text, "## Keyframes against ORB-SLAM2", "walking_static")
        self.assertEqual((kf[6], kf[7]), ("49.4 %", "**not met**"))  # 1 - 40/79


class Reuse(unittest.TestCase):
    """Stamps: a run is read back only when the tool's bytes, its arguments and its inputs' bytes match."""

    def setUp(self):
        self.make_results, _, _ = suite_modules()
        import results_stamps  # noqa: E402
        self.stamps = results_stamps
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = Path(self.tmp.name)
        self.tools = self.dir / "tools"
        self.tools.mkdir()
        self.calls = self.dir / "calls.txt"
        self.write_tool("v1")
        self.sequence = self.dir / "sequence"
        (self.sequence / "rgb").mkdir(parents=True)
        (self.sequence / "rgb" / "0.png").write_bytes(b"frame")
        (self.sequence / "rgb.txt").write_text("0 rgb/0.png\n", encoding="utf-8")

    def tearDown(self):
        self.tmp.cleanup()

    def write_tool(self, version: str) -> None:
        """A stand-in cge_slam: logs its call, writes summary.json into --out (the argument after it)."""
        tool = self.tools / "cge_slam"
        tool.write_text(f"#!/bin/sh\n# {version}\necho call >> {self.calls}\n"
                        'while [ "$1" != "--out" ]; do shift; done\nmkdir -p "$2"\n'
                        'echo \'{"frames": 1}\' > "$2/summary.json"\n', encoding="utf-8")
        tool.chmod(0o755)

    def run_slam(self, reuse: bool, mode: str = "YMK") -> int:
        runner = self.make_results.Runner(self.tools, self.dir / "work", False)
        runner.reuse = reuse
        summary = self.make_results.slam(runner, runner.commands, self.sequence, self.dir / "work" / "out", "--mode",
                                         mode)
        self.assertEqual(summary, {"frames": 1})
        self.assertEqual(len(runner.commands), 1)  # logged whether run or read back
        return len(self.calls.read_text(encoding="utf-8").splitlines())

    def test_reused_only_when_everything_matches(self):
        self.assertEqual(self.run_slam(reuse=True), 1)
        self.assertEqual(self.run_slam(reuse=True), 1)  # same tool, arguments, inputs: read back
        self.assertEqual(self.run_slam(reuse=False), 2)  # without --reuse: run again
        self.assertEqual(self.run_slam(reuse=True, mode="YM"), 3)  # other arguments
        self.assertEqual(self.run_slam(reuse=True, mode="YM"), 3)
        (self.sequence / "rgb" / "0.png").write_bytes(b"frame!")  # an input's bytes changed
        self.assertEqual(self.run_slam(reuse=True, mode="YM"), 4)
        self.write_tool("v2")  # the tool changed
        self.assertEqual(self.run_slam(reuse=True, mode="YM"), 5)
        self.assertEqual(self.run_slam(reuse=True, mode="YM"), 5)

    def test_folder_digest_is_content(self):
        before = self.stamps.input_digest(self.sequence)
        (self.sequence / self.stamps.STAMP).write_text("anything", encoding="utf-8")
        self.assertEqual(self.stamps.input_digest(self.sequence), before)  # the stamp itself does not count
        (self.sequence / "depth.txt").write_text("", encoding="utf-8")
        self.assertNotEqual(self.stamps.input_digest(self.sequence), before)


class LoopTarget(unittest.TestCase):
    def test_marks(self):
        _, _, report = suite_modules()
        self.assertEqual(report.loop_target({"precision": 1.0, "event_recall": 1.0}), "met")
        self.assertEqual(report.loop_target({"precision": 1.0, "event_recall": 0.875}), "**not met**")
        self.assertEqual(report.loop_target({"precision": 0.98, "event_recall": 1.0}), "**not met**")
        self.assertEqual(report.loop_target({"precision": None, "event_recall": 1.0}), "n/a")
        self.assertEqual(report.scene_validity({"precision": 1.0, "event_recall": 0.75}), "valid")
        self.assertEqual(report.scene_validity({"precision": 1.0, "event_recall": 1.0}), "**not valid**")
        self.assertEqual(report.scene_validity({"precision": 0.9, "event_recall": 0.75}), "**not valid**")
        self.assertEqual(report.scene_validity({}), "n/a")
        self.assertEqual(report.paper_loops("loop_dynamic", "bow_only"), "100 % / 75.0 % (6 TP, 0 FP, 2 FN)")
        self.assertEqual(report.paper_loops("loop_dynamic", "combined"), "not given")


class Refusals(unittest.TestCase):
    def run_suite(self, *extra: str) -> subprocess.CompletedProcess:
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "docs"
            result = subprocess.run([sys.executable, ARGS.suite, "--tools", ARGS.tools, "--out", str(out), "--work",
                                     str(Path(tmp) / "work"), "--quick", *extra], capture_output=True, text=True)
            self.assertFalse((out / "RESULTS.md").exists())
            return result

    def test_bad_peer_folder(self):
        r = self.run_suite("--orbslam2", "/nonexistent/peer")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("--orbslam2 /nonexistent/peer: not a folder", r.stderr)

    def test_bad_real_data(self):
        r = self.run_suite("--real-data", "/nonexistent/tum")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("--real-data /nonexistent/tum: no rgb.txt", r.stderr)

    def test_bad_run_count(self):
        r = self.run_suite("--orbslam2-runs", "0")
        self.assertEqual(r.returncode, 2, r.stderr)
        self.assertIn("--orbslam2-runs must be at least 1", r.stderr)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--tools", required=True)
    parser.add_argument("--suite", required=True)
    ARGS, rest = parser.parse_known_args()
    unittest.main(argv=[sys.argv[0], *rest])
