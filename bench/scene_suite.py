#!/usr/bin/env python3
"""The scene suite: every shared scene ($P2N_DATA_DIR, else the team's ../shared/data) at a short and a normal
budget, one table.

A default changes only when this table shows that no scene loses more than 0.3 dB at either budget. Each scene is
imported (or solved by COLMAP) once; each budget then trains the field and bakes the splats on a copy of that
workspace, and the render stage scores the field on whole held-out images. The table gives, per scene and budget,
the held-out PSNR and SSIM of the field and of the splats, samples a ray, seconds per stage and the warnings the
product raised; the photo scenes with surveyed cameras also get their camera error; last, the machine and the
suite's own time. Run it alone on the machine (nothing else running): it measures time.

    python3 bench/scene_suite.py OUT [--scenes fox,fern,...] [--budgets fast,default,lego_200@20,...] [-- OPTIONS...]

OPTIONS go to every run, the import and sfm's too (e.g. `-- --train.distortion 0`, to measure a change against
the defaults).
OUT/suite.md is the table; OUT/<scene>/<budget>/ the workspaces.
"""

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DATA = os.environ.get("P2N_DATA_DIR") or os.path.join(ROOT, "..", "shared", "data")
BIN = os.path.join(ROOT, "build", "cli", "photo2nerf")
COMPARE = os.path.join(ROOT, "build", "bench", "compare_cameras")

# name: (input, kind, surveyed cameras for the sfm check or None)
SCENES = {
    "fox": ("fox", "real capture (instant-ngp cameras)", None),
    "fern": ("fern", "forward-facing (LLFF)", None),
    "lego": ("lego", "object on white (Blender)", None),
    "mic": ("mic", "object on white (Blender)", None),
    "lego_200": ("lego_200/lego_200x200.npz", "object on white (.npz, 200 px)", None),
    "maryrose": ("maryrose", "real object capture (LLFF cameras, masks)", None),
    "herzjesu_p25": ("herzjesu_p25/images", "photos, COLMAP (surveyed cameras)",
                     "herzjesu_p25/reference_transforms.json"),
    "entry_p10": ("entry_p10/images", "10 photos, COLMAP (surveyed cameras)", "entry_p10/reference_transforms.json"),
    "beer_video": ("beer_video/Beer.mp4", "phone video, COLMAP", None),
    "snowmiku_plush": ("snowmiku_plush/images", "97 phone photos around a plush, COLMAP", None),
    "computer_mouse": ("computer_mouse/images", "59 phone photos around a mouse, COLMAP", None),
}
# Budget name: (train.preset, train.time_budget or None for the preset's, stages run, scenes or None for all).
# default@300 is the field alone at 5 minutes, the budget of the best figures so far (docs/benchmarks.md).
BUDGETS = {
    "fast": ("fast", None, "splat", None),
    "default": ("default", None, "splat", None),
    "lego_200@20": ("default", 20, "train", ["lego_200"]),
    "lego_200@60": ("default", 60, "train", ["lego_200"]),
    "default@300": ("default", 300, "train", ["fox", "fern", "lego"]),
}
TIMED_STAGES = ["sfm", "poses", "train", "splat", "render"]


def run(command, log):
    with open(log, "a") as out:
        out.write("$ " + " ".join(command) + "\n")
        out.flush()
        subprocess.run(command, stdout=out, stderr=subprocess.STDOUT, check=True)


def read_json(path):
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def stage_seconds(ws, stage):
    for folder in sorted(os.listdir(ws)):
        manifest = read_json(os.path.join(ws, folder, "manifest.json"))
        if manifest and manifest.get("stage") == stage:
            return manifest.get("wall_seconds")
    return None


def fmt(value, digits=2):
    return "-" if value is None else f"{value:.{digits}f}"


def prepare(scene, out, extra):
    """The scene's workspace up to its cameras (shared by every budget)."""
    source, _, _ = SCENES[scene]
    base = os.path.join(out, scene, "poses")
    os.makedirs(os.path.join(out, scene), exist_ok=True)
    if not os.path.exists(os.path.join(base, "20_poses", "manifest.json")):
        shutil.rmtree(base, ignore_errors=True)
        run([BIN, "run", os.path.join(DATA, source), "-w", base, "--until", "poses", "--run.progress", "none"] + extra,
            os.path.join(out, scene, "log.txt"))
    return base


def run_budget(scene, budget, base, out, extra):
    preset, seconds, until, _ = BUDGETS[budget]
    ws = os.path.join(out, scene, budget)
    shutil.rmtree(ws, ignore_errors=True)
    shutil.copytree(base, ws, symlinks=True)
    log = os.path.join(out, scene, "log.txt")
    command = [BIN, "run", "-w", ws, "--until", until, "--train.preset", preset, "--run.progress", "none"]
    if seconds:
        command += ["--train.time_budget", str(seconds)]
    run(command + extra, log)
    # The field on whole held-out images (the splats' are in their report).
    run([BIN, "render", "-w", ws, "--render.source", "field", "--render.path", "none", "--render.video", "false",
         "--run.progress", "none"], log)
    return ws


def row(scene, budget, ws):
    train = read_json(os.path.join(ws, "30_train", "train_report.json")) or {}
    splat = read_json(os.path.join(ws, "35_splat", "splat_report.json")) or {}
    field = read_json(os.path.join(ws, "40_render", "eval.json")) or {}
    warnings = [w["code"] for w in train.get("warnings", []) + splat.get("warnings", [])]
    seconds = " / ".join(fmt(stage_seconds(ws, s), 0) for s in TIMED_STAGES)
    return (f"| {scene} | {budget} | {fmt(field.get('psnr'))} | {fmt(field.get('ssim'), 3)} | "
            f"{fmt(splat.get('heldout_psnr'))} | {fmt(splat.get('heldout_ssim'), 3)} | "
            f"{fmt(train.get('samples_per_ray_rendered'), 1)} | {train.get('steps', '-')} | {seconds} | "
            f"{', '.join(warnings) or '-'} |")


def camera_error(scene, base):
    reference = SCENES[scene][2]
    if not reference:
        return None
    result = subprocess.run([COMPARE, os.path.join(base, "20_poses", "transforms.json"),
                             os.path.join(DATA, reference)], capture_output=True, text=True)
    registered = (read_json(os.path.join(base, "10_sfm", "sfm_report.json")) or {}).get("registered")
    return f"{scene}: {registered} photos registered; " + " ".join(result.stdout.split())


def machine():
    model = "unknown CPU"
    if os.path.exists("/proc/cpuinfo"):
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True).stdout.strip()
    return f"{model}, {os.cpu_count()} threads, {platform.system()}; commit {commit}{' (modified)' if dirty else ''}"


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out")
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--budgets", default=",".join(BUDGETS))
    args = parser.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    start = time.time()
    lines = ["| scene | budget | field PSNR | field SSIM | splats PSNR | splats SSIM | samples a ray | steps | "
             "seconds: sfm / poses / train / splat / render | warnings |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    cameras = []
    for scene in args.scenes.split(","):
        if scene not in SCENES:
            sys.exit(f"unknown scene {scene}; the suite's scenes: {', '.join(SCENES)}")
        base = prepare(scene, args.out, extra)
        error = camera_error(scene, base)
        if error:
            cameras.append(error)
            print(error, flush=True)
        for budget in args.budgets.split(","):
            if budget not in BUDGETS:
                sys.exit(f"unknown budget {budget}; the suite's budgets: {', '.join(BUDGETS)}")
            scenes = BUDGETS[budget][3]
            if scenes and scene not in scenes:
                continue
            ws = run_budget(scene, budget, base, args.out, extra)
            lines.append(row(scene, budget, ws))
            print(lines[-1], flush=True)
    minutes = (time.time() - start) / 60
    text = "\n".join(lines + [""] + cameras + ["", f"Machine: {machine()}. The suite took {minutes:.1f} minutes."])
    if extra:
        text += f" Options given to every run: {' '.join(extra)}."
    with open(os.path.join(args.out, "suite.md"), "w") as f:
        f.write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
