"""Loop closure's figures against a ground truth (TUM layout), for bench/loop_closure.sh.

  loop_errors.py end GROUNDTRUTH TRAJECTORY
      the end-to-start error: the estimated motion from the first pose to the last against the
      true one, "<metres> <degrees>"
  loop_errors.py loops GROUNDTRUTH LOOPS_CSV SIGMA_M SIGMA_DEG
      each kept loop of sdf_tracker_offline's loops.csv (the relative pose of two submaps' anchors)
      against the truth at the anchors' timestamps: "<kept> <false> <worst metres> <worst degrees>",
      false counting those more than three standard deviations off in either.

Standard library only (Debian's python3 without numpy)."""
import math
import sys


def quaternion_matrix(qx, qy, qz, qw):
    return [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
            [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
            [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]


def pose(values):
    """(R, t) from tx ty tz qx qy qz qw."""
    tx, ty, tz, qx, qy, qz, qw = values
    return quaternion_matrix(qx, qy, qz, qw), [tx, ty, tz]


def transpose(r):
    return [[r[j][i] for j in range(3)] for i in range(3)]


def multiply(r, s):
    return [[sum(r[i][k] * s[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def relative(a, b):
    """a^-1 * b."""
    ra_t = transpose(a[0])
    d = [b[1][i] - a[1][i] for i in range(3)]
    return multiply(ra_t, b[0]), [sum(ra_t[i][k] * d[k] for k in range(3)) for i in range(3)]


def difference(a, b):
    """Metres and degrees between two poses."""
    r, t = relative(a, b)
    cos = max(-1.0, min(1.0, (r[0][0] + r[1][1] + r[2][2] - 1.0) / 2.0))
    return math.sqrt(sum(x * x for x in t)), math.degrees(math.acos(cos))


def read_tum(path):
    poses = []
    with open(path) as f:
        for line in f:
            fields = line.split()
            if not fields or fields[0].startswith('#'):
                continue
            poses.append((float(fields[0]), pose([float(x) for x in fields[1:8]])))
    if not poses:
        sys.exit(f"loop_errors.py: no poses in {path}")
    return poses


def nearest(poses, stamp, within=0.02):
    best = min(poses, key=lambda p: abs(p[0] - stamp))
    if abs(best[0] - stamp) > within:
        sys.exit(f"loop_errors.py: no ground truth within {within} s of {stamp}")
    return best[1]


def end_to_start(groundtruth, trajectory):
    truth, estimate = read_tum(groundtruth), read_tum(trajectory)
    first, last = estimate[0], estimate[-1]
    true_motion = relative(nearest(truth, first[0]), nearest(truth, last[0]))
    estimated_motion = relative(first[1], last[1])
    metres, degrees = difference(true_motion, estimated_motion)
    print(f"{metres:.4f} {degrees:.3f}")


def loops(groundtruth, loops_csv, sigma_m, sigma_deg):
    truth = read_tum(groundtruth)
    kept = false = 0
    worst_m = worst_deg = 0.0
    with open(loops_csv) as f:
        header = f.readline().strip().split(',')
        for line in f:
            row = dict(zip(header, line.strip().split(',')))
            # (A loop to a loaded map's submap has no anchor time of this run: not checked.)
            if row.get('kept') != '1' or not row['from_anchor_time'] or not row['to_anchor_time']:
                continue
            kept += 1
            measured = pose([float(row[k]) for k in ('tx', 'ty', 'tz', 'qx', 'qy', 'qz', 'qw')])
            true_relative = relative(nearest(truth, float(row['from_anchor_time'])),
                                     nearest(truth, float(row['to_anchor_time'])))
            metres, degrees = difference(true_relative, measured)
            worst_m, worst_deg = max(worst_m, metres), max(worst_deg, degrees)
            false += metres > 3 * sigma_m or degrees > 3 * sigma_deg
    print(f"{kept} {false} {worst_m:.4f} {worst_deg:.3f}")


if __name__ == '__main__':
    if len(sys.argv) == 4 and sys.argv[1] == 'end':
        end_to_start(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 6 and sys.argv[1] == 'loops':
        loops(sys.argv[2], sys.argv[3], float(sys.argv[4]), float(sys.argv[5]))
    else:
        sys.exit(__doc__)
