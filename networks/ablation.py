#!/usr/bin/python3
"""The paper's loss ablation, repeated: MSE alone against MSE + cosine similarity, two seeds each.

  /usr/bin/python3 networks/ablation.py --data build-nets/dataset --out build-nets/ablation \
      --report docs/networks-ablation.md --chart docs/networks-ablation.png

Every model has the shipped model's settings (networks/models/arm_tsi/MODEL_CARD.md: 64 px,
widths 16,32,64,64, 2 recursive steps, 16 epochs) and differs only in --cos-weight (0: image MSE
+ 0.1 x flow MSE; 0.5, the default: plus 0.05 x (1 - cos) on RGB vectors and 0.1 x 0.5 x (1 - cos)
on flow directions) and --seed. MSE + cosine with seed 1 is the shipped model itself (its folder
and its training checkpoint); the others are trained by networks/train.py into OUT/NAME, one after
another (skipped where OUT/NAME/model.json exists; resumed where only the checkpoint does).

Each model is then scored by `dynsky sky evaluate` (C++ / OpenCV, held-out ARM frames, PSNR and
SSIM at the given horizons; `sky evaluate --model` takes advect-residual models only, so each
folder is scored as its 'paper' column, the folder standing in for networks/models/arm_tsi through
DYNSKY_DATA: evaluate_cpp; its report goes to OUT/eval/NAME) and, in PyTorch, on what the cosine
term is meant to help, FlowNet's flow direction: on held-out pairs, seen cloud pixels with a
Farneback target, the mean cosine between predicted and target directions, and the median angle
between them where the target moves at least 0.5 px.
"""
import argparse
import csv
import json
import os
import subprocess
import sys

import numpy as np
import torch

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import data as D  # noqa: E402
import unet as U  # noqa: E402

# The shipped model's training arguments (MODEL_CARD.md), less output folders, seed and loss.
TRAIN_ARGS = ["--sequences", "arm_tsi", "--res", "64", "--flow-widths", "16,32,64,64", "--cloud-widths",
              "16,32,64,64", "--unroll", "2", "--epochs", "16", "--eval-every", "4"]
LOSSES = [("mse", "MSE only", 0.0), ("msecos", "MSE + cosine", 0.5)]
MIN_MOVE_PX = 0.5


def models(args):
    """(name, loss key, loss label, cos weight, seed, folder, checkpoint) for every run."""
    out = []
    for key, label, cw in LOSSES:
        for seed in [int(s) for s in args.seeds.split(",")]:
            name = f"{key}-s{seed}"
            if key == "msecos" and seed == 1 and args.shipped:
                out.append((name, key, label, cw, seed, args.shipped, args.shipped_checkpoint))
            else:
                folder = os.path.join(args.out, name)
                out.append((name, key, label, cw, seed, folder, os.path.join(folder, "checkpoint.pt")))
    return out


def train_missing(args, runs):
    for name, _, _, cw, seed, folder, ckpt in runs:
        if os.path.exists(os.path.join(folder, "model.json")):
            continue
        os.makedirs(folder, exist_ok=True)
        cmd = ["nice", "-n", str(args.nice), sys.executable, os.path.join(HERE, "train.py"), "--data", args.data,
               *TRAIN_ARGS, "--cos-weight", f"{cw:g}", "--seed", str(seed), "--threads", str(args.threads),
               "--checkpoint-dir", folder, "--out", folder, "--name", name]
        if os.path.exists(ckpt):
            cmd.append("--resume")
        print("+", " ".join(cmd), flush=True)
        subprocess.run(cmd, check=True)


def evaluate_cpp(args, name, folder):
    """Scores the FlowNet + CloudNet folder with `dynsky sky evaluate` into OUT/eval/NAME and reads its CSV.

    `sky evaluate --model` takes advect-residual models only; it scores the paper's form in its own
    column ("paper"), the model it finds at networks/models/arm_tsi under its data roots. So each
    folder is scored as that model: a data root OUT/eval/NAME/data-root whose
    networks/models/arm_tsi links to the folder, given first through DYNSKY_DATA (util/data_path.cpp;
    every other data file falls through to the usual roots), beside --model advect. The start frames
    are the folder's held-out ARM frames (its split.json), at its resolution."""
    edir = os.path.join(args.out, "eval", name + ("-shipped" if folder == args.shipped else ""))
    os.makedirs(edir, exist_ok=True)
    with open(os.path.join(folder, "model.json")) as f:
        info = json.load(f)
    with open(os.path.join(folder, "split.json")) as f:
        lo, hi = json.load(f)["arm_tsi"]["heldout"]
    root = os.path.join(edir, "data-root")
    link = os.path.join(root, "networks", "models", "arm_tsi")
    os.makedirs(os.path.dirname(link), exist_ok=True)
    if os.path.islink(link) or os.path.exists(link):
        os.remove(link)
    os.symlink(os.path.abspath(folder), link)
    report = os.path.join(edir, "evaluation.md")
    cmd = [args.dynsky, "sky", "evaluate", "--model", "advect", "--sequence", "arm-tsi", "--horizons", args.horizons,
           "--resolutions", str(info["resolution"]), "--frames", f"{lo}-{hi - 1}", "--out", report, "--quiet"]
    if args.shared:
        cmd += ["--shared", args.shared]
    if args.limit:
        cmd += ["--limit", str(args.limit)]
    print("+ DYNSKY_DATA=" + root, " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, env=dict(os.environ, DYNSKY_DATA=os.path.abspath(root)))
    scores = {}
    with open(os.path.splitext(report)[0] + ".csv") as f:
        for row in csv.DictReader(f):
            if int(row["resolution"]) == info["resolution"]:
                scores[(int(row["horizon"]), row["method"])] = row
    rows = {}
    for h in sorted({h for h, _ in scores}):
        if (h, "paper") not in scores:
            raise SystemExit(f"ablation.py: error: {report}: no 'paper' column at horizon {h}: `dynsky sky evaluate` "
                             f"did not score {folder} as the paper's model (its Delta t must divide the photographs' "
                             "30 s; run the command above without --quiet to see why)")
        m, p, fb = scores[(h, "paper")], scores[(h, "persistence")], scores[(h, "farneback")]
        rows[h] = {"model_psnr": float(m["psnr_db"]), "model_ssim": float(m["ssim"]),
                   "persistence_psnr": float(p["psnr_db"]), "persistence_ssim": float(p["ssim"]),
                   "farneback_psnr": float(fb["psnr_db"]), "farneback_ssim": float(fb["ssim"]),
                   "model_mse": float(m["mse"]), "frames": int(m["frames"])}
    # `sky evaluate` no longer reports median flow magnitudes (the rollout's and FlowNet's motion).
    return {"horizons": rows, "median_motion_px": None}


def load_model(folder, ckpt):
    with open(os.path.join(folder, "model.json")) as f:
        info = json.load(f)
    model = U.CloudModel(info["flow_widths"], info["cloud_widths"], info.get("warp_kernel", 5))
    model.load_state_dict(torch.load(ckpt)["model"])
    model.eval()
    # The checkpoint must be the exported model: replay the folder's reference pair.
    ref = os.path.join(folder, "reference_input.npy")
    if os.path.exists(ref):
        x = torch.from_numpy(np.load(ref)).permute(2, 0, 1)[None]
        with torch.no_grad():
            f = model.flownet(x)[0].permute(1, 2, 0).numpy()
        diff = float(np.abs(f - np.load(os.path.join(folder, "reference_flow.npy"))).max())
        if diff > 1e-4:
            raise SystemExit(f"{ckpt}: checkpoint does not match the exported model in {folder} (flow differs by {diff})")
    return model


@torch.no_grad()
def flow_direction(model, seq, split):
    """FlowNet direction against the Farneback target on held-out pairs (seen cloud pixels)."""
    lo, hi = split[seq.name]["heldout"]
    cos_all, ang_moving = [], []
    for t in range(lo, hi - 1):
        x = torch.from_numpy(seq.images[t]).permute(2, 0, 1)[None]
        p = model.flownet(x)[0].permute(1, 2, 0).numpy()
        tgt = seq.flow_target[t]
        m = (seq.valid[t] & seq.valid[t + 1]).astype(bool) & (tgt[..., 2] > 0)
        pd = p[..., 0:2] / np.maximum(np.linalg.norm(p[..., 0:2], axis=-1, keepdims=True), 1e-6)
        c = np.clip((pd * tgt[..., 0:2]).sum(-1), -1, 1)
        cos_all.append(c[m])
        moving = m & (np.linalg.norm(seq.flow[t], axis=-1) >= MIN_MOVE_PX)
        ang_moving.append(np.degrees(np.arccos(c[moving])))
    c, a = np.concatenate(cos_all), np.concatenate(ang_moving)
    return {"mean_cos": float(c.mean()), "median_angle_deg": float(np.median(a)),
            "within_45deg": float((a <= 45).mean()), "pixels": int(c.size), "pixels_moving": int(a.size)}


def json_path(args):
    """All numbers, beside the models, named after the report (so two reports do not overwrite each other)."""
    return os.path.join(args.out, os.path.splitext(os.path.basename(args.report))[0] + ".json")


def spread(vals):
    return float(np.mean(vals)), float(np.min(vals)), float(np.max(vals))


def write_report(args, results, path):
    hs = [int(h) for h in args.horizons.split(",")]
    first = results[0]["cpp"]["horizons"]
    seeds = sorted({r["seed"] for r in results})
    L = ["# Loss ablation: MSE alone against MSE + cosine similarity", "",
         "Written by `/usr/bin/python3 networks/ablation.py " + " ".join(args.argv) + "`.", "",
         f"Every model has the shipped model's settings (64 px, widths 16, 32, 64, 64, 2 recursive steps, 16 epochs, "
         f"ARM training frames) and differs only in the loss (`networks/train.py --cos-weight`) and the seed "
         f"({', '.join(map(str, seeds))}). MSE only: image MSE + 0.1 x flow MSE (`--cos-weight 0`). MSE + cosine "
         "(the default, 0.5): image MSE + 0.05 x (1 - cos of RGB vectors) + 0.1 x (flow MSE + 0.5 x (1 - cos of "
         "flow directions on cloud pixels))." + (f" MSE + cosine seed 1 is the shipped model `{os.path.relpath(args.shipped, ROOT)}`." if args.shipped else " Every model was trained here (no --shipped)."), "",
         f"Image scores: `dynsky sky evaluate --model advect --sequence arm-tsi --horizons {args.horizons}`'s "
         "'paper' column, each model standing in for the paper's (networks/ablation.py evaluate_cpp), with "
         "--frames the model's held-out ARM frames ("
         f"{first[hs[0]]['frames']} start frames, 64 px, [0, 1] form, seen sky pixels, means of per-frame values; "
         "Farneback extrapolation: the previous pair's flow applied h times along its streamlines). "
         "Flow direction: FlowNet's output against the Farneback target on the held-out pairs, seen cloud pixels "
         "with a target direction; mean cosine over all of them, median angle and share within 45 degrees over "
         f"those moving at least {MIN_MOVE_PX} px.", "",
         "## Per model", "",
         "| loss | seed | " + " | ".join(f"PSNR {h}" for h in hs) + " | " + " | ".join(f"SSIM {h}" for h in hs) +
         " | flow cos | flow angle (median) | within 45 deg |",
         "|---|---:|" + "---:|" * (2 * len(hs) + 3)]
    for r in results:
        c, fd = r["cpp"]["horizons"], r["direction"]
        L.append(f"| {r['label']} | {r['seed']}{' (shipped)' if r['shipped'] else ''} | " +
                 " | ".join(f"{c[h]['model_psnr']:.2f}" for h in hs) + " | " +
                 " | ".join(f"{c[h]['model_ssim']:.3f}" for h in hs) +
                 f" | {fd['mean_cos']:.3f} | {fd['median_angle_deg']:.1f} deg | {100 * fd['within_45deg']:.1f} % |")
    L.append("| persistence | | " + " | ".join(f"{first[h]['persistence_psnr']:.2f}" for h in hs) + " | " +
             " | ".join(f"{first[h]['persistence_ssim']:.3f}" for h in hs) + " | | | |")
    L.append("| Farneback extrapolation | | " + " | ".join(f"{first[h]['farneback_psnr']:.2f}" for h in hs) + " | " +
             " | ".join(f"{first[h]['farneback_ssim']:.3f}" for h in hs) + " | | | |")
    L += ["", "PSNR in dB, horizons in 30 s steps.", "",
          f"## Mean over seeds (min - max)", "",
          "| loss | " + " | ".join(f"PSNR {h}" for h in hs) + f" | SSIM {hs[0]} | SSIM {hs[-1]} | flow cos | flow angle (median) |",
          "|---|" + "---:|" * (len(hs) + 4)]
    summary = {}
    for key, label, _ in LOSSES:
        rs = [r for r in results if r["loss"] == key]
        if not rs:
            continue
        row = {f"psnr{h}": spread([r["cpp"]["horizons"][h]["model_psnr"] for r in rs]) for h in hs}
        row.update({f"ssim{h}": spread([r["cpp"]["horizons"][h]["model_ssim"] for r in rs]) for h in hs})
        row["cos"] = spread([r["direction"]["mean_cos"] for r in rs])
        row["angle"] = spread([r["direction"]["median_angle_deg"] for r in rs])
        summary[key] = row

        def fmt(v, d):
            return f"{v[0]:.{d}f} ({v[1]:.{d}f} - {v[2]:.{d}f})"
        ss = [fmt(row[f"ssim{h}"], 3) for h in (hs[0], hs[-1])]
        L.append(f"| {label} | " + " | ".join(fmt(row[f"psnr{h}"], 2) for h in hs) + f" | {ss[0]} | {ss[1]} | "
                 f"{fmt(row['cos'], 3)} | {fmt(row['angle'], 1)} deg |")
    if len(summary) == 2:
        a, b = summary["msecos"], summary["mse"]
        L += ["", "Difference, MSE + cosine minus MSE only, of the seed means, against the spread between seeds "
              "(max - min, largest of the two losses):", "",
              "| | " + " | ".join(f"PSNR {h}" for h in hs) + " | flow cos | flow angle |",
              "|---|" + "---:|" * (len(hs) + 2),
              "| difference | " + " | ".join(f"{a[f'psnr{h}'][0] - b[f'psnr{h}'][0]:+.2f} dB" for h in hs) +
              f" | {a['cos'][0] - b['cos'][0]:+.3f} | {a['angle'][0] - b['angle'][0]:+.1f} deg |",
              "| seed spread | " + " | ".join(
                  f"{max(a[f'psnr{h}'][2] - a[f'psnr{h}'][1], b[f'psnr{h}'][2] - b[f'psnr{h}'][1]):.2f} dB" for h in hs) +
              f" | {max(a['cos'][2] - a['cos'][1], b['cos'][2] - b['cos'][1]):.3f} | "
              f"{max(a['angle'][2] - a['angle'][1], b['angle'][2] - b['angle'][1]):.1f} deg |"]
        # Same seed = same initial weights and batch order, so the per-seed difference isolates the loss.
        by = {(r["loss"], r["seed"]): r for r in results}
        common = sorted(s for s in seeds if ("mse", s) in by and ("msecos", s) in by)
        if common:
            def paired(get, d, unit, better_is_higher=True):
                v = [get(by[("msecos", s)]) - get(by[("mse", s)]) for s in common]
                wins = sum((x > 0) == better_is_higher and x != 0 for x in v)
                return f"{min(v):+.{d}f} to {max(v):+.{d}f}{unit}, {wins}/{len(v)}"
            L.append("| same seed: range, seeds where cosine is better | " + " | ".join(
                paired(lambda r, h=h: r["cpp"]["horizons"][h]["model_psnr"], 2, " dB") for h in hs) +
                f" | {paired(lambda r: r['direction']['mean_cos'], 3, '')} | "
                f"{paired(lambda r: r['direction']['median_angle_deg'], 1, ' deg', False)} |")
    L += ["", f"![PSNR against horizon, per loss]({os.path.relpath(args.chart, os.path.dirname(path))})", "",
          f"Per-model reports of `dynsky sky evaluate`: `{os.path.relpath(args.out, ROOT)}/eval/NAME/`; "
          f"all numbers: `{os.path.relpath(json_path(args), ROOT)}`.", ""]
    with open(path, "w") as f:
        f.write("\n".join(L))
    return summary


def chart(args, results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    hs = [int(h) for h in args.horizons.split(",")]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    colors = {"mse": "tab:orange", "msecos": "tab:blue"}
    first = results[0]["cpp"]["horizons"]
    everyone = np.array([[r["cpp"]["horizons"][h]["model_psnr"] for h in hs] for r in results]).mean(0)
    for ax, rel in ((axes[0], False), (axes[1], True)):
        base = everyone if rel else np.zeros(len(hs))
        for key, label, _ in LOSSES:
            rs = [r for r in results if r["loss"] == key]
            if not rs:
                continue
            v = np.array([[r["cpp"]["horizons"][h]["model_psnr"] for h in hs] for r in rs]) - base
            ax.plot(hs, v.mean(0), "-", color=colors[key], label=f"{label} (mean of {len(rs)} seeds)")
            ax.fill_between(hs, v.min(0), v.max(0), color=colors[key], alpha=0.15)
            for r, row in zip(rs, v):
                ax.plot(hs, row, "o" if r["seed"] == 1 else "s", color=colors[key], ms=5, mfc="none",
                        label=f"{label}, seed {r['seed']}" + (" (shipped)" if r["shipped"] else ""))
        if not rel:
            ax.plot(hs, [first[h]["persistence_psnr"] for h in hs], "--", color="gray", label="persistence")
            ax.plot(hs, [first[h]["farneback_psnr"] for h in hs], ":", color="black", label="Farneback extrapolation")
            ax.set_ylabel("held-out PSNR (dB)")
            ax.set_title("PSNR against horizon")
        else:
            ax.axhline(0, color="gray", lw=0.5)
            ax.set_ylabel("PSNR minus the mean of all models (dB)")
            ax.set_title("Same, relative (band: min - max over seeds)")
        ax.set_xlabel("horizon (30 s steps)")
        ax.set_xticks(hs)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Loss ablation, ARM TSI held-out frames (dynsky sky evaluate)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", default=os.path.join(ROOT, "build-nets", "dataset"), help="dataset folder (with split.json)")
    p.add_argument("--out", default=os.path.join(ROOT, "build-nets", "ablation"), help="folder for the trained models and evaluations")
    p.add_argument("--seeds", default="1,2", help="comma-separated seeds, trained for each loss")
    p.add_argument("--shipped", default=os.path.join(ROOT, "networks", "models", "arm_tsi"),
                   help="the shipped model folder, used as MSE + cosine seed 1 ('' to train that one too)")
    p.add_argument("--shipped-checkpoint", default=os.path.join(ROOT, "build-nets", "sweep", "w16-d4", "checkpoint.pt"),
                   help="the shipped model's training checkpoint (for the PyTorch flow-direction score)")
    p.add_argument("--dynsky", default=os.path.join(ROOT, "build-nets", "cli", "dynsky"), help="the built dynsky program")
    p.add_argument("--horizons", default="1,2,3,6", help="steps ahead to score")
    p.add_argument("--threads", type=int, default=1, help="training threads")
    p.add_argument("--nice", type=int, default=10, help="niceness of the training runs")
    p.add_argument("--report", default=os.path.join(ROOT, "docs", "networks-ablation.md"))
    p.add_argument("--chart", default=os.path.join(ROOT, "docs", "networks-ablation.png"))
    p.add_argument("--no-train", action="store_true", help="only evaluate models already trained")
    p.add_argument("--shared", default="", help="the shared data folder for `dynsky sky evaluate` (default: its own)")
    p.add_argument("--limit", type=int, default=0, help="score only the first K held-out start frames (quick checks)")
    args = p.parse_args(argv)
    args.argv = [os.path.relpath(a, ROOT) if os.path.isabs(a) else a for a in (argv if argv is not None else sys.argv[1:])]
    if args.shipped and not os.path.exists(args.shipped_checkpoint):
        raise SystemExit(f"{args.shipped_checkpoint}: no such checkpoint (pass --shipped '' to train MSE + cosine seed 1 instead)")
    torch.set_num_threads(1)
    runs = models(args)
    if not args.no_train:
        train_missing(args, runs)
    split = D.load_split(args.data)
    seq = D.Sequence(os.path.join(args.data, "arm_tsi"), load_exact=False)
    results = []
    for name, key, label, cw, seed, folder, ckpt in runs:
        if not os.path.exists(os.path.join(folder, "model.json")):
            print(f"{name}: not trained ({folder}), left out", flush=True)
            continue
        with open(os.path.join(folder, "model.json")) as f:
            info = json.load(f)
        if info["resolution"] != seq.resolution:
            seq = D.resize_sequence(seq, info["resolution"])
        r = {"name": name, "loss": key, "label": label, "cos_weight": cw, "seed": seed, "folder": folder,
             "shipped": folder == args.shipped, "cpp": evaluate_cpp(args, name, folder),
             "direction": flow_direction(load_model(folder, ckpt), seq, split),
             "python_psnr": info["heldout_psnr_python"]}
        results.append(r)
        print(json.dumps({k: r[k] for k in ("name", "direction")}), flush=True)
    if not results:
        raise SystemExit("no trained models to evaluate")
    summary = write_report(args, results, args.report)
    chart(args, results, args.chart)
    with open(json_path(args), "w") as f:
        json.dump({"models": results, "summary": summary}, f, indent=1)
    print(f"wrote {args.report}, {args.chart}")


if __name__ == "__main__":
    main()
