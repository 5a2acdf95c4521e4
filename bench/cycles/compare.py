#!/usr/bin/python3
"""Compares two linear EXR renders of the same scene pixel by pixel.

Usage: compare.py A.exr B.exr [--a-err A.stderr.exr] [--b-err B.stderr.exr] [--a-n N] [--b-n N]
                  [--alpha 0.01]

Prints one JSON object: the relative RMSE ||a - b|| / ||b|| over the pixels either covers, each
image's noise (the relative norm of its per-pixel standard error, when given), the noise expected of
the difference, and a per-pixel Z-test (as Mitsuba's: z = (a - b) / sqrt(se_a^2 + se_b^2) per pixel
and channel, two-sided, Sidak-corrected for the number of values tested at significance `alpha`)
with the fraction of pixels that pass. A standard error estimated from few independent values
(--b-n: Cycles' runs) makes z heavy-tailed: with --a-n / --b-n (the samples behind each standard
error) each value's critical point is Student's t at its Welch-Satterthwaite degrees of freedom. Needs numpy and OpenImageIO's Python module (Debian:
python3-numpy, python3-openimageio).
"""
import argparse
import json
import math
import sys

import numpy as np
import OpenImageIO as oiio


def read(path):
    img = oiio.ImageInput.open(path)
    if img is None:
        sys.exit(f"compare: cannot read {path}: {oiio.geterror()}")
    px = img.read_image(format="float")
    img.close()
    return np.asarray(px, dtype=np.float64)[:, :, :3]


def z_critical(p_two_sided):
    """The z with P(|Z| > z) = p, by bisection on erfc (no scipy)."""
    lo, hi = 0.0, 40.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if math.erfc(mid / math.sqrt(2)) > p_two_sided:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def t_critical(p_two_sided, nu):
    """The t with P(|T| > t) = p for Student's t with nu degrees of freedom (numerically)."""
    if nu > 1e5:
        return z_critical(p_two_sided)
    c = math.exp(math.lgamma((nu + 1) / 2) - math.lgamma(nu / 2)) / math.sqrt(nu * math.pi)
    u = np.linspace(1e-6, 1.0, 20001)

    def tail2(t):  # 2 * int_t^inf f(x) dx with x = t / u
        x = t / u
        f = c * (1 + x * x / nu) ** (-(nu + 1) / 2) * t / (u * u)
        return 2 * np.trapz(f, u)

    lo, hi = 0.0, 1e3
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if tail2(mid) > p_two_sided:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--a-err")
    ap.add_argument("--b-err")
    ap.add_argument("--a-n", type=float, default=math.inf)
    ap.add_argument("--b-n", type=float, default=math.inf)
    ap.add_argument("--alpha", type=float, default=0.01)
    args = ap.parse_args()
    a, b = read(args.a), read(args.b)
    if a.shape != b.shape:
        sys.exit(f"compare: sizes differ: {a.shape} and {b.shape}")
    covered = (a.max(axis=2) > 0) | (b.max(axis=2) > 0)
    out = {"pixels": int(covered.sum())}
    diff = (a - b)[covered]
    out["rrmse"] = float(np.linalg.norm(diff) / np.linalg.norm(b[covered]))
    out["mean_ratio"] = float(a[covered].sum() / b[covered].sum())
    var = np.zeros_like(a)
    welch = np.zeros_like(a)  # sum of var^2 / (n - 1): Welch-Satterthwaite's denominator
    for name, err, img, n in (("a", args.a_err, a, args.a_n), ("b", args.b_err, b, args.b_n)):
        if err:
            e = read(err)
            out[f"noise_{name}"] = float(np.linalg.norm(e[covered]) / np.linalg.norm(img[covered]))
            var += e * e
            if math.isfinite(n):
                welch += (e * e) ** 2 / (n - 1)
    if args.a_err or args.b_err:
        out["noise_expected"] = float(np.sqrt(var[covered].sum()) / np.linalg.norm(b[covered]))
        tested = var[covered] > 0
        n = int(tested.sum())
        # Sidak: each of the n values at 1 - (1 - alpha)^(1/n), so all pass with probability 1 - alpha.
        per_value = -math.expm1(math.log1p(-args.alpha) / max(n, 1))
        zc = z_critical(per_value)
        z = np.zeros(diff.shape)
        z[tested] = np.abs(diff[tested]) / np.sqrt(var[covered][tested])
        crit = np.full(diff.shape, zc)
        if welch.any():
            w = welch[covered]
            nu = np.where(w > 0, var[covered] ** 2 / np.maximum(w, 1e-300), np.inf)
            # Critical points on a grid of degrees of freedom, each value rounded down (safe side).
            grid = sorted(set(int(v) for v in np.geomspace(1, 1e5, 60)))
            table = {g: t_critical(per_value, g) for g in grid}
            keys = np.array(grid)
            idx = np.searchsorted(keys, np.minimum(nu, 1e5), side="right") - 1
            crit = np.array([table[k] for k in keys])[np.clip(idx, 0, len(keys) - 1)]
            out["dof_median"] = float(np.median(nu[tested]))
        pixel_pass = (z < crit).all(axis=1)
        out["z_critical"] = zc
        out["z_pass"] = float(pixel_pass.mean())
        out["z_max"] = float(z.max())
    print(json.dumps(out))


if __name__ == "__main__":
    main()
