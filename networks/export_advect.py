#!/usr/bin/python3
"""Exports a trained advect-residual model (networks/train_advect.py) as the folder the C++ side
loads:

  /usr/bin/python3 networks/export_advect.py --checkpoint RUN/final.pt --data /work/data/dataset_v2 \
      --out networks/models/advect_residual [--eval EVAL.json]

  model.onnx             opset 11, fixed 1 x 8 x N x N input "warped_image_flow", output "next"
                         1 x 3 x N x N (before clamping); position planes are constants added after
                         the first and last convolutions; Resize with constant scales
  model.json             format dynsky-cloud-model, version 2, kind advect-residual, the interface
  split.json             per source: frames trained on (train / fit), validation, held out
  reference_image.npy    1 x 3 x N x N  I (a held-out real frame, [0, 1] form)
  reference_flow.npy     1 x 2 x N x N  F (its previous pair's Farneback flow, pixels at N)
  reference_input.npy    1 x 8 x N x N  [W, I, F / (0.08 N)] as Python builds it from the two
                         above (the C++ warp can be checked against it)
  reference_output.npy   1 x 3 x N x N  PyTorch's output for reference_input (before clamping)
"""
import argparse
import copy
import datetime
import json
import os
import sys

import numpy as np
import torch

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import advect as A  # noqa: E402
import export as E  # noqa: E402
import unet as U  # noqa: E402
from script_errors import fail, run_main  # noqa: E402

INTERFACE = """\
N = the network resolution (model.json "resolution"). Images are in the [0, 1] network form
(log map: v = log(1 + L / unit_scale) / log(1 + unit_max / unit_scale), clipped), 0 outside the sky
disc (pixel (i, j) has centre u = (i + 0.5) 2 / N - 1, v = (j + 0.5) 2 / N - 1; inside if r <= 1).
Flow F (N x N x 2, pixels at N per step, +x right, +y down): the displacement content undergoes
over one step. Sources: (a) the previous frame: Farneback flow previous -> current; (b) a user
wind (procedural data: the exact flow); (c) nothing: F = 0.
Rim extension E(I): for each pixel centre, u = 2(i + 0.5)/N - 1, v = 2(j + 0.5)/N - 1,
r = hypot(u, v); if r > r_in = 1 - 1.5/N scale (u, v) by r_in / r; sample I bilinearly at
x = (u + 1)N/2 - 0.5, y = (v + 1)N/2 - 0.5 (border replicate).
Warp (outside the ONNX graph): W(x) = E(I)(x - F(x)), bilinear, border replicate (cv::remap
INTER_LINEAR + BORDER_REPLICATE with pixel-centre coordinates = PyTorch grid_sample
align_corners=True, padding border), then 0 outside the disc.
ONNX input: 1 x 8 x N x N = [W (3), I (3), F / (flow_scale N) (2)]; output: 1 x 3 x N x N = the
next image before clamping; the caller clamps to [0, 1] and zeros outside the disc.
Recursion: a rollout keeps F fixed (constant velocity, Eulerian) and feeds each prediction back
as I. The flow input sets the speed, so any cadence works: dt_s is the cadence trained on most
(ARM, 30 s); a 60 s cadence (Mobotix, in training) gives a flow per 60 s.
Saturated pixels (>= 0.999 in any channel: the sun) are removed (filled from their surroundings)
before stepping, as for the v1 model."""


USER_WIND = """\
How the training built a flow from a uniform wind (networks/advect.py wind_flow; the procedural exact flow
agrees to ~0.01-0.1 px): the layer displacement per step w = (wind speed x dt / layer height) in image axes
(+x right = west, +y down = south in the canonical north-up, east-left fisheye). For each pixel centre (u, v),
r = hypot(u, v), theta = r x 90 deg (clamped to 88 deg), ground point P = tan(theta) (u, v) / r (units of the
layer height); source S = P - w; r_s = atan(|S|) / 90 deg; F = ((u, v) - r_s S / |S|) x N / 2 pixels
(0 beyond 88 deg)."""


def export_onnx(model, n, path):
    model = copy.deepcopy(model).eval()
    for m in model.modules():
        if isinstance(m, U.UNet):
            m.freeze_position(n)
    torch.onnx.export(model, torch.zeros(1, 8, n, n), path, opset_version=11, input_names=["warped_image_flow"],
                      output_names=["next"], do_constant_folding=True)
    E.inline_constant_identities(path)
    return E.check_onnx_for_opencv(path)


@torch.no_grad()
def write_reference(model, image, flow, folder, background=None):
    """image (1, 3, N, N), flow (1, 2, N, N); background (1, 3, N, N) for a model trained on the
    compensated warp (its input is then warp(I) + B - warp(B), as the C++ side builds it)."""
    model.eval()
    x = A.network_input(image, flow, A.compensation(background, flow) if background is not None else None)
    y = model(x)
    if background is not None:
        np.save(os.path.join(folder, "reference_background.npy"), background.numpy().astype(np.float32))
    np.save(os.path.join(folder, "reference_image.npy"), image.numpy().astype(np.float32))
    np.save(os.path.join(folder, "reference_flow.npy"), flow.numpy().astype(np.float32))
    np.save(os.path.join(folder, "reference_input.npy"), x.numpy().astype(np.float32))
    np.save(os.path.join(folder, "reference_output.npy"), y.numpy().astype(np.float32))


def model_info(model, args, n, ops, extra=None):
    info = {
        "format": "dynsky-cloud-model",
        "version": 2,
        "kind": "advect-residual",
        "name": os.path.basename(os.path.normpath(args["out"])) if "out" in args else "advect_residual",
        "resolution": n,
        "import_resolution": 256,
        "dt_s": 30.0,
        "dt_note": "the flow input sets the speed: any cadence works with a flow measured (or a wind projected) "
                   "over that cadence; trained on 30 s (ARM, procedural) and 60 s (Mobotix) steps",
        "flow_scale": A.FLOW_SCALE,
        "unit_scale": A.UNIT_SCALE,
        "unit_max": A.UNIT_MAX,
        "cloud_rule": "rb",
        "cloud_threshold": 0.75,
        "widths": list(model.widths),
        "kernel": model.kernel,
        "change_bound": model.bound,
        "gate": bool(getattr(model, "gate", False)),
        "network_output_rule": ("next = sigmoid(-g) W + sigmoid(g) I + change_bound tanh(c); the UNet's 4 output channels "
                                "are g, c_r, c_g, c_b" if getattr(model, "gate", False) else
                                "next = W + change_bound tanh(c)" if not model.kernel else
                                "next = softmax-weighted k x k neighbours of W + change_bound tanh(c)"),
        "user_wind_flow": USER_WIND,
        "input": {"name": "warped_image_flow", "shape": [1, 8, n, n],
                  "channels": ["W r", "W g", "W b", "I r", "I g", "I b", "F x / (flow_scale N)", "F y / (flow_scale N)"]},
        "output": {"name": "next", "shape": [1, 3, n, n], "note": "before clamping; clamp to [0, 1], 0 outside the disc"},
        "rim_r_in": "1 - 1.5 / N",
        "saturated_threshold": A.SATURATED,
        "interface": INTERFACE,
        "onnx_file": "model.onnx",
        "onnx_opset": 11,
        "onnx_ops": ops,
        "parameters": U.parameter_count(model),
        "macs_per_step": A.macs(model, n),
        "created": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ"),
    }
    info.update(extra or {})
    return info


def write_card(args, info, used, names, excluded):
    import advect_data as AD
    lines = [f"# Model card: {info['name']} (kind advect-residual)", "",
             "A medium-step cloud model whose motion comes from a GIVEN flow, never from memory: the sky is "
             "warped by the flow (outside the network) and a small UNet corrects the warped image by a bounded "
             "change. Report, figures and how it was chosen: docs/networks-advect-residual.md.", "",
             "## Interface (exact; the C++ side implements this)", "", "```", INTERFACE, "```", "",
             "## What it is", "",
             f"- N = {info['resolution']}; UNet widths {info['widths']} (networks/unet.py blocks, (u, v) position "
             "planes added as constants after the first and last convolutions), input 8 channels, output "
             + ("4 channels (g, c): next = sigmoid(-g) W + sigmoid(g) I + " if info.get("gate") else
                "3 channels: next = W + " if not info["kernel"] else
                f"{info['kernel'] ** 2} kernel logits + 3: next = softmax-weighted {info['kernel']} x {info['kernel']} "
                "neighbours of W + ") + f"{info['change_bound']:g} tanh(c)"
             + (" (the gate variant: per pixel the net blends the warped image W and the unwarped I, so it can hold "
                "clear sky still under a wind, and adds a bounded change)." if info.get("gate") else "."),
             f"- {info['parameters']:,} parameters, {info['macs_per_step'] / 1e6:.1f} M multiply-adds per step; "
             f"ONNX opset 11, fixed 1 x 8 x {info['resolution']} x {info['resolution']} input, operators "
             f"{', '.join(info['onnx_ops'])}.",
             "- reference_image.npy (I) and reference_flow.npy (F) give reference_input.npy through the warp above; "
             "reference_output.npy is PyTorch's output for reference_input.npy (before clamping).", "",
             "## Data and split", "",
             "| source | frames | dt | what | fit (train) | validation | held out |", "|---|---:|---:|---|---|---|---|"]
    what = {"arm_tsi": "ARM TSI 2017-05-24 15:40-18:09 UTC, broken cumulus",
            "arm_clear": "ARM TSI 2017-05-24 12:00-15:39 UTC, clear morning",
            "arm_dusk": "ARM TSI 2017-05-24 00:00-01:30 UTC, overcast clearing at dusk",
            "mobotix": "Mobotix, Sophia Antipolis 2020-08-12 06:00-13:59, mostly overcast (other camera)"}
    for name, sp in used.items():
        meta = json.load(open(os.path.join(args.data, name, "meta.json")))
        desc = what.get(name)
        if desc is None:
            pr = meta.get("procedural", {})
            layers = ", ".join(f"{l['type']} {l['wind_speed_mps']:g} m/s from {l['wind_from_deg']:g} deg at "
                               f"{l['altitude_m'] / 1e3:g} km" for l in pr.get("layers", []))
            desc = f"procedural, coverage {pr.get('coverage')}: {layers}"
        lines.append(f"| {name} | {meta['frame_count']} | {meta['dt_s']:g} s | {desc} | {sp['fit'][0]}-{sp['fit'][1] - 1} "
                     f"({sp['train'][0]}-{sp['train'][1] - 1}) | {sp['val'][0]}-{sp['val'][1] - 1} | "
                     f"{sp['heldout'][0]}-{sp['heldout'][1] - 1} |")
    lines += ["", f"Trained on the part `{info.get('trained_part')}` (fit = first 70 %, train = first 80 %) of: "
              f"{', '.join(info['trained_on'])}" + (f"; left out: {', '.join(sorted(e for e in excluded if e))}" if any(excluded) else "")
              + ". The last 20 % of every source (held out) was not used for training or model selection "
              "(selection used the validation part, 70-80 %).", "",
              "Samples (networks/advect_data.py): frame k, flow F = prev Farneback (k-1 -> k) / true motion "
              "(procedural: exact flow; real: the prev Farneback flow fitted as one uniform wind) / a random uniform "
              "wind on clear skies / 0 (p = 0.15); targets k+1..k+K with the same F; rotation about the zenith "
              "(flow vectors rotated), mirroring, exposure and white-balance gains in HDR. Loss: per sample "
              "log(MSE + 0.05 (1 - cos) + 1e-6) over pixels seen at k and k+t and not saturated.", ""]
    if args.command:
        lines += ["## Training command", "", "```", args.command, "```", ""]
    if args.card_tables and os.path.exists(args.card_tables):
        lines += ["# Results (held-out, PyTorch, [0, 1] form at N, seen sky pixels)", "",
                  "model, prev F: given the previous frame (F = Farneback prev -> current, fixed); model, true F: from one "
                  "frame with the true motion (procedural: exact flow; real: the previous pair's Farneback flow fitted as "
                  "one uniform wind); Farneback: the previous pair's flow applied h times, "
                  "out(x) = I(x - h F(x)), 0 outside (sky/sky_metrics.cpp advect_by_flow). PSNR: mean of per-frame "
                  "10 log10(1 / MSE).", ""]
        lines += [l.replace("## ", "### ") for l in open(args.card_tables).read().splitlines()]
    if getattr(args, "card_extra", "") and os.path.exists(args.card_extra):
        lines += [""] + open(args.card_extra).read().splitlines()
    lines += ["", "## Limits", "",
              "- The network corrects a warp; it cannot know motion the flow does not carry (F = 0 gives a "
              "persistence-like sky).",
              "- Clouds entering the view upwind come from the rim extension (the rim's values carried inward), "
              "corrected by the net; over long rollouts these streaks, not real new clouds, fill the upwind sky.",
              "- Trained on four real sequences of two cameras on two days; the sun and its aureole are not predicted "
              "(saturated pixels are removed before stepping; none occur at 64 px in this data set).", ""]
    with open(os.path.join(args.out, "MODEL_CARD.md"), "w") as f:
        f.write("\n".join(lines))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--checkpoint", required=True)
    p.add_argument("--data", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--reference-source", default="",
                   help="the data set's sequence whose first held-out frame gives the reference pair "
                        "(default: arm_tsi when the data set has it, else the first in its split.json)")
    p.add_argument("--extra", default="", help="JSON file of extra model.json fields (metrics, timings)")
    p.add_argument("--card-tables", default="", help="markdown (networks/report_advect.py --tables) for the card")
    p.add_argument("--command", default="", help="the training command, for the card")
    p.add_argument("--card-extra", default="", help="more markdown for the card (unseen camera, stability verdicts)")
    args = p.parse_args(argv)
    import advect_data as AD
    import train_advect as T
    model, targs = T.load_model(args.checkpoint)
    os.makedirs(args.out, exist_ok=True)
    split_path = os.path.join(args.data, "split.json")
    if not os.path.exists(split_path):
        fail(f"{split_path}: not found (--data must be a data set of networks/build_dataset_v2.py)")
    split = json.load(open(split_path))
    reference = args.reference_source or ("arm_tsi" if "arm_tsi" in split else (sorted(split) or [""])[0])
    if reference not in split or not os.path.exists(os.path.join(args.data, reference, "meta.json")):
        fail(f"{args.data}: no sequence '{reference}' for the reference pair (--reference-source; "
                 f"the data set has: {', '.join(sorted(split)) or 'none'})")
    src = AD.Source(os.path.join(args.data, reference))
    if targs.get("res") and targs["res"] != src.n:
        T.resize_sequence_advect(src, targs["res"])
    n = src.n
    ops = export_onnx(model, n, os.path.join(args.out, "model.onnx"))
    k = split[src.name]["heldout"][0] + 1
    compensated = bool(targs.get("compensated"))
    if compensated and src.background is None:
        fail(f"{args.data}/{reference}: no background.npy, which a model trained with --compensated needs for its "
                 "reference pair (rebuild the data set with networks/build_dataset_v2.py)")
    for stale in ("reference_background.npy",):
        if os.path.exists(os.path.join(args.out, stale)):
            os.remove(os.path.join(args.out, stale))
    write_reference(model, AD.t_img(src.images[k:k + 1]), AD.t_img(src.flow[k - 1:k]), args.out,
                    AD.t_img(src.background[k:k + 1]) if compensated else None)
    extra = json.load(open(args.extra)) if args.extra else {}
    # What the C++ side must do for this checkpoint (motion/advect_residual.cpp reads "base"): a model
    # trained on the compensated warp run on the plain one moves the sky's gradient with the clouds.
    extra.setdefault("base", "compensated" if compensated else "warp")
    if targs.get("smooth"):
        extra.setdefault("previous_frame_flow", "smoothed (Gaussian sigma N / 32)")
    names = [s for s in (targs.get("sources") or "").split(",") if s] or sorted(split)
    ex = set((targs.get("exclude") or "").split(","))
    used = {s: split[s] for s in names if s not in ex}
    extra.setdefault("trained_on", sorted(used))
    extra.setdefault("trained_part", targs.get("part"))
    extra.setdefault("training", {k: targs[k] for k in ("epochs", "steps_per_epoch", "batch", "unroll", "lr", "p_zero",
                                                          "cos_weight", "seed", "threads") if k in targs})
    info = model_info(model, {"out": args.out}, n, ops, extra)
    with open(os.path.join(args.out, "model.json"), "w") as f:
        json.dump(info, f, indent=2)
    with open(os.path.join(args.out, "split.json"), "w") as f:
        json.dump(used, f, indent=2)
    write_card(args, info, used, names, ex)
    size = os.path.getsize(os.path.join(args.out, "model.onnx"))
    print(f"wrote {args.out}: model.onnx {size / 1e6:.2f} MB, ops {ops}")
    return info


if __name__ == "__main__":
    run_main("export_advect.py", main)
