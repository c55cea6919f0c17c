"""Shared helpers of the Python module's tests: the CLI to compare with, and a PNG reader."""
import os
import struct
import subprocess
import zlib

import numpy as np
import pytest

import hsr


@pytest.fixture(scope="session")
def cli():
    """Runs the `hsr` command line (HSR_CLI, set by ctest); returns (exit status, stderr)."""
    path = os.environ.get("HSR_CLI")
    if not path or not os.path.exists(path):
        pytest.fail("HSR_CLI must name the hsr executable (ctest sets it)")

    def run(*args):
        done = subprocess.run([path, *map(str, args)], capture_output=True, text=True)
        return done.returncode, done.stderr.strip()

    return run


def read_png(path):
    """The pixels of an 8-bit RGB or RGBA PNG as (H, W, C) uint8 (what hsr's writer produces)."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat = 8, b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, color_type = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and color_type in (2, 6)
            channels = 3 if color_type == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(height, 1 + width * channels)
    out = np.zeros((height, width * channels), np.int32)
    for y in range(height):
        f, line = raw[y, 0], raw[y, 1:].astype(np.int32)
        prev = out[y - 1] if y else np.zeros_like(line)
        row = np.zeros_like(line)
        for x in range(line.size):
            a = row[x - channels] if x >= channels else 0
            b = prev[x]
            c = prev[x - channels] if x >= channels else 0
            if f == 0:
                p = 0
            elif f == 1:
                p = a
            elif f == 2:
                p = b
            elif f == 3:
                p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            row[x] = (line[x] + p) & 255
        out[y] = row
    return out.reshape(height, width, channels).astype(np.uint8)


def random_pose(rng, distance=6.0):
    """A world-to-camera pose (4x4) looking at the origin from `distance`, OpenCV axes."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    pose = np.eye(4)
    pose[:3, :3] = R
    pose[:3, 3] = [0.0, 0.0, distance]  # the origin is straight ahead, `distance` away
    return pose


@pytest.fixture(scope="session")
def cubes():
    return hsr.load("builtin:cubes")
