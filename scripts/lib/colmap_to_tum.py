#!/usr/bin/python3
# A COLMAP text model's images as a TUM trajectory of world_from_cam poses,
# each image stamped by a "name stamp" file (the timestamps.txt of an image
# folder run), or, with STAMPS "-", by its name (<nanoseconds>.png, as in a
# EuRoC folder). With a EuRoC camera sensor.yaml (its T_BS = body_from_cam)
# the poses are world_from_body instead.
#   /usr/bin/python3 scripts/lib/colmap_to_tum.py MODEL_TXT STAMPS OUT.tum [SENSOR_YAML]
import os, re, sys, numpy as np
model, stamps_file, out_file = sys.argv[1], sys.argv[2], sys.argv[3]
body_from_cam = np.eye(4)
if len(sys.argv) > 4:
    text = open(sys.argv[4]).read()
    block = text[text.index("T_BS"):]
    data = re.search(r"data:\s*\[([^\]]*)\]", block).group(1)
    body_from_cam = np.array([float(v) for v in data.replace("\n", " ").split(",")]).reshape(4, 4)
stamps = None if stamps_file == "-" else dict(line.split() for line in open(stamps_file))
def stamp_of(name):
    if stamps is not None:
        return float(stamps[name])
    return int(os.path.splitext(os.path.basename(name))[0]) * 1e-9
def quaternion(R):  # Hamilton, x y z w
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    return x, y, z, w
rows = []
lines = [l for l in open(f"{model}/images.txt") if not l.startswith("#")]
for header in lines[0::2]:
    v = header.split()
    qw, qx, qy, qz, tx, ty, tz = map(float, v[1:8])
    q = np.array([qw, qx, qy, qz]); w, x, y, z = q / np.linalg.norm(q)
    R = np.array([[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)], [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)], [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]])
    world_from_cam = np.eye(4)
    world_from_cam[:3, :3] = R.T
    world_from_cam[:3, 3] = -R.T @ np.array([tx, ty, tz])
    pose = world_from_cam @ np.linalg.inv(body_from_cam)
    rows.append((stamp_of(v[9]), pose[:3, 3], quaternion(pose[:3, :3])))
with open(out_file, "w") as f:
    for t, C, q in sorted(rows, key=lambda r: r[0]):
        f.write(f"{t:.9f} {C[0]:.9f} {C[1]:.9f} {C[2]:.9f} " + " ".join(f"{c:.12f}" for c in q) + "\n")
