"""Collects held-out PSNR at fixed training times from the runs of train_bench.sh into curves.csv, and plots
every run's curve into curves.png (with build/bench/plot_curves)."""
import csv
import os
import subprocess
import sys

out, runs = sys.argv[1], sys.argv[2:]
marks = [15, 30, 60, 120, 300, 600, 900]
rows = []
series = []
for run in runs:
    preset, _, field = run.partition(":")
    name = f"{preset}_{field or 'ngp'}"
    metrics = list(csv.DictReader(open(os.path.join(out, name, "metrics.csv"))))
    points = [(float(m["wall_seconds"]), float(m["heldout_psnr"])) for m in metrics]
    row = {"run": name}
    for i, mark in enumerate(marks):
        # The first evaluation at or after the mark, unless it is at or after the next mark (a run evaluated
        # every 60 s has nothing to say at 15 s).
        next_mark = marks[i + 1] if i + 1 < len(marks) else float("inf")
        later = [(s, p) for s, p in points if s >= mark - 0.5]
        row[f"psnr_{mark}s"] = f"{later[0][1]:.2f}" if later and later[0][0] < next_mark - 0.5 else ""
    for target in (23, 28, 30):
        reached = [s for s, p in points if p >= target]
        row[f"seconds_to_{target}dB"] = f"{reached[0]:.0f}" if reached else ""
    rows.append(row)
    series.append(f"{name}={os.path.join(out, name, 'metrics.csv')}")
with open(os.path.join(out, "curves.csv"), "w", newline="") as f:
    writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    writer.writeheader()
    writer.writerows(rows)
print(open(os.path.join(out, "curves.csv")).read())
plot = os.path.join(os.path.dirname(__file__), "..", "build", "bench", "plot_curves")
subprocess.run([plot, os.path.join(out, "curves.png")] + series, check=True)
