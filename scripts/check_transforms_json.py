#!/usr/bin/env python3
"""Loads a transforms.json the way nerfstudio's and instant-ngp's loaders read
it, checks it against nerfstudio's documented convention
(docs.nerf.studio/quickstart/data_conventions.html), and, given a COLMAP text
model of the same images, checks that the poses and intrinsics are that
model's (COLMAP's cam_from_world in OpenCV camera axes; nerfstudio's
camera-to-world in OpenGL axes: +x right, +y up, +z back).

    check_transforms_json.py EXPORT/transforms.json [--colmap-model RUN/model_txt]
                             [--tolerance 1e-9]

Python 3 standard library only. Prints one line per check and exits 1 on
the first failure.
"""
import argparse
import json
import math
import os
import sys

MODELS = {
    # camera_model: distortion keys nerfstudio reads for it
    "PINHOLE": [],
    "OPENCV": ["k1", "k2", "p1", "p2"],
    "OPENCV_FISHEYE": ["k1", "k2", "k3", "k4"],
}


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(len(b))) for j in range(len(b[0]))]
            for i in range(len(a))]


def transpose(a):
    return [list(row) for row in zip(*a)]


def quaternion_to_matrix(w, x, y, z):
    n = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def determinant(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def read_colmap_text_model(folder):
    """cameras.txt and images.txt of a COLMAP text model (COLMAP's format)."""
    cameras = {}
    with open(os.path.join(folder, "cameras.txt")) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            fields = line.split()
            cameras[int(fields[0])] = (fields[1], int(fields[2]), int(fields[3]),
                                       [float(v) for v in fields[4:]])
    images = {}
    with open(os.path.join(folder, "images.txt")) as f:
        lines = [line for line in f if not line.startswith("#")]
    for i in range(0, len(lines), 2):  # a pose line, then a points line
        fields = lines[i].split()
        if not fields:
            continue
        qw, qx, qy, qz, tx, ty, tz = (float(v) for v in fields[1:8])
        images[fields[9]] = (int(fields[8]), quaternion_to_matrix(qw, qx, qy, qz), [tx, ty, tz])
    return cameras, images


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("transforms")
    parser.add_argument("--colmap-model", help="COLMAP text model folder of the same images")
    parser.add_argument("--tolerance", type=float, default=1e-9)
    args = parser.parse_args()
    folder = os.path.dirname(os.path.abspath(args.transforms))
    with open(args.transforms) as f:
        data = json.load(f)

    # Intrinsics at the top level, as the convention allows for a shared camera.
    model = data.get("camera_model", "OPENCV")
    if model not in MODELS:
        fail("camera_model %r is not one of %s" % (model, sorted(MODELS)))
    for key in ["fl_x", "fl_y", "cx", "cy"] + MODELS[model]:
        if not isinstance(data.get(key), (int, float)):
            fail("top-level %r must be a number" % key)
    for key in ["w", "h"]:
        if not isinstance(data.get(key), int) or data[key] <= 0:
            fail("top-level %r must be a positive integer" % key)
    if not 0 < data["cx"] < data["w"] or not 0 < data["cy"] < data["h"]:
        fail("principal point (%g, %g) outside the %dx%d image" %
             (data["cx"], data["cy"], data["w"], data["h"]))
    print("ok: camera %s %dx%d, fl %.3f %.3f, c %.3f %.3f" %
          (model, data["w"], data["h"], data["fl_x"], data["fl_y"], data["cx"], data["cy"]))
    if "ply_file_path" in data:
        ply = os.path.join(folder, data["ply_file_path"])
        with open(ply, "rb") as f:
            if f.read(4) != b"ply\n":
                fail("%s is not a PLY file" % ply)
        print("ok: ply_file_path %s" % data["ply_file_path"])

    frames = data.get("frames")
    if not isinstance(frames, list) or not frames:
        fail("'frames' must be a non-empty list")
    flip = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]  # OpenGL <-> OpenCV camera axes
    poses = {}
    for i, frame in enumerate(frames):
        path = frame.get("file_path")
        if not isinstance(path, str) or os.path.isabs(path):
            fail("frame %d: file_path must be a relative path" % i)
        if not os.path.isfile(os.path.join(folder, path)):
            fail("frame %d: %s does not exist (relative to %s)" % (i, path, folder))
        m = frame.get("transform_matrix")
        if (not isinstance(m, list) or len(m) != 4 or
                any(not isinstance(r, list) or len(r) != 4 for r in m)):
            fail("frame %d: transform_matrix must be 4x4" % i)
        if m[3] != [0, 0, 0, 1]:
            fail("frame %d: last row of transform_matrix is %s" % (i, m[3]))
        rotation = [row[:3] for row in m[:3]]
        rtr = matmul(transpose(rotation), rotation)
        error = max(abs(rtr[r][c] - (r == c)) for r in range(3) for c in range(3))
        if error > 1e-9 or determinant(rotation) < 0:
            fail("frame %d: rotation not orthonormal (%g) or a reflection" % (i, error))
        centre = [m[r][3] for r in range(3)]
        # camera-to-world in OpenCV axes, then world-to-camera
        cv_rotation = matmul(rotation, flip)
        cam_from_world = transpose(cv_rotation)
        translation = [-sum(cam_from_world[r][k] * centre[k] for k in range(3)) for r in range(3)]
        poses[os.path.basename(path)] = (cam_from_world, translation, centre)
    print("ok: %d frames, files exist, transform_matrix rigid" % len(frames))

    if args.colmap_model:
        cameras, images = read_colmap_text_model(args.colmap_model)
        if len(cameras) != 1:
            fail("the COLMAP model has %d cameras" % len(cameras))
        name, width, height, params = next(iter(cameras.values()))
        if (width, height) != (data["w"], data["h"]):
            fail("image size %dx%d, COLMAP model %dx%d" % (data["w"], data["h"], width, height))
        # COLMAP's and nerfstudio's principal points share a convention.
        fx, fy, cx, cy = ((params[0], params[0], params[1], params[2]) if len(params) in (3, 4, 5)
                          else params[:4])
        for key, value in [("fl_x", fx), ("fl_y", fy), ("cx", cx), ("cy", cy)]:
            if abs(data[key] - value) > args.tolerance:
                fail("%s %.17g, COLMAP model %.17g" % (key, data[key], value))
        print("ok: intrinsics equal the COLMAP model's (%s)" % name)
        if set(poses) != set(images):
            fail("frames %d, COLMAP images %d, or other names" % (len(poses), len(images)))
        worst_rotation = worst_position = 0.0
        for image_name, (rotation, translation, centre) in poses.items():
            _, colmap_rotation, colmap_translation = images[image_name]
            worst_rotation = max(worst_rotation, max(abs(rotation[r][c] - colmap_rotation[r][c])
                                                     for r in range(3) for c in range(3)))
            colmap_centre = [-sum(colmap_rotation[k][r] * colmap_translation[k] for k in range(3))
                             for r in range(3)]
            worst_position = max(worst_position,
                                 max(abs(centre[r] - colmap_centre[r]) for r in range(3)))
        if worst_rotation > args.tolerance or worst_position > args.tolerance:
            fail("poses differ from the COLMAP model: rotation %g, position %g m (tolerance %g)" %
                 (worst_rotation, worst_position, args.tolerance))
        print("ok: %d poses equal the COLMAP model's: rotation elements within %.1e, camera "
              "centres within %.1e m" % (len(poses), worst_rotation, worst_position))
    print("transforms.json OK")


if __name__ == "__main__":
    main()
