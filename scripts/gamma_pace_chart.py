#!/usr/bin/python3
"""Charts the pace of Gamma's two in-betweens from bench/gamma_pace's CSV.

    build/bench/gamma_pace docs && /usr/bin/python3 scripts/gamma_pace_chart.py docs/gamma-pace.csv docs/gamma-pace.png

Top: cloud displacement between consecutive frames (degrees); bottom: second difference of the
horizontal illuminance the sky gives a scene (lx per frame^2). Medium steps are shaded.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main(path, out):
    rows = list(csv.DictReader(open(path)))
    t = [float(r["time_s"]) for r in rows]
    col = lambda name: [float(r[name]) for r in rows]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6.5), dpi=110, sharex=True)
    for ax in (top, bottom):
        for r, x in zip(rows, t):
            if r["boundary"] == "1":
                ax.axvline(x, color="0.85", lw=5, zorder=0)
        ax.grid(alpha=0.3)
    style = {"constant": dict(color="tab:blue", marker="o", ms=3), "paper": dict(color="tab:orange", marker="s", ms=3)}
    for g, label in (("constant", "constant pace (default)"), ("paper", "the paper's (--gamma paper)")):
        top.plot(t, col("displacement_%s_deg" % g), label=label, **style[g])
        bottom.plot(t, col("d2_illuminance_%s_lx" % g), label=label, **style[g])
    top.set_ylabel("cloud displacement per frame (deg)")
    top.set_title("Gamma's pace between medium steps (grey: steps)")
    bottom.set_ylabel("2nd difference of illuminance (lx)")
    bottom.set_xlabel("time (s)")
    top.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    fig.savefig(out)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
