"""Writes RESULTS.md from the runs make_results.py collected.

Every number in the report comes from a tool's output file; the few judgements (target met or not,
which exponent scaling separates better) are computed from those numbers here, never typed in.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

# What the issues quote from the paper (Wang & Luo 2025). Its tables themselves were not available
# to us; RESULTS.md says so instead of inventing them.
PAPER_ATE_REDUCTION = 0.97  # "97% less [ATE] than ORB-SLAM2 on TUM" (issue 5)
PAPER_KEYFRAME_REDUCTION = 0.61  # "paper: 61%" fewer keyframes than ORB-SLAM2 (issue 5)
PAPER_TRACKING_MS = 26.7  # tracking time per frame (issue 5)

# Targets of issue 5 checked here.
TARGET_ATE_RATIO = 0.10  # YMK at most 10% of mode none
TARGET_ATE_M = 0.02  # and under 2 cm
TARGET_KEYFRAME_REDUCTION = 0.50  # at least 50% fewer keyframes than the ORB-SLAM2-style policy
TARGET_TRACKING_MS = 30.0
TARGET_GHOST_RATIO = 0.01  # issue 6: ghost voxels of YMK under 1% of mode none


@dataclass
class Context:
    plan: object
    quick: bool
    walking: dict
    loops: dict
    study: dict
    figures: dict
    figures_prefix: str
    steps: dict
    machine: str
    jobs: int
    commands: list
    walking_presets: list
    modes: list
    loop_presets: list
    loop_scorings: list


def is_number(v) -> bool:
    return isinstance(v, (int, float)) and not (isinstance(v, float) and math.isnan(v))


def num(v, digits: int = 3, scale: float = 1.0) -> str:
    return f"{v * scale:.{digits}g}" if is_number(v) else "n/a"


def fixed(v, decimals: int = 1, scale: float = 1.0) -> str:
    return f"{v * scale:.{decimals}f}" if is_number(v) else "n/a"


def pct(v, decimals: int = 1) -> str:
    return f"{v * 100:.{decimals}f} %" if is_number(v) else "n/a"


def get(d, *keys):
    for k in keys:
        d = d.get(k) if isinstance(d, dict) else None
    return d


def table(header: list[str], rows: list[list[str]]) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return out + [""]


def figure(ctx: Context, key: str, caption: str) -> list[str]:
    name = ctx.figures.get(key)
    return [f"![{caption}]({ctx.figures_prefix}/{name})", ""] if name else [f"({caption}: no data to draw.)", ""]


def yes_no(ok) -> str:
    return "n/a" if ok is None else ("met" if ok else "**not met**")


def setting(ctx: Context) -> list[str]:
    p = ctx.plan
    return [
        "## The setting, and what differs from the paper's",
        "",
        f"- **Data.** The paper runs on real TUM RGB-D sequences (fr3 walking_xyz, walking_halfsphere, "
        f"walking_rpy, walking_static). We run on synthetic presets of the same names rendered by `cge_sim` "
        f"(seed {p.seed}; {p.walking_frames} frames each; loop scenes {p.loop_frames} frames, three laps), "
        "with exact ground truth: poses, depth, instance masks and loop pairs (docs/SIMULATION.md). The "
        "people and motions are simpler than TUM's, so absolute errors are smaller than on TUM.",
        "- **Segmentation.** The paper runs YOLOv8-seg. We use the ground-truth masks after the simulated "
        "segmentation errors (masks eroded by 2 px, feet lost in 20% of frames, 3% missed instances, 2% "
        "false positives), so the MAD filter has mask edges to repair. YOLOv8-seg on real data is covered by "
        "docs/REAL_DATA.md.",
        "- **Baseline.** The paper compares with ORB-SLAM2 itself. Our baseline is mode `none` of the same "
        "pipeline: no dynamic handling and an ORB-SLAM2-style keyframe policy (our implementation, without "
        "ORB-SLAM2's local mapping, culling or RGB-D close-point rule). Modes Y and YM keep that policy; "
        "YMK adds the patch keyframe selector.",
        "- **Paper's figures.** We could not obtain the paper's full tables; where an issue quotes a figure "
        "of the paper, it stands beside ours. Everything else is ours only.",
        "",
    ]


def trajectory_section(ctx: Context) -> list[str]:
    lines = ["## Trajectory error per sequence and mode (paper Tables 2 to 4, Figures 8 and 9)", "",
             "ATE: RMSE of the positions after a rigid alignment (TUM `evaluate_ate`); RPE over 1 s "
             "(TUM `evaluate_rpe`). `cge_eval ate|rpe` compute both; cge_slam writes them to summary.json.", ""]
    rows = []
    for preset in ctx.walking_presets:
        for mode in ctx.modes:
            s = get(ctx.walking, (preset, mode), "summary") or {}
            rows.append([preset, mode, fixed(get(s, "ate", "rmse_m"), 1, 1000),
                         fixed(get(s, "rpe", "translation_rmse_m"), 1, 1000),
                         fixed(get(s, "rpe", "rotation_rmse_deg"), 3),
                         f"{s.get('tracked_frames', 'n/a')}/{s.get('frames', 'n/a')}"])
    lines += table(["sequence", "mode", "ATE RMSE [mm]", "RPE trans. RMSE [mm]", "RPE rot. RMSE [deg]",
                    "tracked frames"], rows)

    lines += ["Against the targets of issue 5 (YMK at most 10% of mode none and under 2 cm; the paper "
              f"reports {PAPER_ATE_REDUCTION:.0%} less ATE than ORB-SLAM2 on TUM):", ""]
    rows = []
    missed = False
    for preset in ctx.walking_presets:
        none = get(ctx.walking, (preset, "none"), "summary", "ate", "rmse_m")
        ymk = get(ctx.walking, (preset, "YMK"), "summary", "ate", "rmse_m")
        ratio = ymk / none if is_number(none) and is_number(ymk) and none > 0 else None
        ok = None if ratio is None else (ratio <= TARGET_ATE_RATIO and ymk < TARGET_ATE_M)
        missed = missed or (ok is False and ymk < TARGET_ATE_M)
        rows.append([preset, fixed(none, 1, 1000), fixed(ymk, 1, 1000), pct(ratio),
                     pct(1 - ratio) if ratio is not None else "n/a", yes_no(ok)])
    lines += table(["sequence", "ATE none [mm]", "ATE YMK [mm]", "YMK / none", "reduction (paper: 97 %)",
                    "target"], rows)
    if missed:
        lines += ["Where the ratio is missed although YMK is under 2 cm, mode `none` is the reason: RANSAC PnP "
                  "and the robust loss of our tracker reject most points on the walking people, so it drifts "
                  "by centimetres where ORB-SLAM2 on TUM drifts by decimetres.", ""]
    lines += figure(ctx, "trajectory_walking_xyz", "walking_xyz: estimate against ground truth, error in red")
    lines += figure(ctx, "trajectory_walking_halfsphere", "walking_halfsphere: estimate against ground truth")
    lines += figure(ctx, "ate", "ATE per mode")
    return lines


def keyframe_section(ctx: Context) -> list[str]:
    lines = ["## Keyframes against the ORB-SLAM2-style policy (paper Figure 10)", "",
             "Modes none, Y and YM insert keyframes by the ORB-SLAM2-style policy, YMK by the patch keyframe "
             "selector (ALGORITHMS.md section 2). The fair comparison is YM against YMK: same dynamic "
             f"handling, different policy. Issue 5 asks for at least {TARGET_KEYFRAME_REDUCTION:.0%} fewer "
             f"keyframes at no worse ATE; the paper reports {PAPER_KEYFRAME_REDUCTION:.0%} fewer than ORB-SLAM2.",
             ""]
    rows = []
    for preset in ctx.walking_presets:
        counts = {m: get(ctx.walking, (preset, m), "summary", "keyframes") for m in ctx.modes}
        ym, ymk = counts.get("YM"), counts.get("YMK")
        ate_ym = get(ctx.walking, (preset, "YM"), "summary", "ate", "rmse_m")
        ate_ymk = get(ctx.walking, (preset, "YMK"), "summary", "ate", "rmse_m")
        reduction = 1 - ymk / ym if is_number(ym) and is_number(ymk) and ym > 0 else None
        none = counts.get("none")
        reduction_none = 1 - ymk / none if is_number(none) and is_number(ymk) and none > 0 else None
        ok = None
        if reduction is not None and is_number(ate_ym) and is_number(ate_ymk):
            ok = reduction >= TARGET_KEYFRAME_REDUCTION and ate_ymk <= ate_ym
        rows.append([preset] + [str(counts[m]) if counts[m] is not None else "n/a" for m in ctx.modes] +
                    [pct(reduction_none), pct(reduction), f"{fixed(ate_ym, 1, 1000)} / {fixed(ate_ymk, 1, 1000)}",
                     yes_no(ok)])
    lines += table(["sequence"] + [f"{m}" for m in ctx.modes] +
                   ["YMK fewer than none", "YMK fewer than YM", "ATE YM / YMK [mm]", "target (vs YM)"], rows)
    lines += ["The ORB-SLAM2-style policy counts the tracked points against the reference keyframe's map "
              "points with `--reference-min-observations 1` (every map point); with ORB-SLAM2's nMinObs = 3 "
              "and without its RGB-D close-point rule it inserts far fewer keyframes (docs/SLAM.md).", ""]
    lines += figure(ctx, "keyframes", "keyframes per mode")
    return lines


def leak_section(ctx: Context) -> list[str]:
    lines = ["## Dynamic features that survive filtering (paper Figure 4)", "",
             "Leak rate: of the keypoints that lie on a moving body (ground-truth masks of the instances that "
             "move), the fraction still labelled static after the dynamic filter, over all frames (frames.csv "
             "columns `moving_keypoints`, `moving_kept`).", ""]
    rows = []
    for preset in ctx.walking_presets:
        for mode in ctx.modes:
            leak = get(ctx.walking, (preset, mode), "summary", "dynamic_leak") or {}
            rows.append([preset, mode, str(leak.get("moving_keypoints", "n/a")), str(leak.get("moving_kept", "n/a")),
                         pct(leak.get("rate"), 2)])
    lines += table(["sequence", "mode", "keypoints on moving bodies", "kept as static", "leak rate"], rows)
    lines += figure(ctx, "leak", "leak rate per mode")
    return lines


def timing_section(ctx: Context) -> list[str]:
    stages = ["segmentation", "features", "dynamic_filter", "tracking", "keyframe", "local_mapping",
              "loop_closing", "optimisation", "total"]
    columns = [(p, "YMK", ctx.walking) for p in ctx.walking_presets]
    columns += [(p, "combined", ctx.loops) for p in ctx.loop_presets]
    lines = ["## Time per stage (paper Table 5)", "",
             "Median milliseconds per frame (mean in brackets), mode YMK; the loop scenes with loop closing "
             "and correction (pose graph + global bundle adjustment, which runs on few frames: its median "
             "is 0, its mean shows the cost). Segmentation here is reading the simulated masks, not a "
             "network. Measured with " + (f"{ctx.jobs} runs at a time (each single threaded, on a core of its own)"
             if ctx.jobs > 1 else "one run at a time") + " on: " + ctx.machine + ".", ""]
    rows = []
    for stage in stages:
        row = [stage]
        for preset, key, runs in columns:
            st = get(runs, (preset, key), "summary", "stages", stage) or {}
            row.append(f"{fixed(st.get('median_ms'), 1)} ({fixed(st.get('mean_ms'), 1)})")
        rows.append(row)
    lines += table(["stage"] + [p for p, _, _ in columns], rows)
    tracking = [get(ctx.walking, (p, "YMK"), "summary", "stages", "tracking", "median_ms")
                for p in ctx.walking_presets]
    tracking = [t for t in tracking if is_number(t)]
    if tracking:
        worst = max(tracking)
        lines += [f"Tracking median, worst walking sequence: {worst:.1f} ms (issue 5: under "
                  f"{TARGET_TRACKING_MS:.0f} ms, {yes_no(worst < TARGET_TRACKING_MS)}; paper: "
                  f"{PAPER_TRACKING_MS} ms on its hardware).", ""]
    return lines


def map_section(ctx: Context) -> list[str]:
    lines = ["## Semantic map scores (paper Figure 13)", "",
             "walking_xyz, `cge_slam --map` per mode (tracked poses), scored by `cge_eval map map.ot --sequence "
             "DIR --trajectory trajectory.txt --keyframes keyframes.txt` (docs/MAPS.md). Ghost voxels: occupied "
             "voxels that only a moving person ever occupied. Two ghost sets: from every frame at its "
             "ground-truth pose, moved into the map's frame by the ATE alignment (the issue's measure; a few "
             "millimetres of pose error put static floor into it), and from the run's keyframes at the poses "
             "the map was built with (no alignment; a voxel a person pixel reached and no static pixel did). "
             "Integrity and fluctuation of the semantic entities (mode none has no segmentation, hence no "
             "classes and no entities).", ""]
    rows = []
    ghosts: dict[str, dict[str, object]] = {"ground truth": {}, "keyframe poses": {}}
    for mode in ctx.modes:
        m = get(ctx.walking, ("walking_xyz", mode), "map_eval") or {}
        ghosts["ground truth"][mode] = m.get("ghost_voxels")
        ghosts["keyframe poses"][mode] = m.get("ghost_voxels_keyframe_poses")
        rows.append([mode, str(m.get("occupied_voxels", "n/a")), num(m.get("ghost_fraction"), 4),
                     str(m.get("ghost_voxels", "n/a")), str(m.get("ghost_voxels_keyframe_poses", "n/a")),
                     str(m.get("entities", "n/a")), num(m.get("integrity"), 3), num(m.get("fluctuation"), 3)])
    lines += table(["mode", "occupied voxels", "ghost fraction", "ghost voxels (ground-truth poses)",
                    "ghost voxels (keyframe poses)", "entities", "integrity", "fluctuation"], rows)
    for measure, counts in ghosts.items():
        none, ymk = counts.get("none"), counts.get("YMK")
        if is_number(none) and is_number(ymk) and none > 0:
            ratio = ymk / none
            lines += [f"Ghost voxels of YMK against mode none, ghost set at {measure}: {pct(ratio)} (issue 6: "
                      f"under 1 %, {yes_no(ratio < TARGET_GHOST_RATIO)}).", ""]
    return lines


def missed_by_reason(evaluation: dict) -> str:
    """'3: 2 too_few_matches, 1 continuity' from cge_eval loops' missed_* values."""
    total = evaluation.get("missed_loop_queries")
    if not is_number(total):
        return "n/a"
    reasons = [(key[len("missed_"):], value) for key, value in sorted(evaluation.items())
               if key.startswith("missed_") and key != "missed_loop_queries" and is_number(value) and value > 0]
    return f"{total:g}" + (": " + ", ".join(f"{value:g} {reason}" for reason, value in reasons) if reasons else "")


def loop_section(ctx: Context) -> list[str]:
    from results_plots import SCORING_LABELS

    lines = ["## Loop closing: precision and recall (paper Table 6, Figure 18)", "",
             "Mode YMK with loop closing and correction (`--loop-correction pgo+ba`), vocabulary from 20 "
             "frames of walking_xyz. Scorings (`--loop-scoring`, docs/LOOP_CLOSING.md): BoW only "
             "(ORB-SLAM2-like), the paper's CGE ranking, and ours (S_sum times the relative BoW score, the "
             "default). Precision: accepted loops that are ground-truth pairs; query recall: keyframes with a "
             "ground-truth loop for which one was accepted; event recall: revisits (laps) with at least one "
             "accepted loop. Missed: keyframes with a ground-truth loop and no correct detection, by the "
             "loops.csv reason (`cge_eval loops`; wrong_match = accepted against a place that is not a "
             "ground-truth pair). Issue 5 asks for recall 100% at precision 100%.", ""]
    rows = []
    for preset in ctx.loop_presets:
        for scoring in ctx.loop_scorings:
            run = ctx.loops.get((preset, scoring)) or {}
            e = run.get("loops") or {}
            s = run.get("summary") or {}
            rows.append([preset, SCORING_LABELS.get(scoring, scoring), str(e.get("queried_keyframes", "n/a")),
                         f"{e.get('correct_detections', 'n/a')}/{e.get('detections', 'n/a')}",
                         num(e.get("precision"), 3), num(e.get("query_recall"), 3), num(e.get("event_recall"), 3),
                         missed_by_reason(e), str(get(s, "loops", "corrections")), fixed(get(s, "ate", "rmse_m"), 1, 1000),
                         f"{s.get('tracked_frames', 'n/a')}/{s.get('frames', 'n/a')}"])
    lines += table(["scene", "scoring", "keyframes queried", "correct/accepted", "precision", "query recall",
                    "event recall", "missed (by reason)", "corrections", "ATE [mm]", "tracked frames"], rows)
    lines += ["The P-R curves apply a rising threshold to the score that gates each scoring (S_sum, or the "
              "BoW score for BoW only) of the loops the run accepted (`cge_eval loops --curve`); thresholds "
              "below the run's own gate are not explored, and the continuity check is not re-run per "
              "threshold.", ""]
    for preset in ctx.loop_presets:
        lines += figure(ctx, f"pr_{preset}", f"{preset}: precision-recall over the threshold")
    return lines


def study_section(ctx: Context) -> list[str]:
    lines = ["## The entropy measures: collapse and separation", "",
             "`cge_loop_study` on the loop scenes: every studied frame's graph as the loop closer builds it "
             "(ORB features, ground-truth dynamic masks), its degree-degree entropy at alpha = 0.5 with raw "
             "exponents (the paper) and normalised exponents; then S_sum alone for every pair of frames, "
             "labelled by the ground-truth loops. Collapse: the information index I = log2|V| - H lies "
             "within the tool's tolerance (1 bit) of log2|V|, i.e. H <= 1 bit: the degree-degree "
             "distribution puts its mass on one or two nodes (ALGORITHMS.md section 4), and the index "
             "then mostly compares node counts.", ""]
    rows = []
    verdicts = []
    for preset in ctx.loop_presets:
        v = get(ctx.study, preset, "values") or {}
        rows.append([preset, num(v.get("frames"), 6), num(v.get("pairs"), 6), num(v.get("revisit_pairs"), 6),
                     pct(v.get("collapse_fraction_raw")), pct(v.get("collapse_fraction_normalised")),
                     num(v.get("auc_raw"), 3), num(v.get("auc_normalised"), 3),
                     num(v.get("average_precision_raw"), 3), num(v.get("average_precision_normalised"), 3)])
        if is_number(v.get("auc_raw")) and is_number(v.get("auc_normalised")):
            verdicts.append(v["auc_normalised"] > v["auc_raw"])
    lines += table(["scene", "frames", "pairs", "revisit pairs", "collapsed raw", "collapsed normalised",
                    "ROC AUC raw", "ROC AUC normalised", "AP raw", "AP normalised"], rows)
    if verdicts and all(verdicts):
        lines += ["The normalised scaling separates revisits from non-revisits better than the raw index on "
                  "every loop scene (higher ROC AUC), which supports it as the loop closer's default "
                  "(`LoopCloserSettings`, docs/LOOP_CLOSING.md).", ""]
    elif verdicts:
        lines += ["The normalised scaling does **not** separate better on every loop scene; the default "
                  "(normalised) rests on the end-to-end loop figures of docs/LOOP_CLOSING.md, not on S_sum "
                  "alone.", ""]
    lines += figure(ctx, "roc_study", "ROC of S_sum alone, raw against normalised exponents")
    return lines


def provenance(ctx: Context) -> list[str]:
    lines = ["## How these numbers were made", "",
             f"Machine: {ctx.machine}. Wall time per step: " +
             ", ".join(f"{k} {v:.0f} s" for k, v in ctx.steps.items()) + ".", "",
             "<details><summary>Every command the suite ran (paths relative to its work folder)</summary>", "",
             "```"]
    lines += ctx.commands
    lines += ["```", "", "</details>", ""]
    return lines


def render(ctx: Context) -> str:
    p = ctx.plan
    lines = ["# Results", "",
             "Generated by the results suite, examples/results/make_results.py; do not edit by hand. "
             "Regenerate it, with its figures in docs/results/, by one command (Debian 12: "
             "`.ci/install-deps` first, which includes python3-matplotlib; about 13 minutes on 2 cores):", "",
             "```sh",
             "cmake -S . -B build -DCMAKE_BUILD_TYPE=Release && cmake --build build -j2 --target results",
             "```", ""]
    if ctx.quick:
        lines += [f"**Quick run** ({p.walking_frames}-frame walking sequences, {p.loop_frames}-frame loop "
                  "scenes): it checks that the suite works; its numbers do not measure the method.", ""]
    lines += ["Everything below is deterministic (same seeds and tools, same numbers) except the times.", ""]
    for section in (setting, trajectory_section, keyframe_section, leak_section, timing_section, map_section,
                    loop_section, study_section, provenance):
        lines += section(ctx)
    return "\n".join(lines).rstrip() + "\n"
