#!/usr/bin/python3
"""Long-rollout stability of the advect-residual model on every kind of start, through
`dynsky sky predict --stats` (docs/networks.md, "Stability"):

  /usr/bin/python3 networks/stability_advect.py --dynsky build/cli/dynsky --steps 360 \
      --chart docs/networks-advect-stability.png --summary docs/networks-advect-stability.json

Starts (256 px): a real ARM photograph with its previous frame (the motion measured from it), a
procedural cumulus sky with its own wind, and Hosek-Wilkie clear skies at five sun elevations under
a 12 m/s wind. Per step, from the CSV: mean luminance (HDR), cloud cover (red/blue rule on the
model-resolution image), high-frequency energy (sigma 2 px at the model's resolution), non-finite
pixels; the mean is taken without the start's sun pixels (restored and dimmed by the cloud over the
sun every step: a covered sun is lighting, not drift; the chart also plots the mean with them). The criteria (issue 10): no NaN; clear skies keep cover within +0.03 of the start over 120
steps; cloudy starts keep the mean luminance within 20 % and at least half the fine detail.
"""
import argparse
import csv
import json
import os
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def read_stats(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def run(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dynsky", default=os.path.join(ROOT, "build", "cli", "dynsky"))
    p.add_argument("--model", default="auto")
    p.add_argument("--shared", default=os.path.join(os.path.dirname(ROOT), "shared"))
    p.add_argument("--steps", type=int, default=360)
    p.add_argument("--res", type=int, default=256)
    p.add_argument("--chart", default=os.path.join(ROOT, "docs", "networks-advect-stability.png"))
    p.add_argument("--summary", default=os.path.join(ROOT, "docs", "networks-advect-stability.json"))
    args = p.parse_args(argv)
    tmp = tempfile.mkdtemp(prefix="dynsky-stability-")
    d = args.dynsky
    starts = {}
    seq = os.path.join(args.shared, "skies", "arm_tsi_sgp_20170524", "images")
    for name in ("tsi_sgpC1_20170524173930Z.jpg", "tsi_sgpC1_20170524174000Z.jpg"):
        run([d, "sky", "import", "--preset", "arm-tsi", "--sky-res", str(args.res), os.path.join(seq, name), "--out",
             os.path.join(tmp, name.replace(".jpg", ".exr"))])
    starts["photograph (ARM, held out, previous frame)"] = (
        os.path.join(tmp, "tsi_sgpC1_20170524174000Z.exr"), ["--prev", os.path.join(tmp, "tsi_sgpC1_20170524173930Z.exr")])
    run([d, "sky", "procedural", "--cloud-seed", "11", "--coverage", "0.5", "--duration", "0", "--wind-speed", "10", "--wind-from", "240", "--sun-elevation", "45",
         "--sky-res", str(args.res), "--out", os.path.join(tmp, "proc"), "-q"])
    starts["procedural cumulus (its wind)"] = (os.path.join(tmp, "proc", "frame_0000.exr"),
                                               ["--wind-from", "240", "--wind-speed", "10"])
    for k, el in enumerate((5, 15, 30, 50, 75)):
        run([d, "sky", "procedural", "--coverage", "0", "--duration", "0", "--sun-elevation", str(el), "--sun-azimuth",
             str(40 + 70 * k), "--sky-res", str(args.res), "--out", os.path.join(tmp, f"clear_{el}"), "-q"])
        starts[f"clear, sun at {el} deg"] = (os.path.join(tmp, f"clear_{el}", "frame_0000.exr"),
                                            ["--wind-from", str(30 + 80 * k), "--wind-speed", "12"])
    summary, curves = {}, {}
    for name, (sky, extra) in starts.items():
        stats = os.path.join(tmp, "stats.csv")
        run([d, "sky", "predict", "--model", args.model, "--sky", sky, "--steps", str(args.steps), "--every",
             str(args.steps), "--out", os.path.join(tmp, "pred"), "--stats", stats, "-q"] + extra)
        s = read_stats(stats)
        clear = name.startswith("clear")
        n120 = min(len(s["step"]), 121)
        e = {"steps": int(s["step"][-1]), "nonfinite": int(sum(s["nonfinite"])),
             "unit_min": min(s["min_unit"]), "unit_max": max(s["max_unit"]),
             "cover_start": s["cloud_coverage"][0], "cover_max_rise_120": max(s["cloud_coverage"][:n120]) - s["cloud_coverage"][0],
             "mean_ratio_min": min(s["mean_luminance_without_sun"]) / s["mean_luminance_without_sun"][0],
             "mean_ratio_max": max(s["mean_luminance_without_sun"]) / s["mean_luminance_without_sun"][0],
             "mean_with_sun_ratio_min": min(s["mean_luminance"]) / s["mean_luminance"][0],
             "mean_with_sun_ratio_max": max(s["mean_luminance"]) / s["mean_luminance"][0],
             "hf_ratio_min": min(s["hf_energy"]) / s["hf_energy"][0] if s["hf_energy"][0] > 0 else None,
             "hf_ratio_end": s["hf_energy"][-1] / s["hf_energy"][0] if s["hf_energy"][0] > 0 else None}
        if clear:
            e["passes"] = e["nonfinite"] == 0 and e["cover_max_rise_120"] <= 0.03
        else:
            e["passes"] = (e["nonfinite"] == 0 and 0.8 <= e["mean_ratio_min"] and e["mean_ratio_max"] <= 1.2
                           and (e["hf_ratio_min"] or 0) >= 0.5)
        summary[name] = e
        curves[name] = s
        print(name, json.dumps(e), flush=True)
    with open(args.summary, "w") as f:
        json.dump(summary, f, indent=2)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2), dpi=100)
    for name, s in curves.items():
        t = [x / 120 for x in s["step"]]  # hours at 30 s
        m = s["mean_luminance_without_sun"]
        line, = ax[0].plot(t, [v / m[0] for v in m], label=name)
        ax[0].plot(t, [v / s["mean_luminance"][0] for v in s["mean_luminance"]], color=line.get_color(), lw=0.6, ls=":")
        ax[1].plot(t, [v - s["cloud_coverage"][0] for v in s["cloud_coverage"]], label=name)
        h0 = s["hf_energy"][0] or 1
        ax[2].plot(t, [v / h0 for v in s["hf_energy"]], label=name)
    ax[0].axhspan(0.8, 1.2, color="0.92")
    ax[0].set_title("mean luminance / start (sun's pixels left out; dotted: with them)")
    ax[1].axhline(0.03, color="r", lw=0.8)
    ax[1].set_title("cloud cover - start (clear: must stay under 0.03)")
    ax[2].axhline(0.5, color="r", lw=0.8)
    ax[2].set_title("high-frequency energy / start")
    for a in ax:
        a.set_xlabel("hours (30 s steps)")
        a.grid(alpha=0.3)
    ax[2].legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(args.chart)
    print("wrote", args.chart, "and", args.summary)


if __name__ == "__main__":
    main()
