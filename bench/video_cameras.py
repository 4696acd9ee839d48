#!/usr/bin/env python3
"""The cameras of a video's frames against a reference COLMAP model of frames taken from the same video at a fixed
rate (frame k of the reference is frame k * STEP of the video), through compare_cameras.

Each reference frame is paired with the registered frame of ours nearest it in the video (at most --tolerance video
frames away: the camera moves little in a tenth of a second); both sets go to compare_cameras as transforms.json
under the reference frame's name, which aligns the centres by a similarity and prints the errors.

usage: bench/video_cameras.py WS REFERENCE_SPARSE [--step 10] [--tolerance 3] [--compare build/bench/compare_cameras]
example: bench/video_cameras.py ws_beer ../shared/data/beer_video/reference_sparse/0
"""
import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile


def read_colmap_images(path):
    """name -> camera-to-world 4x4 (OpenGL axes) from COLMAP's images.bin."""
    poses = {}
    with open(path, "rb") as f:
        (count,) = struct.unpack("<Q", f.read(8))
        for _ in range(count):
            _, qw, qx, qy, qz, tx, ty, tz, _ = struct.unpack("<idddddddi", f.read(64))
            name = b""
            while (c := f.read(1)) != b"\0":
                name += c
            (points,) = struct.unpack("<Q", f.read(8))
            f.read(24 * points)
            r = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
                 [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
                 [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
            t = [tx, ty, tz]
            # world_from_cam = [R^T | -R^T t]; OpenGL axes: the camera's y and z flipped.
            rows = []
            for i in range(3):
                centre = -sum(r[j][i] * t[j] for j in range(3))
                rows.append([r[0][i], -r[1][i], -r[2][i], centre])
            poses[name.decode()] = rows + [[0, 0, 0, 1]]
    return poses


def frame_number(name):
    stem = os.path.splitext(os.path.basename(name))[0]
    digits = stem[len(stem.rstrip("0123456789")):]
    return int(digits) if digits else None


def write_transforms(path, poses):
    frames = [{"file_path": name, "transform_matrix": pose} for name, pose in sorted(poses.items())]
    with open(path, "w") as f:
        json.dump({"frames": frames}, f)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("workspace")
    parser.add_argument("reference")
    parser.add_argument("--step", type=int, default=10)
    parser.add_argument("--tolerance", type=int, default=3)
    parser.add_argument("--compare", default=os.path.join(os.path.dirname(__file__), "..", "build", "bench",
                                                          "compare_cameras"))
    args = parser.parse_args()
    reference = read_colmap_images(os.path.join(args.reference, "images.bin"))
    with open(os.path.join(args.workspace, "20_poses", "transforms.json")) as f:
        ours = {frame_number(fr["file_path"]): fr["transform_matrix"] for fr in json.load(f)["frames"]}
    ours.pop(None, None)
    paired_ours, paired_reference = {}, {}
    for name, pose in reference.items():
        k = frame_number(name)
        if k is None or not ours:
            continue
        nearest = min(ours, key=lambda n: abs(n - k * args.step))
        if abs(nearest - k * args.step) <= args.tolerance:
            paired_ours[name] = ours[nearest]
            paired_reference[name] = pose
    print(f"reference frames {len(reference)}, ours registered {len(ours)}, paired {len(paired_ours)} "
          f"(within {args.tolerance} video frames of frame k * {args.step})")
    with tempfile.TemporaryDirectory() as tmp:
        write_transforms(os.path.join(tmp, "ours.json"), paired_ours)
        write_transforms(os.path.join(tmp, "reference.json"), paired_reference)
        return subprocess.call([args.compare, os.path.join(tmp, "ours.json"), os.path.join(tmp, "reference.json")])


if __name__ == "__main__":
    sys.exit(main())
