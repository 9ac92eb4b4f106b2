"""The advection-residual cloud model ("advect-residual", docs/networks-advect-residual.md).

Motion comes from a GIVEN flow F, never from memory; a small network only corrects.
One step, at network resolution N, on images I in the [0, 1] network form (0 outside the disc):

  E(I)   rim extension: for each pixel centre u = 2(i + 0.5)/N - 1, v = 2(j + 0.5)/N - 1,
         r = hypot(u, v); if r > r_in = 1 - 1.5/N scale (u, v) by r_in / r; sample I bilinearly
         at x = (u + 1)N/2 - 0.5, y = (v + 1)N/2 - 0.5 (border replicate). Fills the corners with
         the rim's values so warps never pull in black.
  W      = E(I)(x - F(x)), bilinear, border replicate, then 0 outside the disc (outside ONNX:
         OpenCV 4.6 cannot run GridSample; cv::remap INTER_LINEAR + BORDER_REPLICATE on pixel
         centres equals grid_sample(align_corners=True, padding_mode="border")).
  X      = [W (3), I (3), F / (0.08 N) (2)]   (1 x 8 x N x N, the ONNX input)
  next   = net(X) (1 x 3 x N x N, before clamping; the caller clamps to [0, 1] and zeros outside
         the disc)
F (N x N x 2, pixels at N per step, +x right, +y down) is the displacement content undergoes over
one step. A rollout keeps F fixed and feeds each prediction back as I.

Inside the network: next = B + bound * tanh(change), where B is W itself (kernel = 0) or W moved
by per-pixel softmax weights over its k x k neighbours (kernel = 3 or 5). Both start at B = W,
change = 0 (pure advection): the untrained model is the advection baseline.
"""
import math

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as Fn

import unet as U

FLOW_SCALE = 0.08
UNIT_SCALE = 1.0
UNIT_MAX = 300.0
SATURATED = 0.999


# ---------------------------------------------------------------- geometry

def pixel_centres(n):
    return (np.arange(n, dtype=np.float64) + 0.5) * 2.0 / n - 1.0


def disc_mask(n):
    c = pixel_centres(n)
    return (c[None, :] ** 2 + c[:, None] ** 2) <= 1.0


def rim_extension_coords(n):
    """(N, N, 2) pixel coordinates (x, y) that E samples for every output pixel."""
    c = pixel_centres(n)
    u, v = np.meshgrid(c, c)  # u varies along columns (x), v along rows (y)
    r = np.hypot(u, v)
    r_in = 1.0 - 1.5 / n
    s = np.where(r > r_in, r_in / np.maximum(r, 1e-12), 1.0)
    u, v = u * s, v * s
    return np.stack([(u + 1) * n / 2 - 0.5, (v + 1) * n / 2 - 0.5], -1)


def to_grid(coords, n):
    """pixel coordinates (..., 2) -> grid_sample's normalised coordinates (align_corners=True)."""
    return coords * (2.0 / (n - 1)) - 1.0


_cache = {}


def _rim_grid(n, device):
    key = ("rim", n, str(device))
    if key not in _cache:
        _cache[key] = torch.from_numpy(to_grid(rim_extension_coords(n), n).astype(np.float32))[None].to(device)
    return _cache[key]


def _base_coords(n, device):
    key = ("base", n, str(device))
    if key not in _cache:
        jj, ii = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        _cache[key] = torch.from_numpy(np.stack([ii, jj], -1).astype(np.float32))[None].to(device)
    return _cache[key]


def _disc_t(n, device):
    key = ("disc", n, str(device))
    if key not in _cache:
        _cache[key] = torch.from_numpy(disc_mask(n).astype(np.float32))[None, None].to(device)
    return _cache[key]


def rim_extend(img):
    """img (B, C, N, N) -> E(img)."""
    b, _, n, _ = img.shape
    g = _rim_grid(n, img.device).expand(b, n, n, 2)
    return Fn.grid_sample(img, g, mode="bilinear", padding_mode="border", align_corners=True)


def sample(img, coords, padding="border"):
    """Bilinear sample of img (B, C, N, N) at pixel coordinates (B, N, N, 2) (x, y)."""
    n = img.shape[-1]
    return Fn.grid_sample(img, to_grid(coords, n), mode="bilinear", padding_mode=padding, align_corners=True)


def warp(img, flow):
    """W = E(img)(x - F(x)), 0 outside the disc. img (B, 3, N, N), flow (B, 2, N, N) pixels."""
    n = img.shape[-1]
    coords = _base_coords(n, img.device) - flow.permute(0, 2, 3, 1)
    return sample(rim_extend(img), coords, "border") * _disc_t(n, img.device)


def advect_by_flow(img, flow, steps):
    """The Farneback-extrapolation baseline, exactly sky/sky_metrics.cpp advect_by_flow:
    out(x) = img(x - steps F(x)), bilinear, 0 outside the image (cv::BORDER_CONSTANT 0)."""
    n = img.shape[-1]
    coords = _base_coords(n, img.device) - steps * flow.permute(0, 2, 3, 1)
    return sample(img, coords, "zeros")


def compensation(background, flow):
    """B - warp(B): what the clear background (the sky under the clouds, C++ motion/network_form.h
    clear_background) loses when warped. Added to the warp, only the clouds move: W = warp(I) + B -
    warp(B). background (B, 3, N, N) or None."""
    if background is None:
        return None
    return (background - warp(background, flow)) * _disc_t(background.shape[-1], background.device)


def smooth_motion(flow, trusted=None):
    """The C++ motion/flow.h smooth_motion: the previous-frame flow Gaussian-smoothed, sigma N / 32,
    replicate borders. trusted (B, 1, N, N), 1 where the flow measures the sky (seen and unclipped in
    both frames): the average over those pixels only (normalised convolution), the rest filled from
    them (a 4x wider reach where none is near)."""
    sigma = flow.shape[-1] / 32.0
    if trusted is None:
        return gaussian_blur(flow, sigma)
    num, den = gaussian_blur(flow * trusted, sigma), gaussian_blur(trusted, sigma)
    wide_num, wide_den = gaussian_blur(flow * trusted, 4 * sigma), gaussian_blur(trusted, 4 * sigma)
    wide = torch.where(wide_den > 1e-6, wide_num / wide_den.clamp_min(1e-6), torch.zeros_like(wide_num))
    return torch.where(den > 1e-3, num / den.clamp_min(1e-3), wide)


def trusted_flow_pixels(valid_a, valid_b, img_a, img_b):
    """(B, 1, N, N): seen in both frames (valid, B x 1 x N x N) and clipped in neither."""
    return valid_a * valid_b * (1 - saturated(img_a)) * (1 - saturated(img_b))


def network_input(img, flow, comp=None):
    n = img.shape[-1]
    w = warp(img, flow)
    if comp is not None:
        w = w + comp
    return torch.cat([w, img, flow / (FLOW_SCALE * n)], 1)


# ---------------------------------------------------------------- uniform wind

def wind_flow(n, w, theta_max_deg=88.0):
    """Flow (B, 2, N, N) in pixels at N of a uniform wind on one cloud layer seen in the equidistant
    fisheye (r = zenith angle / 90 deg): w (B, 2) is the layer's displacement per step in units of
    its height, in image axes (+x right, +y down). F(x) = x - source(x): the content at pixel x came
    from the ground point P(x) - w. Outside theta_max the layer is treated as at theta_max's
    distance (the motion there is ~0 anyway)."""
    w = torch.as_tensor(w, dtype=torch.float32)
    c = torch.from_numpy(pixel_centres(n).astype(np.float32))
    v, u = torch.meshgrid(c, c, indexing="ij")
    r = torch.sqrt(u * u + v * v).clamp(min=1e-6)
    theta = (r * math.pi / 2).clamp(max=math.radians(theta_max_deg))
    rho = torch.tan(theta)
    px, py = rho * u / r, rho * v / r
    sx = px[None] - w[:, 0, None, None]
    sy = py[None] - w[:, 1, None, None]
    rs = torch.sqrt(sx * sx + sy * sy).clamp(min=1e-9)
    r_src = torch.atan(rs) / (math.pi / 2)
    us, vs = r_src * sx / rs, r_src * sy / rs
    # Where theta was clamped, keep the same relative shift (tiny) rather than a jump.
    fx = (u[None] - us) * n / 2
    fy = (v[None] - vs) * n / 2
    inside = (r * math.pi / 2 <= math.radians(theta_max_deg)).float()[None]
    return torch.stack([fx * inside, fy * inside], 1)


def fit_uniform_wind(flow, weight, n):
    """Least-squares uniform wind w (B, 2) for measured flows (B, 2, N, N) with pixel weights
    (B, 1, N, N), by the small-displacement Jacobian of wind_flow; returns (w, fitted flow)."""
    eps = 1e-3
    jx = wind_flow(n, [[eps, 0.0]])[0] / eps  # (2, N, N): flow per unit wind x
    jy = wind_flow(n, [[0.0, eps]])[0] / eps
    a11 = (weight[:, 0] * (jx * jx).sum(0)).sum((1, 2))
    a12 = (weight[:, 0] * (jx * jy).sum(0)).sum((1, 2))
    a22 = (weight[:, 0] * (jy * jy).sum(0)).sum((1, 2))
    b1 = (weight[:, 0] * (jx[None] * flow).sum(1)).sum((1, 2))
    b2 = (weight[:, 0] * (jy[None] * flow).sum(1)).sum((1, 2))
    det = (a11 * a22 - a12 * a12).clamp(min=1e-12)
    w = torch.stack([(a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det], 1)
    return w, wind_flow(n, w)


# ---------------------------------------------------------------- rotation / mirroring

def rotate(img, angle, mode="bilinear", extend=True):
    """Rotates images (B, C, N, N) about the zenith (the disc centre) by angle (B,) radians:
    out(p) = img(R^-1 p). With extend, the rim extension fills the corners first (then the caller
    masks the disc)."""
    b, _, n, _ = img.shape
    ca, sa = torch.cos(angle)[:, None, None], torch.sin(angle)[:, None, None]
    base = _base_coords(n, img.device)[0]
    cx = (n - 1) / 2.0
    px, py = base[..., 0] - cx, base[..., 1] - cx
    qx = ca * px + sa * py + cx  # R^-1 p
    qy = -sa * px + ca * py + cx
    src = rim_extend(img) if extend else img
    coords = torch.stack([qx, qy], -1)
    return Fn.grid_sample(src, to_grid(coords, n), mode=mode, padding_mode="border", align_corners=True)


def rotate_flow(flow, angle):
    """F'(p) = R F(R^-1 p)."""
    f = rotate(flow, angle, extend=False)
    ca, sa = torch.cos(angle)[:, None, None], torch.sin(angle)[:, None, None]
    return torch.stack([ca * f[:, 0] - sa * f[:, 1], sa * f[:, 0] + ca * f[:, 1]], 1)


def mirror(img):
    return torch.flip(img, [-1])


def mirror_flow(flow):
    f = torch.flip(flow, [-1])
    return torch.stack([-f[:, 0], f[:, 1]], 1)


# ---------------------------------------------------------------- HDR helpers

def unit_to_hdr(v):
    return UNIT_SCALE * (torch.exp(v * math.log1p(UNIT_MAX / UNIT_SCALE)) - 1.0)


def hdr_to_unit(L):
    return torch.log1p(L.clamp(min=0) / UNIT_SCALE) / math.log1p(UNIT_MAX / UNIT_SCALE)


def exposure_jitter(img, gains):
    """img (B, 3, N, N) in [0, 1], gains (B, 3) per-channel factors applied to the radiance."""
    return hdr_to_unit(unit_to_hdr(img) * gains[:, :, None, None]).clamp(0, 1)


def saturated(img):
    """(B, 1, N, N) 1 where any channel >= 0.999 (the sun: the C++ side removes it before stepping)."""
    return (img >= SATURATED).any(1, keepdim=True).float()


def fill_saturated(img, iterations=8):
    """Fills saturated pixels from their surroundings (normalised 3x3 diffusion), as the C++ side
    fills the sun before a step."""
    m = saturated(img)
    if float(m.sum()) == 0:
        return img
    keep = 1 - m
    out = img * keep
    k = torch.ones(1, 1, 3, 3, dtype=img.dtype, device=img.device)
    known = keep
    for _ in range(iterations * 4):
        s = Fn.conv2d(out.reshape(-1, 1, *img.shape[-2:]), k, padding=1).reshape(img.shape)
        c = Fn.conv2d(known, k, padding=1)
        fillv = s / c.clamp(min=1e-6)
        newly = (c > 0).float() * (1 - known)
        out = out * known + fillv * newly
        known = ((known + newly) > 0).float()
        if float((1 - known).sum()) == 0:
            break
    return out


def srgb(x):
    x = x.clamp(0, 1)
    return torch.where(x <= 0.0031308, 12.92 * x, 1.055 * x.clamp(min=1e-9) ** (1 / 2.4) - 0.055)


def cloud_cover(img, mask, threshold=0.75):
    """Cover by the red/blue > 0.75 rule on camera-encoded values (sky/cloud_mask.h
    encode_sky_for_mask re-done at N: radiance from the [0, 1] form, exposed so the disc's 99th
    percentile luminance maps to 1, clamped, sRGB), over mask pixels. img (B, 3, N, N)."""
    L = unit_to_hdr(img)
    lum = 0.2126 * L[:, 0] + 0.7152 * L[:, 1] + 0.0722 * L[:, 2]
    out = []
    for b in range(img.shape[0]):
        m = mask[b, 0] > 0
        p99 = torch.quantile(lum[b][m], 0.99) if m.any() else torch.tensor(1.0)
        e = srgb(L[b] / p99.clamp(min=1e-9))
        ratio = e[0] / e[2].clamp(min=1e-9)
        cl = ((ratio > threshold) & m).float()
        out.append(float(cl.sum() / m.float().sum().clamp(min=1)))
    return out


def cloud_mask_rb(img, mask, threshold=0.75):
    L = unit_to_hdr(img)
    lum = 0.2126 * L[:, 0] + 0.7152 * L[:, 1] + 0.0722 * L[:, 2]
    outs = []
    for b in range(img.shape[0]):
        m = mask[b, 0] > 0
        p99 = torch.quantile(lum[b][m], 0.99)
        e = srgb(L[b] / p99.clamp(min=1e-9))
        outs.append(((e[0] / e[2].clamp(min=1e-9)) > threshold) & m)
    return torch.stack(outs)[:, None].float()


def gaussian_blur(img, sigma=2.0):
    r = int(math.ceil(3 * sigma))
    x = torch.arange(-r, r + 1, dtype=torch.float32)
    k = torch.exp(-x * x / (2 * sigma * sigma))
    k = k / k.sum()
    c = img.shape[1]
    p = Fn.pad(img, (r, r, r, r), mode="replicate")
    p = Fn.conv2d(p, k.view(1, 1, 1, -1).repeat(c, 1, 1, 1), groups=c)
    return Fn.conv2d(p, k.view(1, 1, -1, 1).repeat(c, 1, 1, 1), groups=c)


def hf_energy(img, mask, sigma=2.0):
    """Mean squared difference to a sigma-2 px Gaussian blur over mask pixels (per image). The blur
    is normalised inside the sky disc (G * (I d) / G * d), so the black outside the disc does not
    count as detail at the rim."""
    d = _disc_t(img.shape[-1], img.device)
    blur = gaussian_blur(img * d, sigma) / gaussian_blur(d, sigma).clamp(min=1e-6)
    d = ((img - blur) ** 2).mean(1, keepdim=True)
    return ((d * mask).sum((1, 2, 3)) / mask.sum((1, 2, 3)).clamp(min=1)).tolist()


# ---------------------------------------------------------------- the network

class KernelBlend(nn.Module):
    """out(x) = sum_j w_j(x) W(x + o_j), w = softmax over the k x k offsets of 6 tanh(logit / 6)
    (bounded logits). Conv (fixed one-hot shift kernels), Tanh, Mul, Exp, Div: OpenCV-runnable."""

    def __init__(self, k):
        super().__init__()
        self.k = k
        shifts = torch.zeros(k * k, 1, k, k)
        for j in range(k * k):
            shifts[j, 0, j // k, j % k] = 1.0
        self.register_buffer("shifts", shifts)
        self.register_buffer("ones", torch.ones(1, k * k, 1, 1))

    def forward(self, image, logits):
        e = torch.exp(6.0 * torch.tanh(logits * (1.0 / 6.0)))
        norm = Fn.conv2d(e, self.ones)
        out = []
        for c in range(image.shape[1]):
            nb = Fn.conv2d(image[:, c:c + 1], self.shifts, padding=self.k // 2)
            out.append(Fn.conv2d(nb * e, self.ones) / norm)
        return torch.cat(out, 1)


class AdvectResidual(nn.Module):
    """X (B, 8, N, N) = [W, I, F / (0.08 N)] -> next (B, 3, N, N) before clamping.

    kernel = 0:  next = W + bound tanh(c)
    kernel = k:  next = sum_j softmax_j W(x + o_j) (k x k neighbours) + bound tanh(c)
    gate:        next = (1 - a) W + a I + bound tanh(c), a = sigmoid(g) per pixel: the net can hold
                 a pixel still (a = 1: persistence, e.g. clear sky under a wind) or let it move
                 (a = 0: advection); (1 - a) is computed as sigmoid(-g) (ONNX: Mul, Sigmoid, Add).
    """

    def __init__(self, widths=(16, 32, 64, 64), kernel=0, bound=0.1, centre_logit=4.0, gate=False, gate_logit=-4.0):
        super().__init__()
        self.widths = tuple(widths)
        self.kernel = int(kernel)
        self.bound = float(bound)
        self.gate = bool(gate)
        kk = self.kernel * self.kernel
        ng = 1 if self.gate else 0
        self.unet = U.UNet(8, kk + ng + 3, self.widths)
        with torch.no_grad():  # start as (nearly) pure advection: change 0, kernel ~ centre tap, gate ~ 0
            self.unet.head.weight.zero_()
            self.unet.head.bias.zero_()
            self.unet.pos_out.weight.zero_()
            if kk:
                self.unet.head.bias[kk // 2] = centre_logit
            if ng:
                self.unet.head.bias[kk] = gate_logit
        if kk:
            self.blend = KernelBlend(self.kernel)

    def forward(self, x):
        y = self.unet(x)
        w = x[:, 0:3]
        kk = self.kernel * self.kernel
        base = self.blend(w, y[:, 0:kk]) if kk else w
        c0 = kk
        if self.gate:
            g = y[:, kk:kk + 1]
            base = torch.sigmoid(g * -1.0) * base + torch.sigmoid(g) * x[:, 3:6]  # Mul, not Neg (OpenCV 4.6)
            c0 = kk + 1
        return base + self.bound * torch.tanh(y[:, c0:c0 + 3])


def step(model, img, flow, comp=None):
    """One full step as the C++ side runs it: warp (+ background compensation), network, clamp, zero
    outside the disc."""
    n = img.shape[-1]
    return model(network_input(img, flow, comp)).clamp(0, 1) * _disc_t(n, img.device)


def macs(model, n):
    total = [0]

    def hook(mod, inp, out):
        total[0] += out.numel() * mod.kernel_size[0] * mod.kernel_size[1] * mod.in_channels // mod.groups

    hs = [m.register_forward_hook(hook) for m in model.modules() if isinstance(m, nn.Conv2d)]
    with torch.no_grad():
        model(torch.zeros(1, 8, n, n))
    for h in hs:
        h.remove()
    return total[0]
