"""The PNG figures of RESULTS.md (matplotlib, Agg backend: no display needed).

Every function takes the runs make_results.py collected and writes one file; make_all returns
{figure key: file name} for the report. Figures are drawn from the tools' output files only.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

DPI = 110
MODE_COLOURS = {"ORB-SLAM2": "#4d4d4d", "none": "#b2182b", "Y": "#ef8a62", "YM": "#67a9cf", "YMK": "#2166ac"}
SERIES_LABELS = {"none": "none (ablation)", "ORB-SLAM2": "ORB-SLAM2 (mean of runs)"}
SCORING_COLOURS = {"bow_only": "#7f7f7f", "cge": "#d95f02", "combined": "#1b9e77"}
SCORING_LABELS = {"bow_only": "BoW only", "cge": "BoW + CGE (paper ranking)", "combined": "BoW + CGE (combined)"}


def _save(fig, path: Path) -> str:
    fig.tight_layout()
    # No timestamps in the PNG metadata: same data, same file.
    fig.savefig(path, dpi=DPI, metadata={"Software": None})
    plt.close(fig)
    return path.name


def _plane_axes(rows: list[dict[str, str]]) -> tuple[str, str]:
    """The two world axes along which the ground truth spreads most (the top view of the motion)."""
    spreads = {}
    for axis in "xyz":
        values = [float(r[f"gt_{axis}"]) for r in rows]
        spreads[axis] = max(values) - min(values) if values else 0.0
    first, second = sorted("xyz", key=lambda a: -spreads[a])[:2]
    return tuple(sorted((first, second)))  # type: ignore[return-value]


def trajectories(path: Path, walking: dict, preset: str, modes: list[str]) -> str | None:
    """Estimated (aligned) against ground-truth positions with the error of every pair drawn
    (the paper's Figures 8 and 9 for ORB-SLAM2 and its method)."""
    available = [m for m in modes if walking.get((preset, m), {}).get("aligned")]
    if not available:
        return None
    fig, axes = plt.subplots(1, len(available), figsize=(4.2 * len(available), 4.2), squeeze=False)
    a, b = _plane_axes(walking[(preset, available[0])]["aligned"])
    for ax, mode in zip(axes[0], available):
        rows = walking[(preset, mode)]["aligned"]
        gx = [float(r[f"gt_{a}"]) for r in rows]
        gy = [float(r[f"gt_{b}"]) for r in rows]
        ex = [float(r[f"est_{a}"]) for r in rows]
        ey = [float(r[f"est_{b}"]) for r in rows]
        for x0, y0, x1, y1 in zip(gx, gy, ex, ey):
            ax.plot([x0, x1], [y0, y1], color="#e41a1c", linewidth=0.6, alpha=0.7)
        ax.plot(gx, gy, color="black", linewidth=1.0, label="ground truth")
        ax.plot(ex, ey, color=MODE_COLOURS.get(mode, "blue"), linewidth=1.0, label="estimate")
        ate = walking[(preset, mode)]["summary"].get("ate", {}).get("rmse_m")
        title = f"{preset}, mode {SERIES_LABELS.get(mode, mode)}"
        if ate is not None:
            title += f"\nATE RMSE {ate * 1000:.1f} mm"
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(f"{a} [m]")
        ax.set_ylabel(f"{b} [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize=7, loc="best")
    return _save(fig, path)


def grouped_bars(path: Path, title: str, ylabel: str, groups: list[str], series: list[str],
                 value, colours: dict[str, str], log: bool = False) -> str:
    """One group of bars per entry of groups, one bar per series; value(group, series) or None."""
    fig, ax = plt.subplots(figsize=(9.0, 3.8))
    width = 0.8 / max(1, len(series))
    for i, name in enumerate(series):
        xs, ys = [], []
        for g, group in enumerate(groups):
            v = value(group, name)
            if v is not None:
                xs.append(g + (i - (len(series) - 1) / 2) * width)
                ys.append(v)
        bars = ax.bar(xs, ys, width=width, color=colours.get(name), label=SERIES_LABELS.get(name, name))
        ax.bar_label(bars, fmt="%.3g", fontsize=6, padding=1)
    ax.set_xticks(range(len(groups)))
    ax.set_xticklabels(groups, fontsize=8)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    if log:
        ax.set_yscale("log")
    ax.legend(fontsize=7, ncol=len(series), loc="upper center", bbox_to_anchor=(0.5, -0.1), frameon=False)
    return _save(fig, path)


def pr_curves(path: Path, loops: dict, preset: str, scorings: list[str]) -> str | None:
    """Precision against query recall over the acceptance threshold (Figure 18)."""
    fig, ax = plt.subplots(figsize=(4.8, 4.0))
    drawn = 0
    for scoring in scorings:
        run = loops.get((preset, scoring))
        if not run or not run["curve"]:
            continue
        points = [(float(r["query_recall"]), float(r["precision"])) for r in run["curve"]
                  if r["precision"] not in ("", "nan") and r["query_recall"] not in ("", "nan")]
        if not points:
            continue
        xs, ys = zip(*points)
        ax.step(xs, ys, where="post", color=SCORING_COLOURS[scoring], label=SCORING_LABELS[scoring], marker=".",
                markersize=3)
        drawn += 1
    if drawn == 0:
        plt.close(fig)
        return None
    ax.set_xlim(-0.02, 1.02)
    ax.set_ylim(-0.02, 1.05)
    ax.set_xlabel("recall (loop queries found)")
    ax.set_ylabel("precision")
    ax.set_title(f"{preset}: P-R over the acceptance threshold", fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    return _save(fig, path)


def roc_points(scores: list[float], labels: list[int]) -> tuple[list[float], list[float]]:
    """ROC curve points (false-positive rate, true-positive rate), ties taken together."""
    positives = sum(labels)
    negatives = len(labels) - positives
    order = sorted(range(len(scores)), key=lambda i: -scores[i])
    fpr, tpr = [0.0], [0.0]
    tp = fp = 0
    i = 0
    while i < len(order):
        j = i
        while j < len(order) and scores[order[j]] == scores[order[i]]:
            tp += labels[order[j]]
            fp += 1 - labels[order[j]]
            j += 1
        fpr.append(fp / negatives if negatives else 0.0)
        tpr.append(tp / positives if positives else 0.0)
        i = j
    return fpr, tpr


def roc_study(path: Path, study: dict, presets: list[str]) -> str | None:
    """ROC of S_sum alone, raw against normalised exponent scaling, per loop scene."""
    available = [p for p in presets if p in study and study[p]["pairs"]]
    if not available:
        return None
    fig, axes = plt.subplots(1, len(available), figsize=(4.2 * len(available), 4.0), squeeze=False)
    for ax, preset in zip(axes[0], available):
        pairs = study[preset]["pairs"]
        labels = [int(r["revisit"]) for r in pairs]
        for column, colour, name in (("s_sum_raw", "#d95f02", "raw (paper)"),
                                     ("s_sum_normalised", "#1b9e77", "normalised")):
            fpr, tpr = roc_points([float(r[column]) for r in pairs], labels)
            ax.plot(fpr, tpr, color=colour, label=name)
        ax.plot([0, 1], [0, 1], color="#bbbbbb", linewidth=0.8, linestyle="--")
        ax.set_xlabel("false-positive rate")
        ax.set_ylabel("true-positive rate")
        ax.set_title(f"{preset}: S_sum alone, revisit vs not", fontsize=9)
        ax.legend(fontsize=7, loc="lower right")
    return _save(fig, path)


def make_all(folder: Path, walking: dict, loops: dict, study: dict, walking_presets: list[str], modes: list[str],
             loop_presets: list[str], loop_scorings: list[str], peer: dict | None = None) -> dict[str, str]:
    """peer: {sequence: {"summary": results_peer.summarise(...)}} of the ORB-SLAM2 runs, or empty."""
    figures: dict[str, str] = {}

    def keep(key: str, name: str | None) -> None:
        if name:
            figures[key] = name

    for preset in ("walking_xyz", "walking_halfsphere"):
        keep(f"trajectory_{preset}", trajectories(folder / f"trajectory_{preset}.png", walking, preset,
                                                  ["none", "YMK"]))

    def peer_mean(group, key):
        stats = ((peer or {}).get(group) or {}).get("summary", {}).get(key)
        return stats["mean"] if stats else None

    with_peer = (["ORB-SLAM2"] if peer else []) + modes

    def summary_value(group, mode, *keys):
        run = walking.get((group, mode))
        value = run["summary"] if run else None
        for key in keys:
            value = value.get(key) if isinstance(value, dict) else None
        return value

    keep("keyframes", grouped_bars(folder / "keyframes.png", "Kept keyframes (none/Y/YM: ORB-SLAM2's RGB-D rule)",
                                   "keyframes", walking_presets, with_peer,
                                   lambda g, m: peer_mean(g, "keyframes") if m == "ORB-SLAM2" else
                                   summary_value(g, m, "keyframes"), MODE_COLOURS))
    keep("ate", grouped_bars(folder / "ate.png", "ATE RMSE per mode and ORB-SLAM2", "ATE RMSE [m]", walking_presets,
                             with_peer, lambda g, m: peer_mean(g, "ate_rmse_m") if m == "ORB-SLAM2" else
                             summary_value(g, m, "ate", "rmse_m"), MODE_COLOURS, log=True))
    keep("leak", grouped_bars(folder / "leak.png", "Features on moving bodies kept as static (leak rate)",
                              "leak rate", walking_presets, modes,
                              lambda g, m: summary_value(g, m, "dynamic_leak", "rate"), MODE_COLOURS))
    for preset in loop_presets:
        keep(f"pr_{preset}", pr_curves(folder / f"pr_{preset}.png", loops, preset, loop_scorings))
    keep("roc_study", roc_study(folder / "roc_s_sum.png", study, loop_presets))
    return figures
