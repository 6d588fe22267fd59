#!/usr/bin/python3
# Strecha's fountain-P11 as viosfm's inputs and truth: OUT/timestamps.txt (the
# photos 1 s apart from 1 s, in name order), OUT/groundtruth_cam.tum (the
# ground-truth cameras as world_from_cam, the world turned so that z points
# up: the photos are upright, up is minus the mean of the cameras' y axes, as
# a gravity-aligned VIO's world would be) and OUT/camera.yaml (K of the
# photos, no distortion). Prints the path length.
#   /usr/bin/python3 scripts/lib/fountain_truth.py DATA OUT
import sys, os, numpy as np
data, out = sys.argv[1], sys.argv[2]
names = sorted(f[:-4] for f in os.listdir(os.path.join(data, "images")) if f.endswith(".jpg"))
cams = []
for n in names:
    v = np.array(open(os.path.join(data, "gt_dense_cameras", n + ".jpg.camera")).read().split(), float)
    K, R, C, wh = v[0:9].reshape(3, 3), v[12:21].reshape(3, 3), v[21:24], v[24:26]
    cams.append((K, R, C, wh))
up = -np.mean([R[:, 1] for _, R, _, _ in cams], axis=0)
up /= np.linalg.norm(up)
z = np.array([0.0, 0.0, 1.0])
axis = np.cross(up, z)
s, c = np.linalg.norm(axis), up @ z
if s < 1e-12:
    W = np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
else:
    a = axis / s
    A = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    W = np.eye(3) + s * A + (1 - c) * A @ A  # turns up onto z
def quat(R):  # Hamilton, x y z w
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    zq = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    return x, y, zq, w
with open(os.path.join(out, "timestamps.txt"), "w") as ts, \
     open(os.path.join(out, "groundtruth_cam.tum"), "w") as gt:
    gt.write("# timestamp tx ty tz qx qy qz qw (world z up)\n")
    for i, (n, (K, R, C, wh)) in enumerate(zip(names, cams)):
        t = i + 1
        ts.write(f"{n}.jpg {t}.0\n")
        Rw, Cw = W @ R, W @ C
        gt.write(f"{t}.000000000 {Cw[0]:.9f} {Cw[1]:.9f} {Cw[2]:.9f} " + " ".join(f"{q:.12f}" for q in quat(Rw)) + "\n")
K, _, _, wh = cams[0]
with open(os.path.join(out, "camera.yaml"), "w") as f:
    f.write(f"""%YAML:1.0
sensor_type: camera
comment: Strecha fountain-P11 (gt_dense_cameras K, no distortion)
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
rate_hz: 1
resolution: [{int(wh[0])}, {int(wh[1])}]
camera_model: pinhole
intrinsics: [{K[0,0]}, {K[1,1]}, {K[0,2]}, {K[1,2]}]
distortion_model: radial-tangential
distortion_coefficients: [0.0, 0.0, 0.0, 0.0]
""")
path = sum(np.linalg.norm(cams[i][2] - cams[i - 1][2]) for i in range(1, len(cams)))
print(f"{len(names)} photos, path {path:.2f} m between the first and the last camera")
