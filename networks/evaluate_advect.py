#!/usr/bin/python3
"""Held-out evaluation, long rollouts, CPU time and figures of advect-residual models.

  /usr/bin/python3 networks/evaluate_advect.py --data /work/data/dataset_v2 \
      --model NAME=RUN/final.pt [--model ...] --out /work/data/eval [--rollouts] [--frames]

- heldout.json: per model and source, PSNR at horizons 1, 2, 6 of model_prev, model_true,
  model_zero, advect_prev (no network), persistence, farneback (networks/advect_eval.py says how).
- rollouts.json / rollouts.png (--rollouts, first model): from clear starts (120 steps; cover by the
  red/blue > 0.75 rule on camera-encoded values re-done at N, advect.cloud_cover) and from cloudy
  starts (360 steps; mean of the [0, 1] form, and high-frequency energy = mean squared difference
  to a sigma-2 px Gaussian blur), each with F = prev Farneback and F = true motion / a user wind.
- cpu.json: PyTorch CPU seconds per step on 1 thread (warp + network; network alone).
- frames_*.png (--frames): held-out predictions next to the truth and the baselines.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import advect as A  # noqa: E402
import advect_data as AD  # noqa: E402
import advect_eval as AE  # noqa: E402
import train_advect as T  # noqa: E402
from script_errors import fail, run_main  # noqa: E402


def cpu_time(model, n, repeats=30, rounds=5):
    torch.set_num_threads(1)
    model.eval()
    img = torch.rand(1, 3, n, n) * A._disc_t(n, "cpu")
    flow = torch.randn(1, 2, n, n)
    x = A.network_input(img, flow)
    with torch.no_grad():
        for _ in range(5):
            A.step(model, img, flow)
        best_step, best_net, best_warp = 1e9, 1e9, 1e9
        for _ in range(rounds):
            t0 = time.process_time()
            for _ in range(repeats):
                A.step(model, img, flow)
            best_step = min(best_step, (time.process_time() - t0) / repeats)
            t0 = time.process_time()
            for _ in range(repeats):
                model(x)
            best_net = min(best_net, (time.process_time() - t0) / repeats)
            t0 = time.process_time()
            for _ in range(repeats):
                A.network_input(img, flow)
            best_warp = min(best_warp, (time.process_time() - t0) / repeats)
    return {"step_s": best_step, "network_s": best_net, "warp_s": best_warp}


@torch.no_grad()
def rollout(model, img, flow, steps, mask, comp=None):
    """Returns per-step stats of a rollout with fixed F (mask: pixels to measure, (1, 1, N, N));
    comp: the background compensation of a model trained with --compensated (A.compensation)."""
    x = A.fill_saturated(img)
    stats = {"cover": [], "mean": [], "hf": [], "min": [], "max": [], "finite": True}
    frames = [x]

    def record(z):
        stats["cover"].append(A.cloud_cover(z, mask)[0])
        stats["mean"].append(float((z.mean(1, keepdim=True) * mask).sum() / mask.sum()))
        stats["hf"].append(A.hf_energy(z, mask)[0])
        stats["min"].append(float(z.min()))
        stats["max"].append(float(z.max()))
        stats["finite"] = stats["finite"] and bool(torch.isfinite(z).all())

    record(x)
    for t in range(steps):
        x = A.step(model, x, flow, comp)
        record(x)
        if (t + 1) in (1, 10, 30, 60, 120, 240, 360):
            frames.append(x)
    return stats, frames


def user_wind(n, speed_mps, from_deg, height_m=1500.0, dt=30.0):
    """A user wind as a flow: displacement per step over the layer height, blowing FROM from_deg
    (clockwise from north; the canonical image has north up, east left: drift towards +y for wind
    from the north, towards +x for wind from the east)."""
    d = speed_mps * dt / height_m
    a = math.radians(from_deg)
    # towards (from + 180): north component -cos a, east component -sin a; image +x = west, +y = south
    east, north = -math.sin(a) * d, -math.cos(a) * d
    return A.wind_flow(n, [[-east, -north]])


def compensation_at(s, k, flow, compensated):
    """What a compensated model's warp adds at frame k of source s (None for a plain-warp model), as
    AE.evaluate and the C++ side step it: the frame's clear background moved back."""
    if not compensated:
        return None
    return A.compensation(AD.t_img(s.background[k:k + 1]), flow)


def run_rollouts(model, sources, split, clear_steps=120, cloudy_steps=360, part="heldout", compensated=False):
    by = {s.name: s for s in sources}
    out = {}
    frames = {}
    cases = []
    for name in ("arm_clear", "proc_clear_0", "proc_clear_1", "proc_clear_2", "proc_clear_3"):
        if name in by:
            cases += [(name, "prev", clear_steps), (name, "wind", clear_steps)]
    for name in ("arm_tsi", "arm_dusk", "mobotix", "proc_01", "proc_05", "proc_12"):
        if name in by:
            cases += [(name, "prev", cloudy_steps), (name, "true", cloudy_steps)]
    for name, kind, steps in cases:
        s = by[name]
        k = split[name][part][0] + 1
        img = AD.t_img(s.images[k:k + 1])
        mask = torch.from_numpy(s.valid[k:k + 1].astype(np.float32))[:, None]
        if kind == "prev":
            f = AD.t_img(s.flow[k - 1:k])
        elif kind == "true":
            f = AD.true_flow(s, [k])
        else:
            f = user_wind(s.n, 10.0, 270.0)
        st, fr = rollout(model, img, f, steps, mask, compensation_at(s, k, f, compensated))
        st["start_frame"] = k
        st["flow"] = kind
        st["flow_rms_px"] = float(f.pow(2).sum(1).sqrt().mean())
        c0, m0, h0 = st["cover"][0], st["mean"][0], st["hf"][0]
        st["summary"] = {"steps": steps, "cover_start": c0, "cover_max_rise": max(st["cover"]) - c0,
                         "cover_min": min(st["cover"]), "cover_max": max(st["cover"]),
                         "mean_ratio_min": min(st["mean"]) / m0, "mean_ratio_max": max(st["mean"]) / m0,
                         "hf_ratio_min": min(st["hf"]) / max(h0, 1e-12), "hf_ratio_end": st["hf"][-1] / max(h0, 1e-12),
                         "finite": st["finite"], "min": min(st["min"]), "max": max(st["max"])}
        out[f"{name}/{kind}"] = st
        frames[f"{name}/{kind}"] = fr
        print(name, kind, json.dumps({k: round(v, 4) if isinstance(v, float) else v for k, v in st["summary"].items()}),
              flush=True)
    return out, frames


def to_rgb(t):
    """(1, 3, N, N) [0, 1] form -> displayable HxWx3 (stretched for visibility)."""
    a = t[0].permute(1, 2, 0).numpy()
    return np.clip(a / 0.85, 0, 1)


def save_frames_png(model, sources, split, path, names=("arm_tsi", "arm_dusk", "mobotix", "proc_05", "arm_clear"),
                    h=6, compensated=False):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    by = {s.name: s for s in sources}
    # A held-out part shorter than the horizon and the frame before has no frame to show.
    short = [n for n in names if n in by and split[n]["heldout"][1] - split[n]["heldout"][0] < h + 2]
    names = [n for n in names if n in by and n not in short]
    if short:
        print(f"frames: {', '.join(short)} left out (held-out part shorter than {h + 2} frames)", flush=True)
    if not names:
        return
    cols = ["input I_k", f"truth k+{h}", f"model prev F, {h} steps", f"model true F, {h} steps",
            f"Farneback x{h}", "persistence"]
    fig, axes = plt.subplots(len(names), len(cols), figsize=(2.2 * len(cols), 2.3 * len(names)), squeeze=False)
    with torch.no_grad():
        for r, name in enumerate(names):
            s = by[name]
            lo, hi = split[name]["heldout"]
            k = lo + 1 + (hi - lo - 1 - h) // 2
            x0 = AD.t_img(s.images[k:k + 1])
            fp = AD.t_img(s.flow[k - 1:k])
            ft = AD.true_flow(s, [k])
            a, b = A.fill_saturated(x0), A.fill_saturated(x0)
            cp, ct = compensation_at(s, k, fp, compensated), compensation_at(s, k, ft, compensated)
            for _ in range(h):
                a = A.step(model, a, fp, cp)
                b = A.step(model, b, ft, ct)
            ims = [x0, AD.t_img(s.images[k + h:k + h + 1]), a, b, A.advect_by_flow(x0, fp, h), x0]
            for c, im in enumerate(ims):
                ax = axes[r, c]
                ax.imshow(to_rgb(im))
                ax.set_xticks([])
                ax.set_yticks([])
                if r == 0:
                    ax.set_title(cols[c], fontsize=8)
                if c == 0:
                    ax.set_ylabel(f"{name}\nframe {k}", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def save_rollout_png(roll, frames, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for key, st in roll.items():
        t = np.arange(len(st["cover"]))
        clear = key.split("/")[0] in ("arm_clear",) or key.startswith("proc_clear")
        ls = "--" if key.endswith("/wind") or key.endswith("/true") else "-"
        if clear:
            axes[0].plot(t, np.array(st["cover"]) - st["cover"][0], ls, label=key)
        else:
            axes[1].plot(t, np.array(st["mean"]) / st["mean"][0], ls, label=key)
            axes[2].plot(t, np.array(st["hf"]) / st["hf"][0], ls, label=key)
    axes[0].axhline(0.03, color="k", lw=0.8)
    axes[0].set_title("clear starts: cover - start cover (limit +0.03)")
    axes[1].axhline(0.8, color="k", lw=0.8)
    axes[1].axhline(1.2, color="k", lw=0.8)
    axes[1].set_title("cloudy starts: mean / start mean (limits 0.8, 1.2)")
    axes[2].axhline(0.5, color="k", lw=0.8)
    axes[2].set_title("cloudy starts: HF energy / start (limit 0.5)")
    for ax in axes:
        ax.set_xlabel("step")
        ax.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    # frames strip of a few rollouts
    keys = [k for k in ("arm_tsi/prev", "mobotix/prev", "proc_05/true", "arm_clear/wind") if k in frames]
    if keys:
        ncol = max(len(frames[k]) for k in keys)
        fig, axes = plt.subplots(len(keys), ncol, figsize=(1.9 * ncol, 2.0 * len(keys)), squeeze=False)
        labels = ["start", "1", "10", "30", "60", "120", "240", "360"]
        for r, k in enumerate(keys):
            for c in range(ncol):
                ax = axes[r, c]
                ax.set_xticks([])
                ax.set_yticks([])
                if c < len(frames[k]):
                    ax.imshow(to_rgb(frames[k][c]))
                    ax.set_title(f"{k} {labels[c]}", fontsize=6)
        fig.tight_layout()
        fig.savefig(path.replace(".png", "_frames.png"), dpi=100)
        plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--data", required=True)
    p.add_argument("--model", action="append", required=True,
                   help="NAME=checkpoint.pt, or NAME=checkpoint.pt@S to shrink the change's bound by S")
    p.add_argument("--out", required=True)
    p.add_argument("--part", default="heldout")
    p.add_argument("--sources", default="")
    p.add_argument("--rollouts", action="store_true")
    p.add_argument("--rollout-part", default="heldout", help="rollouts start at the first frame (+1) of this part")
    p.add_argument("--frames", action="store_true")
    p.add_argument("--no-heldout", action="store_true")
    p.add_argument("--clear-steps", type=int, default=120)
    p.add_argument("--cloudy-steps", type=int, default=360)
    args = p.parse_args(argv)
    torch.set_num_threads(1)
    os.makedirs(args.out, exist_ok=True)
    names = [s for s in args.sources.split(",") if s] or None
    if not os.path.isfile(os.path.join(args.data, "split.json")):
        fail(f"{os.path.join(args.data, 'split.json')}: not found (--data must be a data set of networks/build_dataset_v2.py)")
    base_sources, split = AD.load_sources(args.data, names)
    results, cpu = {}, {}
    for spec in args.model:
        name, path = spec.split("=", 1)
        scale = 1.0
        if "@" in path:  # NAME=ckpt.pt@0.5: the per-step change's bound shrunk by 0.5
            path, scale = path.split("@")
            scale = float(scale)
        model, targs = T.load_model(path)
        compensated, smooth = bool(targs.get("compensated")), bool(targs.get("smooth"))
        if compensated:
            missing = [s.name for s in base_sources if s.background is None]
            if missing:
                fail(f"{path}: trained with --compensated, but {args.data}/{missing[0]}/background.npy is not there "
                     "(rebuild the data set with networks/build_dataset_v2.py)")
        model.bound *= scale
        sources = base_sources
        if targs.get("res") and targs["res"] != base_sources[0].n:
            sources, _ = AD.load_sources(args.data, names)
            for s in sources:
                T.resize_sequence_advect(s, targs["res"])
        n = sources[0].n
        cpu[name] = cpu_time(model, n)
        cpu[name].update({"resolution": n, "widths": targs["widths"], "kernel": targs["kernel"],
                          "parameters": sum(q.numel() for q in model.parameters()), "macs": A.macs(model, n)})
        print(name, json.dumps(cpu[name]), flush=True)
        if not args.no_heldout:
            t0 = time.time()
            results[name] = AE.evaluate(model, sources, split, args.part, (1, 2, 6), compensated=compensated,
                                        smooth=smooth)
            print(f"{name}: evaluated in {time.time() - t0:.0f} s", flush=True)
        if args.rollouts and spec == args.model[0]:
            roll, frames = run_rollouts(model, sources, split, args.clear_steps, args.cloudy_steps, args.rollout_part,
                                        compensated)
            with open(os.path.join(args.out, "rollouts.json"), "w") as f:
                json.dump(roll, f)
            save_rollout_png(roll, frames, os.path.join(args.out, "rollouts.png"))
        if args.frames and spec == args.model[0]:
            save_frames_png(model, sources, split, os.path.join(args.out, f"frames_{args.part}.png"),
                            compensated=compensated)
    if results:
        with open(os.path.join(args.out, f"{args.part}.json"), "w") as f:
            json.dump(results, f, indent=1)
    with open(os.path.join(args.out, "cpu.json"), "w") as f:
        json.dump(cpu, f, indent=1)


if __name__ == "__main__":
    run_main("evaluate_advect.py", main)
