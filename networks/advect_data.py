"""Loading the advect-residual data set (networks/build_dataset_v2.py) and drawing training batches.

Each sample: a source (weighted), a frame k of the chosen part (k - 1 in it too, k + K in it), a
flow F chosen from
  prev  the Farneback flow (k - 1 -> k)                               [the --prev case]
  true  procedural: the exact flow of step k -> k + 1 (the wind field, defined everywhere);
        real: the previous pair's Farneback flow fitted as one uniform wind (advect.fit_uniform_wind)
  wind  clear sources only: a random uniform wind over the clear sky (whose right answer is still
        "nothing moves"), as a user wind over a clear sky would give
  zero  F = 0 (the no-information case)
and the targets k + 1 .. k + K (the same F for every step). Augmentation: rotation about the
zenith (images resampled through the rim extension, valid masks resampled, flow vectors rotated),
mirroring (flip x, negate flow x), exposure and white-balance gains applied to the radiance
(inverse log map, scale, map back).
"""
import json
import math
import os

import numpy as np
import torch

import advect as A

DEFAULT_WEIGHTS = {"arm_tsi": 2.0, "arm_clear": 1.0, "arm_dusk": 1.5, "mobotix": 2.0}
PROC_WEIGHT = 0.25


class Source:
    def __init__(self, folder, name=None):
        self.name = name or os.path.basename(os.path.normpath(folder))
        with open(os.path.join(folder, "meta.json")) as f:
            self.meta = json.load(f)
        self.images = np.load(os.path.join(folder, "images.npy"))
        self.valid = np.load(os.path.join(folder, "valid.npy"))
        self.cloud = np.load(os.path.join(folder, "cloud.npy"))
        self.flow = np.load(os.path.join(folder, "flow_farneback.npy"))
        bg = os.path.join(folder, "background.npy")
        self.background = np.load(bg) if os.path.exists(bg) else None
        ex = os.path.join(folder, "flow_exact.npy")
        self.flow_exact = np.load(ex) if os.path.exists(ex) else None
        self.procedural = self.flow_exact is not None
        self.clear = self.name.startswith("proc_clear") or self.name == "arm_clear"
        self.n = self.images.shape[1]

    def __len__(self):
        return self.images.shape[0]


def load_sources(data_dir, names=None):
    split = json.load(open(os.path.join(data_dir, "split.json")))
    names = names or sorted(split)
    return [Source(os.path.join(data_dir, s)) for s in names], split


def t_img(a):
    return torch.from_numpy(np.ascontiguousarray(a)).float().permute(0, 3, 1, 2)


def t_valid(a):
    """(K, N, N) valid masks as (K, 1, N, N) floats."""
    return torch.from_numpy(np.ascontiguousarray(a).astype(np.float32))[:, None]


def wind_weights(src, k, n):
    """Pixels the uniform-wind fit of Farneback (k - 1 -> k) uses: seen cloud pixels with r < 0.9
    (all seen pixels when fewer than 50 are cloud)."""
    c = A.pixel_centres(n)
    r = np.hypot(*np.meshgrid(c, c))
    base = (src.valid[k - 1] * src.valid[k]).astype(np.float32) * (r < 0.9)
    w = base * src.cloud[k - 1]
    return w if w.sum() >= 50 else base


def true_flow(src, ks):
    """(B, 2, N, N) the 'true motion' flow for start frames ks (see module doc)."""
    n = src.n
    if src.procedural:
        return t_img(src.flow_exact[ks])
    prev = t_img(src.flow[[k - 1 for k in ks]])
    w = torch.from_numpy(np.stack([wind_weights(src, k, n) for k in ks]))[:, None]
    _, fit = A.fit_uniform_wind(prev, w, n)
    return fit


class Sampler:
    def __init__(self, sources, split, part, unroll, weights=None, p_zero=0.15, p_wind_clear=0.3,
                 augment=True, seed=1, compensated=False, smooth=False):
        self.sources = sources
        self.unroll = unroll
        self.ranges = []
        w = []
        for s in sources:
            lo, hi = split[s.name][part]
            self.ranges.append((lo + 1, hi - unroll))  # k - 1 >= lo, k + K <= hi - 1
            default = DEFAULT_WEIGHTS.get(s.name, PROC_WEIGHT)
            w.append((weights or {}).get(s.name, default))
        w = np.array(w, np.float64)
        self.p = w / w.sum()
        self.p_zero = p_zero
        self.p_wind_clear = p_wind_clear
        self.augment = augment
        self.compensated = compensated
        self.smooth = smooth
        self.rng = np.random.default_rng(seed)

    def state(self):
        return self.rng.bit_generator.state

    def set_state(self, st):
        self.rng.bit_generator.state = st

    def batch(self, b):
        rng = self.rng
        K = self.unroll
        imgs, valids, flows, kinds, bgs = [], [], [], [], []
        for _ in range(b):
            si = rng.choice(len(self.sources), p=self.p)
            s = self.sources[si]
            lo, hi = self.ranges[si]
            k = int(rng.integers(lo, hi))
            imgs.append(s.images[k:k + K + 1])
            valids.append(s.valid[k:k + K + 1])
            bgs.append(s.background[k] if s.background is not None else np.zeros_like(s.images[k]))
            u = rng.random()
            if u < self.p_zero:
                kind = "zero"
                f = torch.zeros(1, 2, s.n, s.n)
            elif s.clear and u < self.p_zero + self.p_wind_clear:
                kind = "wind"
                speed = rng.uniform(0.02, 0.25)  # displacement per step in layer heights (0.6-7 px at zenith)
                ang = rng.uniform(0, 2 * math.pi)
                f = A.wind_flow(s.n, [[speed * math.cos(ang), speed * math.sin(ang)]])
            elif rng.random() < 0.5:
                kind = "prev"
                f = t_img(s.flow[k - 1:k])
                if self.smooth:
                    trusted = A.trusted_flow_pixels(t_valid(s.valid[k - 1:k]), t_valid(s.valid[k:k + 1]),
                                                    t_img(s.images[k - 1:k]), t_img(s.images[k:k + 1]))
                    f = A.smooth_motion(f, trusted)
            else:
                kind = "true"
                f = true_flow(s, [k])
            flows.append(f)
            kinds.append(kind)
        n = self.sources[0].n
        x = torch.from_numpy(np.stack(imgs)).float().permute(0, 1, 4, 2, 3)  # B, K+1, 3, N, N
        v = torch.from_numpy(np.stack(valids).astype(np.float32))[:, :, None]  # B, K+1, 1, N, N
        f = torch.cat(flows, 0)
        bg = t_img(np.stack(bgs)) if self.compensated else None
        if self.augment:
            x, v, f, bg = augment(x, v, f, rng, bg=bg)
        comp = A.compensation(bg, f) if self.compensated else None
        return x, v, f, kinds, comp


def augment(x, v, f, rng, p_rot=0.75, p_mirror=0.5, exposure_sigma=0.25, wb_sigma=0.05, bg=None):
    B, T, C, n, _ = x.shape
    disc = A._disc_t(n, x.device)
    rot = rng.random(B) < p_rot
    if rot.any():
        ang = torch.from_numpy(np.where(rot, rng.uniform(0, 2 * math.pi, B), 0.0).astype(np.float32))
        angT = ang.repeat_interleave(T)
        x = (A.rotate(x.reshape(B * T, C, n, n), angT) * disc).reshape(B, T, C, n, n)
        v = (A.rotate(v.reshape(B * T, 1, n, n), angT, extend=False) > 0.99).float().reshape(B, T, 1, n, n)
        f = A.rotate_flow(f, ang) * disc
        if bg is not None:
            bg = A.rotate(bg, ang) * disc
        # unrotated samples: angle 0 resamples exactly (identity grid), nothing changes
    mir = rng.random(B) < p_mirror
    if mir.any():
        idx = torch.from_numpy(np.nonzero(mir)[0])
        x[idx] = torch.flip(x[idx], [-1])
        v[idx] = torch.flip(v[idx], [-1])
        f[idx] = A.mirror_flow(f[idx])
        if bg is not None:
            bg[idx] = torch.flip(bg[idx], [-1])
    gains = np.exp(rng.normal(0, exposure_sigma, (B, 1)) + rng.normal(0, wb_sigma, (B, 3)))
    g = torch.from_numpy(gains.astype(np.float32))
    x = A.exposure_jitter(x.reshape(B * T, C, n, n), g.repeat_interleave(T, 0)).reshape(B, T, C, n, n) * disc
    if bg is not None:
        bg = A.exposure_jitter(bg, g) * disc
    return x, v, f, bg
