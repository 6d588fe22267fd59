#!/usr/bin/env python3
"""How far the own VIO's covariance, and the default VIO drift model, can be
trusted: both against the simulator's truth.

For every tracking frame of a `viosfm vio` run (the first segment), the yaw
and the position error relative to the first tracking frame (the estimate
aligned to the truth there, in yaw and position) are compared with
  - the VIO's own marginal sigmas (states.csv's sigma_yaw, sigma_p*), and
  - the sigmas the drift model of scene/vio_uncertainty.h predicts between
    that frame and the first one with its default rates (read from the
    header): random walks in time, distance and rotation travelled, the
    scale error, the yaw drift turning the displacement, frame noise.
Prints, per quantity over all runs given, the RMS error, the RMS of each
sigma, and their ratios: 1 is consistent, above 1 overconfident, below 1
pessimistic.

Usage: scripts/vio-covariance-consistency.py GROUNDTRUTH_CSV STATES_CSV [GT STATES ...]
(GROUNDTRUTH_CSV: a simulated sequence's mav0/state_groundtruth_estimate0/data.csv;
STATES_CSV: `viosfm vio SEQ --out DIR`'s DIR/states.csv.)
"""
import bisect
import math
import os
import re
import sys

HEADER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src", "viosfm", "scene",
                      "vio_uncertainty.h")


def model_defaults():
    text = open(HEADER).read()
    body = text[text.index("struct VioUncertaintyModel"):text.index("VioUncertaintyModel Scaled")]
    return {m.group(1): float(m.group(2))
            for m in re.finditer(r"double (\w+) = ([0-9.eE+-]+);", body)}


def qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def qconj(q):
    return (q[0], -q[1], -q[2], -q[3])


def qrot(q, v):
    return qmul(qmul(q, (0.0,) + tuple(v)), qconj(q))[1:]


def yaw_of(q):
    w, x, y, z = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def read_groundtruth(path):
    poses = []
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        f = line.split(",")
        poses.append((int(f[0]), [float(x) for x in f[1:4]], tuple(float(x) for x in f[4:8])))
    return poses


def read_states(path):
    header = None
    frames = []
    for line in open(path):
        f = line.strip().split(",")
        if line.startswith("#"):
            header = [h.strip("# ").split(" ")[0] for h in f]
            continue
        row = dict(zip(header, f))
        if row["status"] != "tracking":
            continue
        frames.append((int(f[0]), [float(row[k]) for k in ("px", "py", "pz")],
                       tuple(float(row[k]) for k in ("qw", "qx", "qy", "qz")),
                       [float(row[k]) for k in ("sigma_yaw", "sigma_px", "sigma_py", "sigma_pz")],
                       int(row["segment"])))
    return frames


def main(args):
    if len(args) < 2 or len(args) % 2:
        sys.exit(__doc__)
    m = model_defaults()
    noise2 = m["position_noise_m"] ** 2 + m["correlated_position_noise_m"] ** 2
    rnoise2 = m["rotation_noise_rad"] ** 2 + m["correlated_rotation_noise_rad"] ** 2
    totals = {}
    for gt_path, states_path in zip(args[0::2], args[1::2]):
        truth = read_groundtruth(gt_path)
        stamps = [g[0] for g in truth]

        def truth_at(t):
            i = bisect.bisect_left(stamps, t)
            for j in (i, i - 1):
                if 0 <= j < len(stamps) and abs(stamps[j] - t) < 2_000_000:
                    return truth[j]
            return None

        frames = read_states(states_path)
        if not frames:
            sys.exit(f"{states_path}: no tracking frame")
        frames = [f for f in frames if f[4] == frames[0][4] and truth_at(f[0])]
        t0, p0, q0, _, _ = frames[0]
        g0 = truth_at(t0)
        dyaw = yaw_of(g0[2]) - yaw_of(q0)
        align = (math.cos(dyaw / 2), 0.0, 0.0, math.sin(dyaw / 2))
        distance = rotation = 0.0
        previous = None
        for t, p, q, sigma, _ in frames:
            g = truth_at(t)
            estimate = [a + b for a, b in zip(qrot(align, [p[i] - p0[i] for i in range(3)]), g0[1])]
            position_error = [g[1][i] - estimate[i] for i in range(3)]
            dq = qmul(g[2], qconj(qmul(align, q)))
            if dq[0] < 0:
                dq = tuple(-x for x in dq)
            yaw_error = 2 * math.atan2(dq[3], dq[0])
            if previous:
                distance += math.dist(previous[0], p)
                r = qmul(qconj(previous[1]), q)
                rotation += 2 * math.acos(min(1.0, abs(r[0])))
            previous = (p, q)
            dt = (t - t0) / 1e9
            yaw_var = (m["yaw_per_sqrt_s"] ** 2 * dt + m["yaw_per_sqrt_m"] ** 2 * distance +
                       m["yaw_per_sqrt_rad"] ** 2 * rotation)
            d = [p[i] - p0[i] for i in range(3)]
            lateral = [-d[1], d[0], 0.0]  # z x d: where the yaw drift turns the displacement
            position_var = [m["position_per_sqrt_s"] ** 2 * dt + m["position_per_sqrt_m"] ** 2 * distance +
                            m["scale_sigma"] ** 2 * d[i] ** 2 + yaw_var / 3 * lateral[i] ** 2 + 2 * noise2
                            for i in range(3)]
            rows = [("yaw (rad)", yaw_error, sigma[0] ** 2, yaw_var + 2 * rnoise2)]
            rows += [(f"{'xyz'[a]} (m)", position_error[a], sigma[1 + a] ** 2, position_var[a])
                     for a in range(3)]
            for key, error, own_var, model_var in rows:
                acc = totals.setdefault(key, [0.0, 0.0, 0.0, 0])
                acc[0] += error ** 2
                acc[1] += own_var
                acc[2] += model_var
                acc[3] += 1
        print(f"{states_path}: {len(frames)} tracking frames, {dt:.0f} s, {distance:.1f} m, "
              f"{rotation:.0f} rad turned")
    print(f"{'':10} {'RMS error':>10} {'own sigma':>10} {'model sigma':>12} {'error/own':>10} "
          f"{'error/model':>12}")
    for key, (e, o, mv, n) in totals.items():
        print(f"{key:10} {math.sqrt(e / n):10.4f} {math.sqrt(o / n):10.4f} {math.sqrt(mv / n):12.4f} "
              f"{math.sqrt(e / o):10.2f} {math.sqrt(e / mv):12.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])
