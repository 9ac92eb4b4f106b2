#!/usr/bin/python3
"""Long-rollout stability of a cloud model: 360 recursive steps (3 hours at 30 s) from a real and a
procedural sky, through `dynsky sky predict --stats`, charted per step:

  /usr/bin/python3 networks/stability.py --model networks/models/arm_tsi --steps 360 \
      --chart docs/networks-stability.png --summary docs/networks-stability.json

Per step: mean luminance (HDR, W m^-2 sr^-1, over the disc), cloud coverage (sky/cloud_mask.h rule on
the model-resolution image), high-frequency energy (mean squared difference from a sigma = 2 px
Gaussian blur of the [0, 1] form at the model's resolution), and the count of non-finite pixels.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def read_stats(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def summarise(stats):
    def rel(key):
        v = stats[key]
        return {"start": v[0], "min": min(v), "max": max(v), "end": v[-1],
                "max_ratio_to_start": max(v) / v[0] if v[0] else None,
                "min_ratio_to_start": min(v) / v[0] if v[0] else None}
    return {"steps": int(stats["step"][-1]), "nonfinite_pixels_total": int(sum(stats["nonfinite"])),
            "unit_min": min(stats["min_unit"]), "unit_max": max(stats["max_unit"]),
            "mean_unit": rel("mean_unit"),
            "mean_luminance": rel("mean_luminance"), "cloud_coverage": rel("cloud_coverage"),
            "hf_energy": rel("hf_energy")}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--model", default=os.path.join(ROOT, "networks", "models", "arm_tsi"))
    p.add_argument("--dynsky", default=os.path.join(ROOT, "build-nets", "cli", "dynsky"))
    p.add_argument("--shared", default=os.path.join(os.path.dirname(ROOT), "shared"))
    p.add_argument("--steps", type=int, default=360)
    p.add_argument("--res", type=int, default=256, help="resolution of the input skies")
    p.add_argument("--photo", default="images/tsi_sgpC1_20170524174000Z.jpg",
                   help="ARM photograph to start from (relative to the sequence folder); default: the first held-out frame")
    p.add_argument("--chart", default=os.path.join(ROOT, "docs", "networks-stability.png"))
    p.add_argument("--summary", default=os.path.join(ROOT, "docs", "networks-stability.json"))
    args = p.parse_args(argv)

    tmp = tempfile.mkdtemp(prefix="dynsky-stability-")
    real = os.path.join(tmp, "real.exr")
    photo = os.path.join(args.shared, "skies", "arm_tsi_sgp_20170524", args.photo)
    subprocess.run([args.dynsky, "sky", "import", "--preset", "arm-tsi", "--sky-res", str(args.res), photo, "--out", real],
                   check=True, stdout=subprocess.DEVNULL)
    proc_dir = os.path.join(tmp, "proc")
    subprocess.run([args.dynsky, "sky", "procedural", "--cloud-seed", "7", "--coverage", "0.5", "--duration", "0", "--sky-res",
                    str(args.res), "--sun-elevation", "50", "--sun-azimuth", "200", "--quiet", "--out", proc_dir], check=True)
    inputs = {"real (ARM TSI, held-out frame)": real, "procedural (seed 7)": os.path.join(proc_dir, "frame_0000.exr")}
    results = {}
    for label, sky in inputs.items():
        stats_path = os.path.join(tmp, f"stats_{len(results)}.csv")
        subprocess.run([args.dynsky, "sky", "predict", "--model", args.model, "--in", sky, "--steps", str(args.steps),
                        "--every", str(args.steps), "--stats", stats_path, "--quiet", "--out",
                        os.path.join(tmp, f"out_{len(results)}")], check=True)
        results[label] = read_stats(stats_path)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    for label, s in results.items():
        minutes = [k * 0.5 for k in s["step"]]  # 30 s steps
        axes[0].plot(minutes, s["mean_luminance"], label=label)
        axes[1].plot(minutes, s["cloud_coverage"], label=label)
        axes[2].plot(minutes, s["hf_energy"], label=label)
    for ax, title in zip(axes, ["mean luminance (W m$^{-2}$ sr$^{-1}$)", "cloud coverage (fraction of the disc)",
                                "high-frequency energy ([0,1] form)"]):
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("minutes predicted (30 s steps)")
        ax.grid(alpha=0.3)
    axes[2].set_yscale("log")
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{args.steps}-step rollout of {os.path.basename(os.path.normpath(args.model))}", fontsize=11)
    fig.tight_layout()
    os.makedirs(os.path.dirname(args.chart), exist_ok=True)
    fig.savefig(args.chart, dpi=100)
    summary = {label: summarise(s) for label, s in results.items()}
    with open(args.summary, "w") as f:
        json.dump(summary, f, indent=2)
    print(json.dumps(summary, indent=2))
    print("wrote", args.chart, "and", args.summary)


if __name__ == "__main__":
    main()
