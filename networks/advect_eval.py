"""Held-out scoring of the advect-residual model against persistence and iterated Farneback.

For every start frame k of a part (k - 1 and k + max horizon inside it), at horizons h:
  model_prev   the model given the previous frame: F = Farneback (k - 1 -> k), fixed, h steps
  model_true   the model from one frame with the true motion: procedural F = exact flow of step
               k -> k + 1; real F = the Farneback flow (k - 1 -> k) fitted as one uniform wind
  model_zero   the model with F = 0
  advect_prev  pure advection (W recursion, no network) with the prev flow: what the net adds
  persistence  I_k
  farneback    I_k(x - h F(x)), bilinear, 0 outside (sky/sky_metrics.cpp advect_by_flow)
PSNR = mean over start frames of 10 log10(1 / MSE), MSE over the three channels of the pixels seen
at k and k + h (valid.npy) and not saturated (>= 0.999 in any channel) in either, [0, 1] form at N.
"""
import numpy as np
import torch

import advect as A
import advect_data as AD

strong_baseline = True  # Farneback with the rim extended, as `dynsky sky evaluate` scores it

METHODS = ("model_prev", "model_true", "model_zero", "advect_prev", "persistence", "farneback")


def pure_advection(x):
    return x[:, 0:3]


@torch.no_grad()
def evaluate_source(model, src, split, part="heldout", horizons=(1, 2, 6), max_starts=None, methods=METHODS,
                    batch=32, compensated=False, smooth=False):
    model.eval() if model is not None and hasattr(model, "eval") else None
    lo, hi = split[src.name][part]
    horizons = tuple(h for h in horizons if hi - (lo + 1) - h >= 1) or horizons[:1]
    H = max(horizons)
    starts = list(range(lo + 1, hi - H))
    if not starts:
        return {m: {} for m in methods}, 0
    if max_starts and len(starts) > max_starts:
        starts = starts[:: int(np.ceil(len(starts) / max_starts))]
    n = src.n
    disc = A._disc_t(n, "cpu")
    res = {m: {h: [] for h in horizons} for m in methods}
    for b0 in range(0, len(starts), batch):
        ks = starts[b0:b0 + batch]
        x0 = AD.t_img(src.images[ks])
        v0 = torch.from_numpy(src.valid[ks].astype(np.float32))[:, None]
        sat0 = A.saturated(x0)
        f_prev = AD.t_img(src.flow[[k - 1 for k in ks]])
        # The models' motion estimate (smoothed, as the C++ side); the baseline keeps the raw flow.
        trusted = A.trusted_flow_pixels(AD.t_valid(src.valid[[k - 1 for k in ks]]), v0,
                                         AD.t_img(src.images[[k - 1 for k in ks]]), x0)
        f_model = A.smooth_motion(f_prev, trusted) if smooth else f_prev
        if compensated and src.background is None:
            # Scoring a compensated model on the plain warp (B = 0) would score another model.
            raise ValueError(f"source {src.name}: no background.npy, which a model trained with --compensated needs "
                             "(rebuild the data set with networks/build_dataset_v2.py)")
        bg = AD.t_img(src.background[ks]) if compensated else None
        flows = {"model_prev": f_model, "advect_prev": f_model, "model_zero": torch.zeros_like(f_prev)}
        if "model_true" in methods:
            flows["model_true"] = AD.true_flow(src, ks)
        preds = {}
        for m in methods:
            if m in flows:
                net = pure_advection if m == "advect_prev" else model
                x = A.fill_saturated(x0)
                out = {}
                comp = A.compensation(bg, flows[m])
                for h in range(1, H + 1):
                    x = A.step(net, x, flows[m], comp)
                    if h in horizons:
                        out[h] = x
                preds[m] = out
        for h in horizons:
            tgt = AD.t_img(src.images[[k + h for k in ks]])
            vh = torch.from_numpy(src.valid[[k + h for k in ks]].astype(np.float32))[:, None]
            mask = v0 * vh * (1 - sat0) * (1 - A.saturated(tgt))
            for m in methods:
                if m == "persistence":
                    p = x0
                elif m == "farneback":
                    # the strong form: rim extended (C++ sky evaluate), one warp by h F
                    p = A.warp(x0, f_prev * h) if strong_baseline else A.advect_by_flow(x0, f_prev, h)
                else:
                    p = preds[m][h]
                mse = ((p - tgt) ** 2).mean(1, keepdim=True)
                mse = (mse * mask).sum((1, 2, 3)) / mask.sum((1, 2, 3)).clamp(min=1)
                res[m][h].extend((10 * torch.log10(1.0 / mse.clamp(min=1e-10))).tolist())
    return {m: {h: float(np.mean(v)) for h, v in r.items()} for m, r in res.items()}, len(starts)


def evaluate(model, sources, split, part="heldout", horizons=(1, 2, 6), max_starts=None, methods=METHODS,
             compensated=False, smooth=False):
    out = {}
    for s in sources:
        r, count = evaluate_source(model, s, split, part, horizons, max_starts, methods, compensated=compensated,
                                   smooth=smooth)
        r["starts"] = count
        out[s.name] = r
    return out


def selection_score(ev, horizons=(1, 2, 6), clip=3.0):
    """Model-selection number (validation parts): mean over sources and horizons of
    (model_prev - farneback) and (model_true - persistence), each clipped to +-clip dB so that no
    single part (e.g. a static clear procedural sky where persistence is exact, 100 dB) dominates."""
    d = []
    for name, r in ev.items():
        for h in horizons:
            if h in r.get("model_prev", {}):
                d.append(np.clip(r["model_prev"][h] - r["farneback"][h], -clip, clip))
            if h in r.get("model_true", {}):
                d.append(np.clip(r["model_true"][h] - r["persistence"][h], -clip, clip))
    return float(np.mean(d)) if d else float("nan")
