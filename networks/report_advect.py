#!/usr/bin/python3
"""Tables and charts of docs/networks-advect-residual.md from networks/evaluate_advect.py outputs.

  /usr/bin/python3 networks/report_advect.py --heldout EVAL/heldout.json --model w16 \
      --cpu EVAL/cpu.json --rollouts EVAL/rollouts.json --chart docs/networks-advect-residual.png \
      --tables EVAL/tables.md
"""
import argparse
import json

import numpy as np

REAL = ("arm_tsi", "arm_clear", "arm_dusk", "mobotix")
H = ("1", "2", "6")


def fmt(x):
    return f"{x:.2f}"


def heldout_table(res, sources=None):
    rows = ["| part | h | model, prev F | Farneback | margin | model, true F | persistence | margin | model, F = 0 | "
            "advection only | starts |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    wins_p, wins_t, total_p, total_t = 0, 0, 0, 0
    fails = []
    for name in sources or res:
        r = res[name]
        for h in H:
            if h not in r["model_prev"]:
                continue
            mp, fb = r["model_prev"][h], r["farneback"][h]
            mt, pe = r["model_true"][h], r["persistence"][h]
            total_p += 1
            total_t += 1
            wins_p += mp > fb
            wins_t += mt > pe
            if mp <= fb:
                fails.append(f"{name} h{h} prev {mp - fb:+.2f}")
            if mt <= pe:
                fails.append(f"{name} h{h} true {mt - pe:+.2f}")
            rows.append(f"| {name} | {h} | {fmt(mp)} | {fmt(fb)} | {mp - fb:+.2f} | {fmt(mt)} | {fmt(pe)} | {mt - pe:+.2f} | "
                        f"{fmt(r['model_zero'][h])} | {fmt(r['advect_prev'][h])} | {r['starts']} |")
    return "\n".join(rows), (wins_p, total_p, wins_t, total_t, fails)


def group_means(res):
    """Mean over the cloudy procedural parts and over the clear procedural parts."""
    groups = {"procedural cloudy (16 parts, mean)": [k for k in res if k.startswith("proc_") and "clear" not in k],
              "procedural clear (4 parts, mean)": [k for k in res if k.startswith("proc_clear")]}
    out = {}
    for g, names in groups.items():
        if not names:
            continue
        r = {m: {} for m in res[names[0]] if m != "starts"}
        for m in r:
            for h in H:
                vals = [res[n][m][h] for n in names if h in res[n][m]]
                if vals:
                    r[m][h] = float(np.mean(vals))
        r["starts"] = int(sum(res[n]["starts"] for n in names))
        out[g] = r
    return out


def rollout_table(roll):
    rows = ["| start | F | steps | cover start | max cover rise | mean / start (min-max) | HF / start (min, end) | "
            "[0,1] min-max | finite |", "|---|---|---:|---:|---:|---|---|---|---|"]
    for key, st in roll.items():
        s = st["summary"]
        name, kind = key.split("/")
        rows.append(f"| {name} (frame {st['start_frame']}) | {kind} ({st['flow_rms_px']:.2f} px rms) | {s['steps']} | "
                    f"{s['cover_start']:.3f} | {s['cover_max_rise']:+.3f} | {s['mean_ratio_min']:.3f}-{s['mean_ratio_max']:.3f} | "
                    f"{s['hf_ratio_min']:.2f}, {s['hf_ratio_end']:.2f} | {s['min']:.3f}-{s['max']:.3f} | {s['finite']} |")
    return "\n".join(rows)


def accuracy(res, method="model_prev", sources=REAL):
    return float(np.mean([res[s][method][h] for s in sources if s in res for h in H]))


def chart(heldout, cpu, path, models):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    ax = axes[0]
    for name in models:
        if name not in heldout or name not in cpu:
            continue
        ms = cpu[name]["step_s"] * 1e3
        ax.scatter([ms], [accuracy(heldout[name])], s=40)
        ax.annotate(f"{name} ({cpu[name]['parameters'] / 1e3:.0f} k)", (ms, accuracy(heldout[name])), fontsize=8,
                    xytext=(4, 4), textcoords="offset points")
    ref = heldout[models[0]]
    for base, label, c in (("farneback", "iterated Farneback", "r"), ("persistence", "persistence", "k"),
                           ("advect_prev", "advection only (no net)", "g")):
        ax.axhline(accuracy(ref, base), color=c, ls="--", lw=1, label=label)
    ax.set_xlabel("PyTorch CPU time per step, 1 thread, warp + network (ms)")
    ax.set_ylabel("held-out PSNR, mean of 4 real parts x horizons 1, 2, 6 (dB)")
    ax.set_title("accuracy vs CPU time (model given the previous frame)")
    ax.legend(fontsize=8)
    ax = axes[1]
    name = models[0]
    r = heldout[name]
    hs = [int(h) for h in H]
    for src, c in zip(REAL, ("C0", "C1", "C2", "C3")):
        if src not in r:
            continue
        ax.plot(hs, [r[src]["model_prev"][h] for h in H], "-o", color=c, label=f"{src} model prev F")
        ax.plot(hs, [r[src]["farneback"][h] for h in H], "--", color=c, label=f"{src} Farneback")
        ax.plot(hs, [r[src]["persistence"][h] for h in H], ":", color=c, label=f"{src} persistence")
    ax.set_xlabel("horizon (steps)")
    ax.set_ylabel("held-out PSNR (dB)")
    ax.set_title(f"{name}: real held-out parts")
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser()
    p.add_argument("--heldout", required=True)
    p.add_argument("--cpu", required=True)
    p.add_argument("--model", required=True, help="the shipped model's name in the JSON")
    p.add_argument("--chart-models", default="")
    p.add_argument("--rollouts", default="")
    p.add_argument("--chart", default="")
    p.add_argument("--tables", required=True)
    args = p.parse_args(argv)
    res = json.load(open(args.heldout))
    cpu = json.load(open(args.cpu))
    r = res[args.model]
    lines = ["## Held-out, real parts", ""]
    t, (wp, tp, wt, tt, fails) = heldout_table(r, [s for s in REAL if s in r])
    lines += [t, ""]
    lines += ["## Held-out, procedural groups (means over parts)", ""]
    g = group_means(r)
    lines += [heldout_table(g)[0], ""]
    lines += ["## Held-out, every procedural part", ""]
    t2, (wp2, tp2, wt2, tt2, fails2) = heldout_table(r, [s for s in r if s.startswith("proc_")])
    lines += [t2, ""]
    lines += [f"Model (prev F) above iterated Farneback: {wp + wp2} of {tp + tp2} (part, horizon) cells "
              f"(real {wp}/{tp}); model (true F) above persistence: {wt + wt2} of {tt + tt2} (real {wt}/{tt}).", "",
              "Cells that miss: " + ("; ".join(fails + fails2) or "none"), ""]
    lines += ["## Sizes", "", "| model | resolution | widths | kernel | parameters | MACs / step | CPU ms / step (warp + net) | "
              "net only | real held-out PSNR, prev F (mean h 1, 2, 6) | true F |", "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name, c in cpu.items():
        if name in res:
            lines.append(f"| {name} | {c['resolution']} | {c['widths']} | {c['kernel']} | {c['parameters']:,} | "
                         f"{c['macs'] / 1e6:.1f} M | {c['step_s'] * 1e3:.2f} | {c['network_s'] * 1e3:.2f} | "
                         f"{accuracy(res[name]):.2f} | {accuracy(res[name], 'model_true'):.2f} |")
    lines.append(f"| iterated Farneback | | | | | | | | {accuracy(r, 'farneback'):.2f} | |")
    lines.append(f"| persistence | | | | | | | | | {accuracy(r, 'persistence'):.2f} |")
    if args.rollouts:
        lines += ["", "## Rollouts", "", rollout_table(json.load(open(args.rollouts))), ""]
    with open(args.tables, "w") as f:
        f.write("\n".join(lines) + "\n")
    if args.chart:
        models = [m for m in args.chart_models.split(",") if m] or [args.model]
        chart(res, cpu, args.chart, models)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
