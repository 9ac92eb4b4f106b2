"""Reading a dataset built by networks/dataset.py, and the flow-target encoding.

A dataset folder holds one sub-folder per sequence (written by `dynsky sky training-data`):
  images.npy          float32 (T, N, N, 3): frames in the networks' [0, 1] form (sky/hdr_recovery.h
                      forward map), 0 outside the sky disc
  valid.npy           uint8 (T, N, N): 1 where the sky was seen (inside the disc and not hidden by
                      the camera's arm / shadow band / masts); losses and metrics use only these
  cloud.npy           uint8 (T, N, N): the red/blue > threshold cloud mask (sky/cloud_mask.h)
  flow_farneback.npy  float32 (T-1, N, N, 2): OpenCV Farneback flow frame k -> k+1, pixels of N
  flow_exact.npy      float32 (T-1, N, N, 2): procedural sequences only, the exact flow
  meta.json           times, Delta t, resolution, where the frames came from
and split.json at the top fixes, per sequence, the frames used for training and the held-out ones
(the last 20 % in time).

Flow encoding (the FlowNet's 3 output channels), from a flow f in pixels at resolution N:
  f_masked = f * cloud_mask            (the paper's I_cm: no flow on clear sky)
  ch0, ch1 = f_masked / |f_masked|     (cos, sin of the direction; (0, 0) where |f| < 1e-3 px)
  ch2      = min(|f_masked| / (FLOW_SCALE * N), 1)
FLOW_SCALE = 0.08: a full-scale magnitude is 8 % of the image width per step (5.1 px at 64 px);
ARM TSI clouds move a median 1.4 px (99th percentile 4.2 px) per 30 s at 64 px.
"""
import json
import os

import numpy as np

FLOW_SCALE = 0.08


def encode_flow(flow, cloud):
    """flow (..., N, N, 2) pixels, cloud (..., N, N) 0/1 -> (..., N, N, 3) encoded target."""
    n = flow.shape[-2]
    f = flow * cloud[..., None].astype(np.float32)
    mag = np.sqrt((f ** 2).sum(-1))
    safe = np.maximum(mag, 1e-3)
    direction = np.where((mag > 1e-3)[..., None], f / safe[..., None], 0.0)
    m = np.minimum(mag / (FLOW_SCALE * n), 1.0)
    return np.concatenate([direction, m[..., None]], axis=-1).astype(np.float32)


def decode_flow(encoded):
    """(..., N, N, 3) -> (..., N, N, 2) in pixels at N."""
    n = encoded.shape[-2]
    d = encoded[..., 0:2]
    norm = np.maximum(np.sqrt((d ** 2).sum(-1, keepdims=True)), 1e-6)
    return d / norm * (encoded[..., 2:3] * FLOW_SCALE * n)


class Sequence:
    def __init__(self, folder, load_exact=True):
        self.name = os.path.basename(os.path.normpath(folder))
        self.folder = folder
        with open(os.path.join(folder, "meta.json")) as f:
            self.meta = json.load(f)
        self.images = np.load(os.path.join(folder, "images.npy"))
        self.valid = np.load(os.path.join(folder, "valid.npy"))
        self.cloud = np.load(os.path.join(folder, "cloud.npy"))
        self.flow = np.load(os.path.join(folder, "flow_farneback.npy"))
        exact = os.path.join(folder, "flow_exact.npy")
        self.flow_exact = np.load(exact) if load_exact and os.path.exists(exact) else None
        self.flow_target = encode_flow(self.flow, self.cloud[:-1])
        self.disc = disc_mask(self.images.shape[1])

    @property
    def resolution(self):
        return self.images.shape[1]

    def __len__(self):
        return self.images.shape[0]


def disc_mask(n):
    c = (np.arange(n) + 0.5) * 2.0 / n - 1.0
    return (c[None, :] ** 2 + c[:, None] ** 2) <= 1.0


def load_split(dataset_dir):
    with open(os.path.join(dataset_dir, "split.json")) as f:
        return json.load(f)


def resize_sequence(seq, n):
    """Area-downscales a loaded sequence to n (for trying 64 px models on a 128 px dataset)."""
    import torch
    import torch.nn.functional as F
    if seq.resolution == n:
        return seq
    k = seq.resolution // n
    assert k * n == seq.resolution, "resolution must divide the dataset's"

    def pool(a, channels_last=True):
        t = torch.from_numpy(np.ascontiguousarray(a)).float()
        if channels_last:
            t = t.permute(0, 3, 1, 2)
        else:
            t = t[:, None]
        t = F.avg_pool2d(t, k)
        return (t.permute(0, 2, 3, 1) if channels_last else t[:, 0]).numpy()

    seq.images = pool(seq.images)
    # A coarse pixel is valid only if all its fine pixels were (no fake sky leaks into losses).
    seq.valid = (pool(seq.valid.astype(np.float32), False) > 0.999).astype(np.uint8)
    seq.cloud = (pool(seq.cloud.astype(np.float32), False) > 0.5).astype(np.uint8)
    seq.flow = pool(seq.flow) / k
    if seq.flow_exact is not None:
        seq.flow_exact = pool(seq.flow_exact) / k
    seq.flow_target = encode_flow(seq.flow, seq.cloud[:-1])
    seq.disc = disc_mask(n)
    seq.images = seq.images * seq.disc[None, :, :, None]
    return seq
