#!/usr/bin/python3
"""Trains a few small UNet configurations and charts held-out accuracy against CPU time per step:

  /usr/bin/python3 networks/sweep.py --data build-nets/dataset --out build-nets/sweep \
      --chart docs/networks-sweep.png

Each configuration is trained by networks/train.py into OUT/NAME (skipped if OUT/NAME/model.json
exists, so an interrupted sweep continues). Accuracy: mean per-frame PSNR one step (30 s) ahead on
the held-out ARM frames, seen-sky pixels only. CPU time: PyTorch, one thread, batch 1, both
networks (networks/train.py cpu_time_per_step; the C++/OpenCV time of the shipped model is in
bench/cloud_model_bench.cpp). The persistence and Farneback-extrapolation baselines are computed
on the same frames at each resolution and drawn as lines.
"""
import argparse
import json
import os
import sys

import numpy as np
import torch
import torch.nn.functional as F

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import data as D  # noqa: E402
import train as T  # noqa: E402

# name, resolution, flow widths, cloud widths
# (All at 64 px: on this shared 2-core machine a 128 px run costs about 4x as much.)
CONFIGS = [
    ("w4-d4", 64, "4,8,16,16", "4,8,16,16"),
    ("w8-d4", 64, "8,16,32,32", "8,16,32,32"),
    ("w16-d4", 64, "16,32,64,64", "16,32,64,64"),
]


def baselines(data_dir, name, res, split):
    """Persistence and Farneback extrapolation (flow of the previous pair, bilinear, 0 outside),
    one step ahead, mean per-frame PSNR on seen pixels: the definitions of `dynsky sky evaluate`."""
    s = D.resize_sequence(D.Sequence(os.path.join(data_dir, name), load_exact=False), res)
    lo, hi = split[name]["heldout"]
    n = res
    ys, xs = np.mgrid[0:n, 0:n].astype(np.float32)
    out = {"persistence": [], "farneback": []}
    for t in range(lo, hi - 1):
        f = s.flow[t - 1]
        grid = torch.from_numpy(np.stack([(xs - f[..., 0] + 0.5) / n * 2 - 1, (ys - f[..., 1] + 0.5) / n * 2 - 1], -1))[None]
        img = torch.from_numpy(s.images[t]).permute(2, 0, 1)[None]
        warped = F.grid_sample(img, grid, mode="bilinear", padding_mode="zeros", align_corners=False)[0].permute(1, 2, 0).numpy()
        m = (s.valid[t] & s.valid[t + 1]).astype(bool)
        for key, pred in (("persistence", s.images[t]), ("farneback", warped)):
            mse = ((pred - s.images[t + 1]) ** 2).mean(-1)[m].mean()
            out[key].append(10 * np.log10(1 / mse))
    return {k: float(np.mean(v)) for k, v in out.items()}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--sequences", default="arm_tsi")
    p.add_argument("--epochs", type=int, default=16)
    p.add_argument("--chart", default=os.path.join(os.path.dirname(HERE), "docs", "networks-sweep.png"))
    p.add_argument("--only", default="", help="comma-separated config names to train (default all)")
    p.add_argument("--extra", default="", help="comma-separated folders of other trained models (train.py --out) "
                                                 "to chart as variants (hollow markers)")
    args = p.parse_args(argv)
    torch.set_num_threads(2)
    split = D.load_split(args.data)
    results = []
    for name, res, fw, cw in CONFIGS:
        folder = os.path.join(args.out, name)
        if not os.path.exists(os.path.join(folder, "model.json")):
            if args.only and name not in args.only.split(","):
                continue
            T.main(["--data", args.data, "--sequences", args.sequences, "--res", str(res), "--flow-widths", fw,
                    "--cloud-widths", cw, "--epochs", str(args.epochs), "--unroll", "2", "--eval-every", "4",
                    "--out", folder, "--name", name])
        with open(os.path.join(folder, "model.json")) as f:
            info = json.load(f)
        r = {"name": name, "resolution": res, "flow_widths": info["flow_widths"], "cloud_widths": info["cloud_widths"],
             "parameters": info["parameters"], "macs_per_step": info["macs_per_step"],
             "cpu_ms_per_step": info["pytorch_cpu_seconds_per_step_1_thread"] * 1e3,
             "heldout_psnr1": info["heldout_psnr_python"]["arm_tsi"]["1"]["model"], "epochs": info["epochs"]}
        r.update({f"{k}_psnr1": v for k, v in baselines(args.data, "arm_tsi", res, split).items()})
        results.append(r)
        print(json.dumps(r), flush=True)
    for folder in [f for f in args.extra.split(",") if f]:
        with open(os.path.join(folder, "model.json")) as f:
            info = json.load(f)
        res = info["resolution"]
        r = {"name": info["name"], "folder": folder, "resolution": res, "variant": True,
             "flow_widths": info["flow_widths"], "cloud_widths": info["cloud_widths"], "parameters": info["parameters"],
             "macs_per_step": info["macs_per_step"], "heldout_psnr1": info["heldout_psnr_python"]["arm_tsi"]["1"]["model"],
             "epochs": info["epochs"], "warp_kernel": info.get("warp_kernel"), "trained_on": info.get("trained_on"),
             "unroll": info.get("unroll")}
        r.update({f"{k}_psnr1": v for k, v in baselines(args.data, "arm_tsi", res, split).items()})
        results.append(r)
    retime(results, args.out)
    with open(os.path.join(args.out, "sweep.json"), "w") as f:
        json.dump(results, f, indent=2)
    chart(results, args.chart)


def retime(results, out, rounds=5):
    """CPU time per step again, all configurations in one process, interleaved, the least
    disturbed round kept: the machine is shared, and times taken at the end of each training
    (model.json) vary with what else ran then."""
    import unet as U
    models = {}
    for r in results:
        folder = r.get("folder", os.path.join(out, r["name"]))
        ck = torch.load(os.path.join(folder, "checkpoint.pt"))
        with open(os.path.join(folder, "model.json")) as f:
            info = json.load(f)
        m = U.CloudModel(info["flow_widths"], info["cloud_widths"], info.get("warp_kernel", 5))
        m.load_state_dict(ck["model"])
        models[r["name"]] = (m.eval(), r["resolution"])
    best = {name: float("inf") for name in models}
    for _ in range(rounds):
        for name, (m, n) in models.items():
            best[name] = min(best[name], T.cpu_time_per_step(m, n, threads=1, repeats=30))
    for r in results:
        r["cpu_ms_per_step"] = best[r["name"]] * 1e3


def chart(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    colours = {64: "tab:blue", 128: "tab:orange"}
    for res in sorted({r["resolution"] for r in results}):
        rs = [r for r in results if r["resolution"] == res]
        c = colours.get(res, "tab:gray")
        ax.axhline(rs[0]["persistence_psnr1"], color=c, ls=":", lw=1, label=f"persistence, {res} px")
        ax.axhline(rs[0]["farneback_psnr1"], color=c, ls="--", lw=1, label=f"Farneback extrapolation, {res} px")
        for r in rs:
            hollow = r.get("variant", False)
            ax.scatter(r["cpu_ms_per_step"], r["heldout_psnr1"], s=40, zorder=3, edgecolors=c,
                       facecolors="none" if hollow else c)
            ax.annotate(f"{r['name']}\n{r['parameters'] / 1e3:.0f}k params", (r["cpu_ms_per_step"], r["heldout_psnr1"]),
                        textcoords="offset points", xytext=(6, -4), fontsize=8)
    ax.set_xscale("log")
    from matplotlib.ticker import ScalarFormatter
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(ScalarFormatter())
    ax.tick_params(axis="x", which="minor", labelsize=7)
    ax.set_xlabel("CPU time per medium step, ms (PyTorch, 1 thread, both networks)")
    ax.set_ylabel("held-out PSNR, 1 step (30 s) ahead, dB")
    ax.set_title("Cloud model size vs accuracy (ARM TSI, last 20 % of the day held out)\n"
                 "filled: width sweep; hollow: variants (see docs/networks.md)", fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fig.savefig(path, dpi=110)
    print("wrote", path)


if __name__ == "__main__":
    main()
