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
    for mark in marks:
        # The evaluation nearest after the mark (evaluations are every 15 s of training).
        later = [p for s, p in points if s >= mark - 0.5]
        row[f"psnr_{mark}s"] = f"{later[0]:.2f}" if later and points[-1][0] >= mark - 0.5 else ""
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
