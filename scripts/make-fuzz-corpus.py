#!/usr/bin/env python3
"""Writes the seed corpus of the fuzzers (fuzz/corpus/<parser>/) from the
project's own inputs: a short `viosfm simulate --no-images` sequence (EuRoC
CSV and yaml files, ground truth, the emulated VIO's TUM trajectory), the
COLMAP models of src/viosfm/io/testdata/, and Kalibr files written here
(never from ../shared/data). Files are small (a few kB): the fuzzers grow
their own working corpus from them in the build folder.

    scripts/make-fuzz-corpus.py BUILD_DIR     (BUILD_DIR holds the viosfm binary)
"""
import math
import os
import shutil
import sqlite3
import struct
import subprocess
import sys
import tempfile

SEPARATOR = b"\n#--viosfm-fuzz-next-file--\n"  # fuzz/fuzz_util.h kFileSeparator
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")


def write(parser, name, data):
    folder = os.path.join(CORPUS, parser)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data)


def head(path, lines):
    with open(path, "rb") as f:
        return b"".join(f.readlines()[:lines])


def quaternion_to_matrix(qw, qx, qy, qz):
    return [
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
    ]


def trajectories(sim):
    tum = head(os.path.join(sim, "vio_emulated.tum"), 12)
    write("tum", "simulated_vio.tum", tum)
    write("tum", "comments_and_repeats.tum",
          b"# timestamp tx ty tz qx qy qz qw\n\n1305031102.175304 1 2 3 0 0 0 1\n"
          b"1305031102.175304 1 2 3 0 0 0 1\n1305031102.211 0.5 -0.25 1e-3 0.6132 0.5962 "
          b"-0.3311 -0.3986\n")
    kitti = []
    for line in tum.decode().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        t, x, y, z, qx, qy, qz, qw = map(float, line.split())
        r = quaternion_to_matrix(qw, qx, qy, qz)
        kitti.append(" ".join("%.6e" % v for v in
                              r[0] + [x] + r[1] + [y] + r[2] + [z]))
    write("kitti", "simulated_vio.txt", ("\n".join(kitti) + "\n").encode())
    write("kitti", "identity.txt", b"1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 2 0 0 1 3\n")
    ground_truth = head(os.path.join(sim, "mav0", "state_groundtruth_estimate0", "data.csv"), 10)
    write("euroc_trajectory", "simulated_ground_truth.csv", ground_truth)
    write("euroc_trajectory", "pose_only.csv",
          b"#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z\n100,1,2,3,1,0,0,0\n"
          b"200, 4, 5, 6, 0, 0, 0, 1.0005\n")
    return ground_truth


def euroc(sim, ground_truth):
    mav0 = os.path.join(sim, "mav0")
    # Without rendered images the simulator writes no cam0/data.csv: list
    # its camera stamps as EuRoC names them.
    with open(os.path.join(sim, "camera_stamps.txt")) as f:
        stamps = [line.strip() for line in f if line.strip() and not line.startswith("#")][:8]
    images = ("#timestamp [ns],filename\n" +
              "".join("%s,%s.png\n" % (stamp, stamp) for stamp in stamps)).encode()
    imu = head(os.path.join(mav0, "imu0", "data.csv"), 40)
    write("euroc_csv", "simulated.bin", images + SEPARATOR + imu + SEPARATOR + ground_truth)
    write("euroc_csv", "no_ground_truth.bin", images + SEPARATOR + imu + SEPARATOR)
    write("euroc_csv", "subfolder_names.bin",
          b"#timestamp [ns],filename\n1000,a/1.png\n2000,a/2.png\n" + SEPARATOR +
          b"#t,wx,wy,wz,ax,ay,az\n900,0,0,0,0,0,9.81\n1500,0,0,0,0,0,9.81\n2100,0,0,0,0,0,9.81\n" +
          SEPARATOR)
    with open(os.path.join(mav0, "cam0", "sensor.yaml"), "rb") as f:
        write("euroc_yaml", "simulated_cam0.yaml", f.read())
    with open(os.path.join(mav0, "imu0", "sensor.yaml"), "rb") as f:
        write("euroc_yaml", "simulated_imu0.yaml", f.read())
    write("euroc_yaml", "equidistant.yaml",
          b"%YAML:1.0\nT_BS:\n  cols: 4\n  rows: 4\n"
          b"  data: [0, -1, 0, 0.1, 1, 0, 0, 0.2, 0, 0, 1, 0.3, 0, 0, 0, 1]\n"
          b"rate_hz: 10\nresolution: [640, 480]\ncamera_model: pinhole\n"
          b"intrinsics: [500, 501, 320, 240]\ndistortion_model: equidistant\n"
          b"distortion_coefficients: [0.1, 0.2, 0.3, 0.4]\n"
          b"gyroscope_noise_density: 1e-4\ngyroscope_random_walk: 2e-5\n"
          b"accelerometer_noise_density: 3e-3\naccelerometer_random_walk: 4e-3\n")


def kalibr():
    camchain = (b"cam0:\n  T_cam_imu:\n  - [0.0, -1.0, 0.0, 0.1]\n  - [1.0, 0.0, 0.0, -0.2]\n"
                b"  - [0.0, 0.0, 1.0, 0.05]\n  - [0.0, 0.0, 0.0, 1.0]\n  cam_overlaps: []\n"
                b"  camera_model: pinhole\n  distortion_coeffs: [-0.28, 0.07, 0.0002, 1.8e-05]\n"
                b"  distortion_model: radtan\n  intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
                b"  resolution: [752, 480]\n  rostopic: /cam0/image_raw\n"
                b"  timeshift_cam_imu: 0.0021\n")
    imu = (b"accelerometer_noise_density: 1.86e-03\naccelerometer_random_walk: 4.33e-04\n"
           b"gyroscope_noise_density: 1.87e-04\ngyroscope_random_walk: 2.66e-05\n"
           b"rostopic: /imu0\nupdate_rate: 200.0\n")
    write("kalibr", "camchain_and_imu.bin", camchain + SEPARATOR + imu)
    write("kalibr", "camchain_only.bin", camchain)
    # Extrinsics and noise in cam0, no intrinsics (the layout of the DM-VIO
    # recordings' camchain; numbers made up here).
    write("kalibr", "noise_in_cam0.bin",
          b"cam0:\n  T_cam_imu:\n  - [1, 0.01, -0.005, 0.012]\n  - [-0.01, 1, 0.024, -0.002]\n"
          b"  - [0.005, -0.024, 1, -0.002]\n  - [0.0, 0.0, 0.0, 1.0]\n"
          b"  accelerometer_noise_density: 0.18      # m/s^1.5\n"
          b"  accelerometer_random_walk: 0.024\n  gyroscope_noise_density: 3.7e-05\n"
          b"  gyroscope_random_walk: 2.6e-06\n  integration_sigma: 0.8\n")
    write("kalibr", "imu0_form.bin",
          b"cam0:\n  T_cam_imu: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n"
          b"  distortion_model: equidistant\n  distortion_coeffs: [0.1, 0.01, 0.001, 0.0001]\n"
          b"  intrinsics: [190.9, 190.9, 254.9, 256.8]\n  resolution: [512, 512]\n" + SEPARATOR +
          b"imu0:\n  accelerometer_noise_density: 0.01\n  accelerometer_random_walk: 0.002\n"
          b"  gyroscope_noise_density: 0.0003\n  gyroscope_random_walk: 4.0e-06\n"
          b"  model: calibrated\n  time_offset: 0.0\n  update_rate: 200.0\n")


def colmap_models():
    testdata = os.path.join(ROOT, "src", "viosfm", "io", "testdata")

    def model(folder, names):
        parts = []
        for name in names:
            with open(os.path.join(testdata, folder, name), "rb") as f:
                parts.append(f.read())
        return SEPARATOR.join(parts)

    text = ["cameras.txt", "images.txt", "points3D.txt"]
    binary = ["cameras.bin", "images.bin", "points3D.bin"]
    write("colmap_text", "multicam.bin", model("colmap_multicam_txt", text))
    write("colmap_binary", "multicam.bin", model("colmap_multicam_bin", binary))
    # The fountain's cameras with a two-image, two-point model of our own.
    with open(os.path.join(testdata, "colmap_fountain_txt", "cameras.txt"), "rb") as f:
        cameras = f.read()
    images = (b"# Image list\n1 1 0 0 0 0 0 0 1 a.png\n10 20 1 30 40 2\n"
              b"2 0.99500416527802571 0 0.099833416646828155 0 -1 0 0 1 b.png\n"
              b"12 22 1 33 44 -1\n")
    points = b"# 3D points\n1 0 0 5 255 0 0 0.5 1 0 2 0\n2 1 1 6 0 255 0 0.25 1 1\n"
    write("colmap_text", "two_images.bin", cameras + SEPARATOR + images + SEPARATOR + points)
    # The same as binary.
    cam = struct.pack("<Q", 1) + struct.pack("<IiQQ", 1, 1, 3072, 2048) + struct.pack(
        "<4d", 2759.48, 2764.16, 1520.69, 1006.81)
    img = struct.pack("<Q", 2)
    img += struct.pack("<I7dI", 1, 1, 0, 0, 0, 0, 0, 0, 1) + b"a.png\0" + struct.pack("<Q", 2)
    img += struct.pack("<ddQ", 10, 20, 1) + struct.pack("<ddQ", 30, 40, 2)
    img += struct.pack("<I7dI", 2, math.cos(0.1), 0, math.sin(0.1), 0, -1, 0, 0, 1) + b"b.png\0"
    img += struct.pack("<Q", 1) + struct.pack("<ddQ", 12, 22, 1)
    pts = struct.pack("<Q", 2)
    pts += struct.pack("<Q3d3Bd", 1, 0, 0, 5, 255, 0, 0, 0.5) + struct.pack("<Q", 2)
    pts += struct.pack("<II", 1, 0) + struct.pack("<II", 2, 0)
    pts += struct.pack("<Q3d3Bd", 2, 1, 1, 6, 0, 255, 0, 0.25) + struct.pack("<Q", 1)
    pts += struct.pack("<II", 1, 1)
    write("colmap_binary", "two_images.bin", cam + SEPARATOR + img + SEPARATOR + pts)


def colmap_database():
    schema_file = os.path.join(ROOT, "src", "viosfm", "io", "testdata",
                               "colmap38_database_schema.txt")
    statements = []
    with open(schema_file) as f:
        for line in f:
            if line.startswith("#") or line.startswith("user_version") or not line.strip():
                continue
            kind, name, sql = line.rstrip("\n").split("|", 2)
            if name != "sqlite_sequence":
                statements.append(sql)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "database.db")
        db = sqlite3.connect(path)
        db.execute("PRAGMA page_size = 512")  # a small seed file
        for sql in statements:
            db.execute(sql)
        db.execute("PRAGMA user_version = 3800")
        db.execute("INSERT INTO cameras VALUES(1, 4, 752, 480, ?, 0)",
                   (struct.pack("<8d", 458.654, 457.296, 367.715, 248.875, -0.28, 0.07, 0.0002,
                                1.8e-05),))
        db.execute("INSERT INTO images VALUES(1, 'a.png', 1, NULL, NULL, NULL, NULL, NULL, NULL, "
                   "NULL)")
        db.execute("INSERT INTO images VALUES(2, 'b.png', 1, 1, 0, 0, 0, 0.1, 0.2, 0.3)")
        for image_id in (1, 2):
            keypoints = b"".join(struct.pack("<6f", 10 + i, 20 + i, 1, 0, 0, 1) for i in range(3))
            db.execute("INSERT INTO keypoints VALUES(?, 3, 6, ?)", (image_id, keypoints))
            db.execute("INSERT INTO descriptors VALUES(?, 3, 128, ?)",
                       (image_id, bytes(range(128)) * 3))
        pair_id = 2147483647 * 1 + 2
        matches = struct.pack("<6I", 0, 0, 1, 1, 2, 2)
        db.execute("INSERT INTO matches VALUES(?, 3, 2, ?)", (pair_id, matches))
        identity = struct.pack("<9d", 1, 0, 0, 0, 1, 0, 0, 0, 1)
        db.execute("INSERT INTO two_view_geometries VALUES(?, 3, 2, ?, 2, ?, ?, ?, ?, ?)",
                   (pair_id, matches, identity, identity, identity, struct.pack("<4d", 1, 0, 0, 0),
                    struct.pack("<3d", 1, 0, 0)))
        db.commit()
        db.close()
        with open(path, "rb") as f:
            write("colmap_database", "two_images_file.bin", b"\x01" + f.read())
    # Structured mode (first byte even): a few rows of the fuzzer's own encoding.
    write("colmap_database", "structured_rows.bin", b"\x00" + bytes(range(256)))


def io_other(sim):
    # PLY as viosfm writes it (binary doubles + colours) and an ASCII one
    # with float coordinates and an extra property (as COLMAP's fused.ply).
    binary = (b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\n"
              b"property double y\nproperty double z\nproperty uchar red\nproperty uchar green\n"
              b"property uchar blue\nend_header\n" +
              struct.pack("<3d3B", 1, 2, 3, 255, 0, 0) + struct.pack("<3d3B", -1.5, 0, 1e6, 0, 9, 99))
    write("io_other", "points_binary.ply", binary)
    write("io_other", "points_ascii.ply",
          b"ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 2\nproperty float x\n"
          b"property float y\nproperty float z\nproperty float nx\nend_header\n"
          b"1 2 3 0.5\n4 5 6 -0.5\n")
    # A vocabulary tree of depth 1: the root and two words, 4-dimensional.
    vocabulary = b"VIOSFMVT" + struct.pack("<I4iQ", 1, 2, 1, 4, 2, 3)
    vocabulary += struct.pack("<3i", 1, 2, -1) + struct.pack("<3i", -1, 0, 0)
    vocabulary += struct.pack("<3i", -1, 0, 1)
    vocabulary += struct.pack("<12f", 0.5, 0.5, 0.5, 0.5, 1, 0, 0, 0, 0, 1, 0, 0)
    write("io_other", "vocabulary.bin", vocabulary)
    write("io_other", "pairs.txt", b"# pairs\n1.png 2.png\n2.png 3.png\n")
    write("io_other", "pairs.csv",
          b"image_id1,image_id2,name1,name2,source,num_matches,has_vio_prior,vio_outlier_ratio,"
          b"vio_rotation_only,vio_rejected,num_inliers,accepted,resumed,reason,vio_depth_applied,"
          b"vio_depth_inconsistent_ratio,vio_depth_rejected\n"
          b"1,2,1.png,2.png,temporal,120,1,0.050000,0,0,110,1,0,accepted,1,0.010000,0\n"
          b"1,3,1.png,3.png,retrieval,40,0,nan,0,0,0,0,0,ransac,0,nan,0\n")
    write("io_other", "scene.csv", head(os.path.join(sim, "scene.csv"), 6))


def cdr_string(text):
    data = text.encode() + b"\0"
    message = b"\x00\x01\x00\x00" + struct.pack("<I", len(data)) + data
    return message + b"\0" * ((4 - len(message) % 4) % 4)


def cdr_imu():
    # Little-endian CDR: stamp, frame_id "imu", then (aligned to 8) the
    # orientation, angular velocity and linear acceleration, each followed by
    # its covariance.
    body = struct.pack("<iI", 1700000000, 5) + struct.pack("<I", 4) + b"imu\0"
    body += b"\0" * ((8 - len(body) % 8) % 8)
    body += struct.pack("<4d", 0, 0, 0, 1) + struct.pack("<9d", -1, *([0] * 8))
    body += struct.pack("<3d", 0.1, 0.2, 0.3) + struct.pack("<9d", *([0] * 9))
    body += struct.pack("<3d", 0, 0, 9.81) + struct.pack("<9d", *([0] * 9))
    return b"\x00\x01\x00\x00" + body


def rosbags():
    testdata = os.path.join(ROOT, "src", "viosfm", "io", "testdata")
    # ROS 1: the bags librosbag wrote.
    for compression in ("none", "bz2", "lz4"):
        name = "librosbag_%s.bag" % compression
        with open(os.path.join(testdata, name), "rb") as f:
            write("rosbag", name, f.read())
    # MCAP: the fixtures written from the specification (lz4 chunks without a
    # summary; messages outside chunks with a summary).
    for name in ("mcap_lz4_no_summary.mcap", "mcap_unchunked_summary.mcap"):
        with open(os.path.join(testdata, name), "rb") as f:
            write("mcap", name, f.read())
    # rosbag2 sqlite3: the early layout and the current one, each with a
    # String and an Imu topic (raw mode: first byte odd), and rows of the
    # fuzzer's own encoding (structured mode: first byte even).
    for layout in ("early", "current"):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "bag_0.db3")
            db = sqlite3.connect(path)
            db.execute("PRAGMA page_size = 512")
            if layout == "early":
                db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type "
                           "TEXT NOT NULL,serialization_format TEXT NOT NULL)")
                types = ("std_msgs/String", "sensor_msgs/Imu")
            else:
                db.execute("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro "
                           "TEXT NOT NULL)")
                db.execute("INSERT INTO schema VALUES(4, 'jazzy')")
                db.execute("CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version "
                           "INTEGER NOT NULL,metadata TEXT NOT NULL)")
                db.execute("INSERT INTO metadata VALUES(1, 7, ?)",
                           ("version: 7\nstorage_identifier: sqlite3\ncompression_format: \"\"\n"
                            "compression_mode: \"\"\nrelative_file_paths:\n  - bag_0.db3\n",))
                db.execute("CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type "
                           "TEXT NOT NULL,serialization_format TEXT NOT NULL,offered_qos_profiles "
                           "TEXT NOT NULL,type_description_hash TEXT NOT NULL)")
                types = ("std_msgs/msg/String", "sensor_msgs/msg/Imu")
            db.execute("CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
                       "timestamp INTEGER NOT NULL, data BLOB NOT NULL)")
            extra = ", '', ''" if layout == "current" else ""
            db.execute("INSERT INTO topics VALUES(1, '/text', ?, 'cdr'%s)" % extra, (types[0],))
            db.execute("INSERT INTO topics VALUES(2, '/imu', ?, 'cdr'%s)" % extra, (types[1],))
            db.execute("INSERT INTO messages VALUES(1, 1, 100, ?)", (cdr_string("hello"),))
            db.execute("INSERT INTO messages VALUES(2, 2, 150, ?)", (cdr_imu(),))
            db.execute("INSERT INTO messages VALUES(3, 1, 200, ?)", (cdr_string("world"),))
            db.commit()
            db.close()
            with open(path, "rb") as f:
                write("rosbag2_sqlite", "%s_layout.bin" % layout, b"\x01" + f.read())
    write("rosbag2_sqlite", "structured_rows.bin", b"\x00" + bytes(range(256)))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    viosfm = os.path.join(sys.argv[1], "src", "viosfm", "cli", "viosfm")
    with tempfile.TemporaryDirectory() as tmp:
        sim = os.path.join(tmp, "sim")
        subprocess.run([viosfm, "--log-level", "warning", "simulate", "--scenario", "room",
                        "--duration", "3", "--static-start", "0.5", "--rate", "10", "--no-images", "--seed", "0", "--out",
                        sim], check=True)
        for parser in os.listdir(CORPUS) if os.path.isdir(CORPUS) else []:
            shutil.rmtree(os.path.join(CORPUS, parser))
        ground_truth = trajectories(sim)
        euroc(sim, ground_truth)
        io_other(sim)
    kalibr()
    colmap_models()
    colmap_database()
    rosbags()
    total = sum(len(files) for _, _, files in os.walk(CORPUS))
    print("wrote %d seed files under %s" % (total, CORPUS))


if __name__ == "__main__":
    main()
