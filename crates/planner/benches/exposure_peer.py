#!/usr/bin/env python3
"""NumPy peer of the planner's exposure model (seed 000 eq. 1-5, closed form per wire segment,
causal cut point), for `cargo bench -p cell_planner --bench exposure`.

A straightforward vectorised implementation on N x M arrays (N surface panels, M wire
segments), written from the model description in src/exposure.rs, independently of the Rust
code. Usage: python3 exposure_peer.py INPUT.json  -> prints one JSON object on stdout:
{"numpy": version, "results": [{"law", "causal", "us_per_eval", "values"}...]}.

INPUT.json: {"surface": [[x, y]...] (closed polygon, no repeated end point),
             "wire": [[x, y]...] (open polyline), "min_distance_mm": 0.05,
             "window": 0.25, "settings": [["paper"|"author_code", "cut_point"|"off"]...],
             "min_seconds": 0.5}
Requires numpy (pip install numpy).
"""
import json
import sys
import time

import numpy as np


def panels(pts):
    a = pts
    b = np.roll(pts, -1, axis=0)
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    mid = 0.5 * (a + b)
    t = d / length[:, None]
    u = (np.cumsum(length) - 0.5 * length) / length.sum()
    return mid, t, u


def exposure(mid, t, u, wire, law, causal, dmin, window):
    a = wire[:-1]
    d = wire[1:] - a
    seg = np.hypot(d[:, 0], d[:, 1])
    safe = np.where(seg > 0, seg, 1.0)
    wx = np.where(seg > 0, d[:, 0] / safe, 0.0)
    wy = np.where(seg > 0, d[:, 1] / safe, 0.0)
    s0 = np.concatenate(([0.0], np.cumsum(seg)[:-1]))
    total = seg.sum()
    tx = t[:, 0:1]
    ty = t[:, 1:2]
    # eq. 1: R = r_w - r_s at each segment start (N x M)
    rx = a[None, :, 0] - mid[:, 0:1]
    ry = a[None, :, 1] - mid[:, 1:2]
    x0 = rx * wx + ry * wy  # position of the segment start along its line, from the foot
    # eq. 2: C(sigma) = c0 + sigma * c1
    c0 = tx * ry - ty * rx
    c1 = tx * wy - ty * wx
    with np.errstate(divide="ignore", invalid="ignore"):
        root = -c0 / c1
    lo = np.where(c1 < 0, np.maximum(root, 0.0), 0.0)
    hi = np.where(c1 > 0, np.minimum(root, seg), seg)
    visible = ~((c1 == 0) & (c0 > 0))  # eq. 3 when C is constant
    if causal == "cut_point":
        # nearest wire point within +-window of normalised arc length (first one on ties)
        wlo = np.maximum(u - window, 0.0)[:, None] * total
        whi = np.minimum(u + window, 1.0)[:, None] * total
        p = np.maximum(wlo - s0, 0.0)
        q = np.minimum(whi - s0, seg)
        inside = p <= q
        sigma = np.minimum(np.maximum(-x0, p), q)
        dx = rx + sigma * wx
        dy = ry + sigma * wy
        d2 = np.where(inside, dx * dx + dy * dy, np.inf)
        jc = np.argmin(d2, axis=1)
        rows = np.arange(len(u))
        cut = s0[jc] + sigma[rows, jc]
        hi = np.minimum(hi, cut[:, None] - s0)
    weight = np.abs(tx * wx + ty * wy)  # eq. 4, unit tangents
    ok = visible & (hi > lo) & (weight > 0) & (seg > 0)
    dist = np.maximum(np.abs(rx * wy - ry * wx), dmin)
    d2 = dist * dist
    xl = x0 + lo
    xh = x0 + hi
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if law == "paper":  # integral of 1/|R| = asinh difference, cancellation-free
            rl = np.sqrt(xl * xl + d2)
            rh = np.sqrt(xh * xh + d2)
            gl = np.where(xl >= 0, xl + rl, d2 / (rl - xl))
            gh = np.where(xh >= 0, xh + rh, d2 / (rh - xh))
            v = np.log(gh / gl)
        else:  # integral of 1/|R|^2
            v = np.arctan2(dist * (xh - xl), d2 + xl * xh) / dist
    return np.where(ok, weight * v, 0.0).sum(axis=1)  # eq. 5


def main():
    spec = json.load(open(sys.argv[1]))
    surface = np.array(spec["surface"], dtype=float)
    wire = np.array(spec["wire"], dtype=float)
    mid, t, u = panels(surface)
    results = []
    for law, causal in spec["settings"]:
        args = (mid, t, u, wire, law, causal, spec["min_distance_mm"], spec["window"])
        values = exposure(*args)
        # best of 5 batches, each at least min_seconds / 5 long
        batch = 1
        while True:
            start = time.perf_counter()
            for _ in range(batch):
                exposure(*args)
            if time.perf_counter() - start > spec.get("min_seconds", 0.5) / 5:
                break
            batch *= 2
        best = float("inf")
        for _ in range(5):
            start = time.perf_counter()
            for _ in range(batch):
                exposure(*args)
            best = min(best, (time.perf_counter() - start) / batch)
        results.append(
            {
                "law": law,
                "causal": causal,
                "us_per_eval": best * 1e6,
                "values": values.tolist(),
            }
        )
    print(json.dumps({"numpy": np.__version__, "results": results}))


if __name__ == "__main__":
    main()
