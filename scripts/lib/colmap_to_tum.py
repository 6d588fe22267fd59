#!/usr/bin/python3
# A COLMAP text model's images as a TUM trajectory of world_from_cam poses,
# each image stamped by a "name stamp" file (the timestamps.txt of an image
# folder run):
#   /usr/bin/python3 scripts/lib/colmap_to_tum.py MODEL_TXT TIMESTAMPS OUT.tum
import sys, numpy as np
model, stamps_file, out_file = sys.argv[1], sys.argv[2], sys.argv[3]
stamps = dict(line.split() for line in open(stamps_file))
rows = []
lines = [l for l in open(f"{model}/images.txt") if not l.startswith("#")]
for header in lines[0::2]:
    v = header.split()
    qw, qx, qy, qz, tx, ty, tz = map(float, v[1:8])
    q = np.array([qw, qx, qy, qz]); w, x, y, z = q / np.linalg.norm(q)
    R = np.array([[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)], [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)], [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]])
    C = -R.T @ np.array([tx, ty, tz])
    # world_from_cam rotation R^T: its quaternion is the conjugate
    rows.append((float(stamps[v[9]]), C, (-x, -y, -z, w)))
with open(out_file, "w") as f:
    for t, C, q in sorted(rows, key=lambda r: r[0]):
        f.write(f"{t:.9f} {C[0]:.9f} {C[1]:.9f} {C[2]:.9f} " + " ".join(f"{c:.12f}" for c in q) + "\n")
