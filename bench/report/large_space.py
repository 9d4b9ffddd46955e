"""Writes the large-space bench's report: per map type, frames tracked, ATE, peak memory, and
ms per frame and map memory in bins of path length (from the ground truth).

usage: large_space.py WALK_DIR WORK_DIR REPORT.md
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

BIN_M = 5.0
WALK_RUNS = ("sparse", "sparse_48mb", "dense")  # the bench's walk: tabled and plotted against its path
BARE_WALLS_RUN = "sparse_bare_walls"  # the same path through the house with bare walls: tabled only


def read_ground_truth(path):
    stamps, positions = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            stamps.append(v[0])
            positions.append(v[1:4])
    return stamps, positions


def path_length_at(stamps, positions):
    """Cumulative path length [m] at each ground-truth stamp."""
    lengths = [0.0]
    for a, b in zip(positions, positions[1:]):
        lengths.append(lengths[-1] + math.dist(a, b))
    return dict(zip(("%.6f" % s for s in stamps), lengths))


def median(values):
    values = sorted(values)
    if not values:
        return float("nan")
    mid = len(values) // 2
    return values[mid] if len(values) % 2 else 0.5 * (values[mid - 1] + values[mid])


def main(walk, work, report):
    stamps, positions = read_ground_truth(os.path.join(walk, "groundtruth.txt"))
    length_of = path_length_at(stamps, positions)
    total_m = max(length_of.values())
    lines = ["# Large spaces: the synthetic house walk", "",
             "Produced by `bash bench/large_space.sh`: %d frames, %.1f m of path at 0.5 m/s through a corridor "
             "and five rooms (a picture or a shelf every metre of their walls), 640x480, Kinect-like noise, "
             "2 threads, default preset. "
             "The dense grid is the default 256^3 cube of 2 cm (5.1 m), placed around the start." % (len(stamps), total_m),
             "", "Runs: `sparse` (MapType=sparse), `sparse_48mb` (the same with MaxMemoryMB=48: blocks away from "
             "the camera swapped to disk and read back when seen again), `dense` (the default grid), and "
             "`%s` (the same walk with bare walls, but for six pictures in the corridor: close to a wall the "
             "view holds one plane, which depth cannot place). Peak resident memory includes the whole-map mesh and "
             "cloud written at the end." % BARE_WALLS_RUN,
             "", "| run | frames tracked | failed | ATE RMSE | ATE max | median ms/frame | p95 | map MiB in memory at the end "
             "| swapped to disk MiB | peak resident MiB |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    fig, (ax_ms, ax_mb) = plt.subplots(1, 2, figsize=(11, 4))
    binned = {}
    for map_type in WALK_RUNS + (BARE_WALLS_RUN,):
        summary_path = os.path.join(work, map_type, "summary.json")
        if not os.path.exists(summary_path):
            lines.append("| %s | run failed: see %s.log | | | | | | | | |" % (map_type, map_type))
            continue
        with open(summary_path) as f:
            s = json.load(f)
        rows = list(csv.DictReader(open(os.path.join(work, map_type, "frames.csv"))))
        ate = s.get("ate_m", {})
        tracked = s["frames"] - s["failed_frames"]
        lines.append("| %s | %d of %d | %d | %.1f cm | %.1f cm | %.1f | %.1f | %.1f | %.1f | %.0f |" % (
            map_type, tracked, s["frames"], s["failed_frames"], 100 * ate.get("rmse", float("nan")),
            100 * ate.get("max", float("nan")), s["ms"]["frame_median"], s["ms"]["frame_p95"],
            float(rows[-1]["map_mb"]), s.get("swapped_mb", 0.0), s["peak_rss_mb"]))
        if map_type not in WALK_RUNS:
            continue
        bins = {}
        for r in rows[1:]:
            length = length_of.get("%.6f" % float(r["timestamp"]))
            if length is None:
                continue
            b = int(length // BIN_M)
            entry = bins.setdefault(b, {"ms": [], "mb": 0.0})
            entry["ms"].append(float(r["tracking_ms"]) + float(r["fusion_ms"]))
            entry["mb"] = float(r["map_mb"])
        binned[map_type] = bins
        xs = [BIN_M * (b + 1) for b in sorted(bins)]
        ax_ms.plot(xs, [median(bins[b]["ms"]) for b in sorted(bins)], marker="o", label=map_type)
        ax_mb.plot(xs, [bins[b]["mb"] for b in sorted(bins)], marker="o", label=map_type)
    lines += ["", "Per %.0f m of path: median ms per frame (tracking + fusion) and the map's memory when the "
              "camera leaves the stretch." % BIN_M, ""]
    header = "| path [m] |" + "".join(" %s ms | %s MiB |" % (m, m) for m in binned)
    lines += [header, "|---|" + "---|---|" * len(binned)]
    all_bins = sorted(set(b for bins in binned.values() for b in bins))
    for b in all_bins:
        row = "| %.0f-%.0f |" % (BIN_M * b, BIN_M * (b + 1))
        for m in binned:
            e = binned[m].get(b)
            row += " %.1f | %.1f |" % (median(e["ms"]), e["mb"]) if e else " | |"
        lines.append(row)
    for ax, label in ((ax_ms, "median ms per frame"), (ax_mb, "map memory [MiB]")):
        ax.set_xlabel("path length [m]")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend()
    true_poses = os.path.join(work, "sparse_true_poses", "summary.json")
    if os.path.exists(true_poses):
        with open(true_poses) as f:
            e = json.load(f).get("single_frame_error_m")
        if e:
            lines += ["", "The tracker alone (`sparse_true_poses`: `--fuse-ground-truth`, each frame tracked from its "
                      "true pose against a map fused at the true poses), translation error per frame: mean %.2f mm, "
                      "median %.2f, p90 %.2f, max %.1f; %d of %d frames over 1 cm." % (
                          1000 * e["mean"], 1000 * e["median"], 1000 * e["p90"], 1000 * e["max"],
                          e["frames_over_1cm"], e["frames"])]
    plot = os.path.splitext(report)[0] + ".png"
    fig.tight_layout()
    fig.savefig(plot, dpi=90)
    lines += ["", "![ms per frame and memory against path length](%s)" % os.path.basename(plot), ""]
    with open(report, "w") as f:
        f.write("\n".join(lines))


if __name__ == "__main__":
    main(*sys.argv[1:4])
