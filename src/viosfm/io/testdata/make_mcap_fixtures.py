#!/usr/bin/env python3
"""Writes the MCAP fixtures of io/mcap_test from the published specification
(mcap.dev/spec), independently of viosfm's writer: Python's struct and zlib,
and the `lz4` command (Debian's lz4 package) for the LZ4 frames.

  mcap_lz4_no_summary.mcap   two lz4 chunks, no summary section (footer of
                             zeros), every CRC computed (chunk, data section)
  mcap_unchunked_summary.mcap  messages directly in the data section, a
                             summary with schemas, channels and statistics,
                             summary offsets and the summary CRC

Both hold, on /chatter (std_msgs/msg/String), the CDR strings "one", "two",
"three" (log times 100, 200, 300 ns), and on /imu (sensor_msgs/msg/Imu) one
big-endian CDR message (log time 250 ns): stamp 1553411909.072940288, frame
"imu_link", orientation (x y z w) 0.1 -0.2 0.3 0.9, angular velocity 0.5 -0.25
0.125, linear acceleration 0.01 -0.02 9.81, covariances 0 with [0] = -1.

    python3 src/viosfm/io/testdata/make_mcap_fixtures.py src/viosfm/io/testdata
"""
import os
import struct
import subprocess
import sys
import zlib

MAGIC = b"\x89MCAP0\r\n"


def u16(v):
    return struct.pack("<H", v)


def u32(v):
    return struct.pack("<I", v)


def u64(v):
    return struct.pack("<Q", v)


def string(text):
    data = text.encode()
    return u32(len(data)) + data


def record(op, content):
    return bytes([op]) + u64(len(content)) + content


def cdr_string_le(text):
    data = text.encode() + b"\0"
    body = u32(len(data)) + data
    message = b"\x00\x01\x00\x00" + body
    return message + b"\0" * ((4 - len(message) % 4) % 4)


class BigEndianCdr:
    """Plain CDR, big-endian: each primitive aligned to its size from the
    first byte after the 4-byte encapsulation header."""

    def __init__(self):
        self.body = b""

    def align(self, n):
        self.body += b"\0" * ((n - len(self.body) % n) % n)

    def put(self, fmt, value):
        size = struct.calcsize(fmt)
        self.align(size)
        self.body += struct.pack(">" + fmt, value)

    def put_string(self, text):
        data = text.encode() + b"\0"
        self.put("I", len(data))
        self.body += data

    def message(self):
        message = b"\x00\x00\x00\x00" + self.body
        return message + b"\0" * ((4 - len(message) % 4) % 4)


def imu_be():
    cdr = BigEndianCdr()
    cdr.put("i", 1553411909)
    cdr.put("I", 72940288)
    cdr.put_string("imu_link")
    for v in (0.1, -0.2, 0.3, 0.9):
        cdr.put("d", v)
    covariance = [-1.0] + [0.0] * 8
    for v in covariance:
        cdr.put("d", v)
    for v in (0.5, -0.25, 0.125):
        cdr.put("d", v)
    for v in covariance:
        cdr.put("d", v)
    for v in (0.01, -0.02, 9.81):
        cdr.put("d", v)
    for v in covariance:
        cdr.put("d", v)
    return cdr.message()


STRING_DEF = "string data\n"
IMU_DEF = ("std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n"
           "float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n"
           "float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n"
           "float64[9] linear_acceleration_covariance\n")


def schema(sid, name, definition):
    return record(0x03, u16(sid) + string(name) + string("ros2msg") + string(definition))


def channel(cid, sid, topic):
    metadata = string("offered_qos_profiles") + string("")
    return record(0x04, u16(cid) + u16(sid) + string(topic) + string("cdr") +
                  u32(len(metadata)) + metadata)


def message(cid, seq, time, data):
    return record(0x05, u16(cid) + u32(seq) + u64(time) + u64(time) + data)


def lz4_frame(data):
    return subprocess.run(["lz4", "-c", "-q", "--content-size"], input=data,
                          capture_output=True, check=True).stdout


def chunk(records, start, end):
    compressed = lz4_frame(records)
    return record(0x06, u64(start) + u64(end) + u64(len(records)) + u32(zlib.crc32(records)) +
                  string("lz4") + u64(len(compressed)) + compressed)


def lz4_no_summary():
    head = MAGIC + record(0x01, string("ros2") + string("viosfm fixture (python)"))
    first = (schema(1, "std_msgs/msg/String", STRING_DEF) + channel(1, 1, "/chatter") +
             message(1, 0, 100, cdr_string_le("one")) + message(1, 1, 200, cdr_string_le("two")))
    second = (schema(2, "sensor_msgs/msg/Imu", IMU_DEF) + channel(2, 2, "/imu") +
              message(2, 0, 250, imu_be()) + message(1, 2, 300, cdr_string_le("three")))
    data = head + chunk(first, 100, 200) + chunk(second, 250, 300)
    data_end = record(0x0F, u32(zlib.crc32(data)))
    footer = record(0x02, u64(0) + u64(0) + u32(0))
    return data + data_end + footer + MAGIC


def unchunked_summary():
    schemas = schema(1, "std_msgs/msg/String", STRING_DEF) + schema(2, "sensor_msgs/msg/Imu",
                                                                    IMU_DEF)
    channels = channel(1, 1, "/chatter") + channel(2, 2, "/imu")
    data = (MAGIC + record(0x01, string("ros2") + string("viosfm fixture (python)")) + schemas +
            channels + message(1, 0, 100, cdr_string_le("one")) +
            message(1, 1, 200, cdr_string_le("two")) + message(2, 0, 250, imu_be()) +
            message(1, 2, 300, cdr_string_le("three")))
    data += record(0x0F, u32(zlib.crc32(data)))
    summary_start = len(data)
    counts = u16(1) + u64(3) + u16(2) + u64(1)
    statistics = record(0x0B, u64(4) + u16(2) + u32(2) + u32(0) + u32(0) + u32(0) + u64(100) +
                        u64(300) + u32(len(counts)) + counts)
    summary = schemas + channels + statistics
    groups = [(0x03, summary_start, len(schemas)),
              (0x04, summary_start + len(schemas), len(channels)),
              (0x0B, summary_start + len(schemas) + len(channels), len(statistics))]
    summary_offset_start = summary_start + len(summary)
    offsets = b"".join(record(0x0E, bytes([op]) + u64(start) + u64(length))
                       for op, start, length in groups)
    footer_head = bytes([0x02]) + u64(20) + u64(summary_start) + u64(summary_offset_start)
    crc = zlib.crc32(summary + offsets + footer_head)
    return data + summary + offsets + footer_head + u32(crc) + MAGIC


def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(folder, "mcap_lz4_no_summary.mcap"), "wb") as f:
        f.write(lz4_no_summary())
    with open(os.path.join(folder, "mcap_unchunked_summary.mcap"), "wb") as f:
        f.write(unchunked_summary())


if __name__ == "__main__":
    main()
