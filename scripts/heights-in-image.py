#!/usr/bin/env python3
"""Heights above the floor of things seen in one image of a model.

    scripts/heights-in-image.py MODEL_TXT IMAGE FLOOR=X0,Y0,X1,Y1 NAME=X0,Y0,X1,Y1 ...

MODEL_TXT: a model in COLMAP's text format (a run's model_txt/), gravity
aligned with z up (as `viosfm run` writes it). IMAGE: an image name of the
model, or its stamp. Each box is a pixel rectangle of that image; the script
takes the 3D points the image observes inside the box and prints their
number and median height (z), and for every box but FLOOR its height above
FLOOR's median. A scene's objects of known height (a door handle, a light
switch, a wall socket, a desk) then check the model's metric scale without
ground truth: heights scale with it.
"""
import statistics
import sys


def parse_box(text):
    name, _, numbers = text.partition("=")
    values = [float(v) for v in numbers.split(",")]
    if not name or len(values) != 4:
        sys.exit(f"error: box '{text}': expected NAME=X0,Y0,X1,Y1")
    return name, values


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    model, image = sys.argv[1], sys.argv[2]
    boxes = [parse_box(arg) for arg in sys.argv[3:]]
    if boxes[0][0] != "FLOOR":
        sys.exit("error: the first box must be FLOOR=X0,Y0,X1,Y1")
    heights = {}
    with open(f"{model}/points3D.txt") as points_file:
        for line_number, line in enumerate(points_file, 1):
            if line.startswith("#") or not line.strip():
                continue
            fields = line.split()
            try:
                heights[int(fields[0])] = float(fields[3])
            except (IndexError, ValueError):
                sys.exit(f"error: {model}/points3D.txt:{line_number}: expected POINT3D_ID X Y Z ...")
    with open(f"{model}/images.txt") as images_file:
        lines = [line for line in images_file if not line.startswith("#")]
    observations = None
    for k in range(0, len(lines) - 1, 2):
        fields = lines[k].split()
        if len(fields) >= 10 and (fields[9] == image or fields[9].rsplit(".", 1)[0] == image):
            values = lines[k + 1].split()
            observations = [(float(values[i]), float(values[i + 1]), int(values[i + 2]))
                            for i in range(0, len(values) - 2, 3)]
            break
    if observations is None:
        sys.exit(f"error: {model}/images.txt: no image named '{image}'")
    floor = None
    for name, (x0, y0, x1, y1) in boxes:
        zs = [heights[p] for x, y, p in observations
              if p >= 0 and p in heights and x0 <= x <= x1 and y0 <= y <= y1]
        if not zs:
            print(f"{name}: no observed points in the box")
            continue
        z = statistics.median(zs)
        if name == "FLOOR":
            floor = z
            print(f"FLOOR: {len(zs)} points, median z {z:+.3f}")
        elif floor is not None:
            print(f"{name}: {len(zs)} points, median z {z:+.3f}, {z - floor:.3f} above the floor")
        else:
            print(f"{name}: {len(zs)} points, median z {z:+.3f}")


if __name__ == "__main__":
    main()
