#!/usr/bin/env python3
"""How well COLMAP's retrieval finds the photos that see the same part of a scene, against the true cameras.

For each photo queried in a `vocab_tree_retriever` log (the sfm stage's `10_sfm/logs/retrieval.log`), the share of the
first K photos it retrieved (itself left out) that are among its K nearest by the true cameras: nearness is the angle
between the viewing directions (radians) plus the distance between the centres over the cameras' largest distance.
The truth is a transforms.json or a synthetic scene's ground_truth_cameras.json (camera-to-world matrices, OpenGL
axes); photos are matched by file name.

    python3 bench/retrieval_recall.py TRUTH.json RETRIEVAL.log [RETRIEVAL.log ...] [--k 20]
"""
import argparse
import json
import math
import os
import re

QUERY = re.compile(r"Querying for image (.*) \[\d+/\d+\]")
RETRIEVED = re.compile(r"  image_id=\d+, image_name=(.*), score=")


def true_cameras(path):
    """File name -> (viewing direction, centre) of every frame of a transforms.json-like file."""
    cameras = {}
    for frame in json.load(open(path))["frames"]:
        m = frame["transform_matrix"]
        direction = (-m[0][2], -m[1][2], -m[2][2])  # OpenGL cameras look along -z
        cameras[os.path.basename(frame["file_path"])] = (direction, (m[0][3], m[1][3], m[2][3]))
    return cameras


def retrieved_lists(path):
    """Queried file name -> the file names retrieved for it, best first, itself left out."""
    lists, query = {}, None
    for line in open(path):
        if match := QUERY.match(line):
            query = os.path.basename(match.group(1))
            lists[query] = []
        elif (match := RETRIEVED.match(line)) and query is not None:
            name = os.path.basename(match.group(1))
            if name != query:
                lists[query].append(name)
    return lists


def recall(cameras, lists, k):
    spread = max(math.dist(a[1], b[1]) for a in cameras.values() for b in cameras.values())

    def nearness(a, b):
        cosine = sum(x * y for x, y in zip(a[0], b[0]))
        return math.acos(max(-1.0, min(1.0, cosine))) + math.dist(a[1], b[1]) / spread

    hits = total = 0
    for query, got in lists.items():
        if query not in cameras:
            continue
        others = sorted((nearness(cameras[query], camera), name) for name, camera in cameras.items() if name != query)
        nearest = {name for _, name in others[:k]}
        hits += len(nearest & set(got[:k]))
        total += k
    return hits / total if total else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("truth")
    parser.add_argument("logs", nargs="+")
    parser.add_argument("--k", type=int, default=20)
    args = parser.parse_args()
    cameras = true_cameras(args.truth)
    for log in args.logs:
        lists = retrieved_lists(log)
        print(f"{log}: recall@{args.k} {recall(cameras, lists, args.k):.3f} over {len(lists)} queries")


if __name__ == "__main__":
    main()
