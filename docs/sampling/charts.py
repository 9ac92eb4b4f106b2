
import csv, sys, os
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
out = sys.argv[1]
rows = list(csv.DictReader(open(os.path.join(out, "accuracy.csv"))))
groups = {}
for r in rows:
    groups.setdefault((r["scene"], r["sky"]), {}).setdefault(r["sampler"], []).append(r)
for (scene, sky), by in groups.items():
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for name, rs in sorted(by.items()):
        rs.sort(key=lambda r: int(r["spp"]))
        style = "-" if name.endswith("+mis") else "--"
        axes[0].loglog([int(r["spp"]) for r in rs], [float(r["rmse"]) for r in rs], style, marker="o", ms=3, label=name)
        axes[1].loglog([float(r["seconds"]) for r in rs], [float(r["rmse"]) for r in rs], style, marker="o", ms=3, label=name)
    axes[0].set_xlabel("samples per pixel"); axes[1].set_xlabel("wall time (s)")
    for a in axes: a.set_ylabel("RMSE"); a.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=6, ncol=2)
    fig.suptitle("%s scene, %s sky" % (scene, sky))
    fig.tight_layout(); fig.savefig(os.path.join(out, "rmse_%s_%s.png" % (scene, sky)), dpi=90); plt.close(fig)
rows = list(csv.DictReader(open(os.path.join(out, "rebuild.csv"))))
fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
for k, threads in enumerate(["1", "all"]):
    by = {}
    for r in rows:
        if r["threads"] == threads: by.setdefault(r["sampler"], []).append(r)
    for name, rs in sorted(by.items()):
        rs.sort(key=lambda r: int(r["n"]))
        axes[k].loglog([int(r["n"]) for r in rs], [float(r["ms"]) for r in rs], marker="o", ms=3, label=name)
    axes[k].set_title("rebuild, %s thread(s)" % threads); axes[k].set_xlabel("sky resolution N"); axes[k].set_ylabel("ms")
    axes[k].grid(True, which="both", alpha=0.3)
axes[1].legend(fontsize=7)
fig.tight_layout(); fig.savefig(os.path.join(out, "rebuild.png"), dpi=90); plt.close(fig)
rows = list(csv.DictReader(open(os.path.join(out, "failures.csv"))))
cases = sorted(set(r["case"] for r in rows)); names = sorted(set(r["sampler"] for r in rows))
fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
w = 0.8 / max(1, len(names))
for i, name in enumerate(names):
    vals = {r["case"]: r for r in rows if r["sampler"] == name}
    xs = [c + i * w for c in range(len(cases))]
    axes[0].bar(xs, [float(vals[c]["rel_mse"]) if c in vals else 0 for c in cases], w, label=name)
    axes[1].bar(xs, [float(vals[c]["firefly"]) if c in vals else 0 for c in cases], w, label=name)
for a, t in zip(axes, ["relative MSE (log)", "share of squared error in brightest 0.1% pixels"]):
    a.set_xticks([c + 0.4 for c in range(len(cases))]); a.set_xticklabels(cases, rotation=30, fontsize=7); a.set_title(t)
axes[0].set_yscale("log"); axes[1].legend(fontsize=6, ncol=2)
fig.tight_layout(); fig.savefig(os.path.join(out, "failures.png"), dpi=90); plt.close(fig)
