#!/usr/bin/env python3
"""Aggregates the benchmark runs (summary.json of each sdf_tracker_offline run) into a dated
markdown + JSON report and two plots: frame time against voxel count (the paper's Fig. 6) and
accuracy per sequence and preset."""
import datetime
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import summaries  # noqa: E402  (bench/report/summaries.py, beside this script)

# The reference release, built and run on this machine kind (figures given in the issue).
REFERENCE_MS = 176.0
REFERENCE_ATE_M = 0.031
TARGET_MS_256 = 33.0
TARGET_MS_200 = 29.0
TARGET_RSS_512_MB = 1024.0


def fmt(value, digits=1, scale=1.0):
    return "-" if value is None else f"{value * scale:.{digits}f}"


def ate_cm(run):
    return run.get("ate_m", {}).get("rmse") * 100 if "ate_m" in run else None


def main(runs_dir, results_dir):
    runs = summaries.load(runs_dir)
    if not runs:
        sys.exit("no runs with a summary.json under " + runs_dir)
    today = datetime.date.today().isoformat()
    lines = [f"# sdf_tracker benchmark, {today}", "",
             "Machine: 2 cores, no GPU. Times are medians (and 95th percentiles) of per-frame processing "
             "inside the runner: tracking + fusion (+ ray casting where listed), file reading excluded. "
             "ATE is the RMSE after rigid alignment (TUM definition). Frames the tracker flags as failed "
             "are counted; their pose is the held one.", ""]

    # Targets of the speed issue.
    lines += ["## Targets (7-Scenes redkitchen, 640x480, 2 threads)", "",
              "| what | measured | target | reference release |", "|---|---|---|---|"]
    targets = {}
    for key, label, target in (("grid_256", "256^3 grid of 2 cm", TARGET_MS_256),
                               ("reference_200_2cm", "200^3 grid of 2 cm", TARGET_MS_200)):
        if key in runs:
            ms = runs[key]["ms"]["frame_median"]
            targets[key] = {"ms": ms, "target_ms": target, "met": ms <= target, "speedup": REFERENCE_MS / ms}
            lines.append(f"| {label}: median ms per frame | {ms:.1f} (p95 {runs[key]['ms']['frame_p95']:.1f}); "
                         f"{REFERENCE_MS / ms:.1f}x the reference | <= {target:.0f} | {REFERENCE_MS:.0f} |")
            lines.append(f"| {label}: ATE RMSE | {fmt(ate_cm(runs[key]), 2)} cm, {runs[key]['failed_frames']} failed "
                         f"| <= 1.5 cm (aim) | {REFERENCE_ATE_M * 100:.1f} cm |")
    if "compact_512_1cm" in runs:
        rss = runs["compact_512_1cm"]["peak_rss_mb"]
        targets["compact_512"] = {"peak_rss_mb": rss, "met": rss <= TARGET_RSS_512_MB}
        lines.append(f"| 512^3 grid (1 cm), compact voxels: peak resident memory | {rss:.0f} MiB "
                     f"(grid {runs['compact_512_1cm']['grid_mb']:.0f} MiB) | <= 1024 MiB | - |")
    lines.append("")

    # Presets x sequences.
    sequences = sorted({n.split("__", 1)[1] for n in runs if n.startswith("preset_")})
    presets = ["default", "paper", "reference"]
    lines += ["## Accuracy and speed per sequence and preset (2 threads)", "",
              "| sequence | " + " | ".join(f"{p}: ATE [mm], failed, ms" for p in presets) + " |",
              "|---" * (len(presets) + 1) + "|"]
    for seq in sequences:
        cells = []
        for p in presets:
            r = runs.get(f"preset_{p}__{seq}")
            cells.append("-" if r is None else
                         f"{fmt(r.get('ate_m', {}).get('rmse'), 1, 1000)}, {r['failed_frames']}, "
                         f"{r['ms']['frame_median']:.1f}")
        lines.append(f"| {seq} | " + " | ".join(cells) + " |")
    lines.append("")

    # Ablation.
    ablations = sorted({n.split("__")[0] for n in runs if n.startswith("ablation_")})
    if ablations:
        ab_sequences = sorted({n.split("__", 1)[1] for n in runs if n.startswith("ablation_")})
        lines += ["## What each improvement of the default preset buys", "",
                  "ATE RMSE with the default preset, and with one improvement switched off.", "",
                  "| variant | " + " | ".join(ab_sequences) + " |", "|---" * (len(ab_sequences) + 1) + "|"]
        row = [fmt(runs.get(f"preset_default__{s}", {}).get("ate_m", {}).get("rmse"), 2, 1000) + " mm"
               for s in ab_sequences]
        lines.append("| default | " + " | ".join(row) + " |")
        for a in ablations:
            row = [fmt(runs.get(f"{a}__{s}", {}).get("ate_m", {}).get("rmse"), 2, 1000) + " mm" for s in ab_sequences]
            lines.append(f"| {a.replace('ablation_', '').replace('_', ' ')} | " + " | ".join(row) + " |")
        lines.append("")

    # Stages, threads, compact.
    lines += ["## Where the time goes (redkitchen, default preset)", "",
              "| run | frame | tracking | fusion | ray casting | peak memory | ATE |", "|---|---|---|---|---|---|---|"]
    for key in ("raycast_default", "threads_1", "grid_256", "compact_256"):
        if key in runs:
            m = runs[key]["ms"]
            lines.append(f"| {key} ({runs[key].get('threads', '?')} threads) | {m['frame_median']:.1f} / "
                         f"{m['frame_p95']:.1f} | {m['tracking_median']:.1f} / {m['tracking_p95']:.1f} | "
                         f"{m['fusion_median']:.1f} / {m['fusion_p95']:.1f} | "
                         f"{m['raycast_median']:.1f} / {m['raycast_p95']:.1f} | {runs[key]['peak_rss_mb']:.0f} MiB | "
                         f"{fmt(ate_cm(runs[key]), 2)} cm |")
    lines += ["", "Median / 95th percentile in ms; ray casting only where the run asked for it.", ""]

    # Grid sweep and plots.
    grid = sorted((r["voxel_count"], r) for n, r in runs.items() if n.startswith("grid_"))
    if grid:
        lines += ["## Frame time against voxel count (redkitchen, 2 cm voxels, 2 threads)", "",
                  "| grid | voxels | frame ms | tracking ms | fusion ms | ATE |", "|---|---|---|---|---|---|"]
        for count, r in grid:
            lines.append(f"| {r['grid'][0]}^3 | {count / 1e6:.1f} M | {r['ms']['frame_median']:.1f} | "
                         f"{r['ms']['tracking_median']:.1f} | {r['ms']['fusion_median']:.1f} | {fmt(ate_cm(r), 2)} cm |")
        lines.append("")
        fig, ax = plt.subplots(figsize=(7, 4))
        xs = [c / 1e6 for c, _ in grid]
        for stage in ("frame", "tracking", "fusion"):
            ax.plot(xs, [r["ms"][f"{stage}_median"] for _, r in grid], marker="o", label=stage)
        ax.set_xlabel("voxels [millions]")
        ax.set_ylabel("median ms per frame")
        ax.set_title("Frame time against voxel count (cf. the paper's Fig. 6)")
        ax.grid(True, alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(results_dir, f"{today}_frame_time_vs_voxels.png"), dpi=100)
        plt.close(fig)
    if sequences:
        fig, ax = plt.subplots(figsize=(8, 4))
        width = 0.25
        for i, p in enumerate(presets):
            values = [runs.get(f"preset_{p}__{s}", {}).get("ate_m", {}).get("rmse", 0) * 1000 for s in sequences]
            ax.bar([x + i * width for x in range(len(sequences))], values, width, label=p)
        ax.set_xticks([x + width for x in range(len(sequences))])
        ax.set_xticklabels([s.replace("synthetic_", "syn ") for s in sequences], rotation=15)
        ax.set_ylabel("ATE RMSE [mm]")
        ax.set_yscale("log")
        ax.set_title("Accuracy per sequence and preset")
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(results_dir, f"{today}_accuracy_per_sequence.png"), dpi=100)
        plt.close(fig)
        lines += [f"![frame time against voxel count]({today}_frame_time_vs_voxels.png)", "",
                  f"![accuracy per sequence]({today}_accuracy_per_sequence.png)", ""]

    with open(os.path.join(results_dir, f"{today}.md"), "w") as f:
        f.write("\n".join(lines))
    with open(os.path.join(results_dir, f"{today}.json"), "w") as f:
        json.dump({"date": today, "targets": targets, "runs": runs}, f, indent=1, sort_keys=True)
    print("\n".join(lines))
    print(f"\nreport: {os.path.join(results_dir, today + '.md')}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
