#!/usr/bin/env python3
"""NumPy peer of the planner's Swarm-Cut optimiser (seed 000 eq. 1-5 exposure, §IV.C PSO over a
periodic cubic B-spline of normal displacements), for the issue 21 benchmark
(`cargo bench -p cell_planner --bench optimise`).

Written from the problem statement and the model description in src/exposure.rs (module docs)
and src/trajectory.rs (`periodic_cubic_bspline`), independently of the Rust optimiser. Plain
vectorised NumPy: the exposure of one candidate path is computed on N x M arrays (N surface
panels, M wire segments); particles are evaluated one after another.

Usage:
    python3 pso_peer.py PROBLEM.json [--iterations N] [--seed S]   -> one JSON object on stdout
    python3 pso_peer.py --self-test                                 -> exit 0 when all checks pass

PROBLEM.json (lengths in mm):
  surface   [[x, y]...]  closed polygon of N panel corner points, anticlockwise, point 0 the
                         one nearest the wire's entry, no repeated end point
  loop      [[x, y]...]  the baseline wire loop, closed (last point repeats the first), starting
                         at the entry
  normals   [[nx, ny]...] outward unit normal at each loop point (same length as loop)
  arc_u     [...]        normalised arc length of each loop point, 0 .. 1 (the spline parameter)
  lead_in   [[x, y]...]  polyline ending at loop[0] (may be empty); its last point follows the
                         displaced loop[0], the others stay
  outline   [[x, y]...]  the full-resolution foil polygon for the clearance test
  min_clearance_mm, min_distance_mm, window, law ("paper" | "author_code"),
  cse (null: the baseline's mean exposure), control_points, smoothing,
  pso {particles, iterations, restart_every, inertia, cognitive, social,
       initial_velocity_mm, restart_velocity_mm, seed}

Output: {"numpy", "iterations", "seconds", "seconds_per_iteration", "evaluations",
         "baseline": STATS, "optimised": STATS, "cse", "controls", "history": [[it, loss]...]}
with STATS = {"loss", "cv", "rms", "p95_abs_dev", "max_abs_dev", "min", "mean",
              "clearance_mm"}: cv = population std / mean of E over the panels, rms =
sqrt(mean (E - CSE)^2), p95_abs_dev = 95th percentile of |E - CSE| (NumPy's default linear
interpolation), clearance_mm = least distance of the loop and lead-in from the outline.
"seconds" is the wall time of the swarm alone (reading the file and the statistics excluded);
"history" holds iteration 0 (the baseline) and every iteration where the global best improved.

Requires numpy (requirements.txt).
"""

import argparse
import json
import math
import sys
import time

import numpy as np


def _keep_freed_memory():
    """Stop glibc returning the N x M temporaries (a few hundred kB each) to the kernel after
    every operation: the page faults of re-mapping them tripled the time per evaluation."""
    try:
        import ctypes

        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, 32 * 1024 * 1024)  # M_MMAP_THRESHOLD: its maximum on 64-bit
        libc.mallopt(-1, 1024 * 1024 * 1024)  # M_TRIM_THRESHOLD
    except (OSError, AttributeError):
        pass  # not glibc: only slower


# ----------------------------------------------------------------------------------------------
# Problem file


class ProblemError(Exception):
    """A problem file that cannot be used; the message names the file and the field."""


def _points(spec, source, name, min_len=0, closed=False):
    try:
        a = np.asarray(spec[name], dtype=float)
    except KeyError:
        raise ProblemError(f"{source}: field `{name}` is missing") from None
    except (TypeError, ValueError) as e:
        raise ProblemError(f"{source}: field `{name}` is not a list of [x, y] numbers: {e}")
    if a.size == 0:
        a = a.reshape(0, 2)
    if a.ndim != 2 or a.shape[1] != 2:
        raise ProblemError(f"{source}: field `{name}` is not a list of [x, y] pairs")
    if not np.all(np.isfinite(a)):
        i = int(np.argwhere(~np.isfinite(a))[0][0])
        raise ProblemError(f"{source}: {name}[{i}] is not finite")
    if len(a) < min_len:
        raise ProblemError(f"{source}: field `{name}` has {len(a)} points, needs {min_len}")
    if closed and np.any(a[0] != a[-1]):
        raise ProblemError(f"{source}: field `{name}` must be closed (last point = first)")
    return a


def _number(spec, source, name, lo=None, integer=False, allow_null=False, within=""):
    if name not in spec:
        raise ProblemError(f"{source}: field `{within}{name}` is missing")
    v = spec[name]
    name = within + name
    if v is None and allow_null:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ProblemError(f"{source}: field `{name}` = {v!r} is not a finite number")
    if integer and v != int(v):
        raise ProblemError(f"{source}: field `{name}` = {v!r} is not an integer")
    if lo is not None and v < lo:
        raise ProblemError(f"{source}: field `{name}` = {v!r} must be >= {lo}")
    return int(v) if integer else float(v)


def read_problem(path):
    try:
        with open(path) as f:
            spec = json.load(f)
    except OSError as e:
        raise ProblemError(f"{path}: cannot read: {e}") from None
    except json.JSONDecodeError as e:
        raise ProblemError(f"{path}: not JSON: {e}") from None
    if not isinstance(spec, dict):
        raise ProblemError(f"{path}: expected a JSON object")
    p = {
        "surface": _points(spec, path, "surface", 3),
        "loop": _points(spec, path, "loop", 4, closed=True),
        "normals": _points(spec, path, "normals"),
        "lead_in": _points(spec, path, "lead_in"),
        "outline": _points(spec, path, "outline", 3),
    }
    if len(p["normals"]) != len(p["loop"]):
        raise ProblemError(
            f"{path}: field `normals` has {len(p['normals'])} entries, `loop` {len(p['loop'])}"
        )
    try:
        p["arc_u"] = np.asarray(spec["arc_u"], dtype=float)
    except KeyError:
        raise ProblemError(f"{path}: field `arc_u` is missing") from None
    except (TypeError, ValueError) as e:
        raise ProblemError(f"{path}: field `arc_u` is not a list of numbers: {e}") from None
    if p["arc_u"].shape != (len(p["loop"]),) or not np.all(np.isfinite(p["arc_u"])):
        raise ProblemError(f"{path}: field `arc_u` must hold one finite number per loop point")
    for name in ("min_clearance_mm", "min_distance_mm", "window", "smoothing"):
        p[name] = _number(spec, path, name, lo=0.0)
    if p["min_distance_mm"] <= 0:
        raise ProblemError(f"{path}: field `min_distance_mm` must be > 0")
    p["cse"] = _number(spec, path, "cse", allow_null=True)
    p["control_points"] = _number(spec, path, "control_points", lo=4, integer=True)
    law = spec.get("law")
    if law not in ("paper", "author_code"):
        raise ProblemError(f'{path}: field `law` = {law!r} must be "paper" or "author_code"')
    p["law"] = law
    pso = spec.get("pso")
    if not isinstance(pso, dict):
        raise ProblemError(f"{path}: field `pso` is missing or not an object")

    def number(name, **kw):
        return _number(pso, path, name, within="pso.", **kw)

    p["pso"] = {
        "particles": number("particles", lo=1, integer=True),
        "iterations": number("iterations", lo=0, integer=True),
        "restart_every": number("restart_every", lo=0, integer=True),
        "inertia": number("inertia"),
        "cognitive": number("cognitive"),
        "social": number("social"),
        "initial_velocity_mm": number("initial_velocity_mm", lo=0.0),
        "restart_velocity_mm": number("restart_velocity_mm", lo=0.0),
        "seed": number("seed", lo=0, integer=True),
    }
    return p


# ----------------------------------------------------------------------------------------------
# Geometry


def bspline_basis(k, u):
    """Indices (M x 4) and weights (M x 4) of the periodic uniform cubic B-spline of k controls
    at the parameters u (trajectory.rs `periodic_cubic_bspline`): t = u*k, i = floor t, f = t - i,
    delta = B0 c[i-1] + B1 c[i] + B2 c[i+1] + B3 c[i+2] (indices mod k)."""
    t = np.mod(u, 1.0) * k
    i = np.minimum(np.floor(t).astype(int), k - 1)
    f = t - i
    w = np.stack(
        [
            (1 - f) ** 3 / 6,
            (3 * f**3 - 6 * f**2 + 4) / 6,
            (-3 * f**3 + 3 * f**2 + 3 * f + 1) / 6,
            f**3 / 6,
        ],
        axis=1,
    )
    idx = np.stack([(i - 1) % k, i, (i + 1) % k, (i + 2) % k], axis=1)
    return idx, w


def point_segment_distance(p, a, b):
    """Distance from points p to segments a-b (arrays of shape (..., 2), broadcast)."""
    d = b - a
    dd = np.einsum("...i,...i->...", d, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.einsum("...i,...i->...", p - a, d) / dd
    s = np.where(dd > 0, np.clip(s, 0.0, 1.0), 0.0)
    q = a + s[..., None] * d
    return np.hypot(p[..., 0] - q[..., 0], p[..., 1] - q[..., 1])


def segment_distance(a, b, c, d):
    """Distance between segments a-b and c-d (arrays (K, 2)); 0 where they cross or touch."""

    def cross(o, p, q):
        return (p[:, 0] - o[:, 0]) * (q[:, 1] - o[:, 1]) - (p[:, 1] - o[:, 1]) * (q[:, 0] - o[:, 0])

    crossing = (cross(c, d, a) * cross(c, d, b) < 0) & (cross(a, b, c) * cross(a, b, d) < 0)
    dist = np.minimum(
        np.minimum(point_segment_distance(a, c, d), point_segment_distance(b, c, d)),
        np.minimum(point_segment_distance(c, a, b), point_segment_distance(d, a, b)),
    )
    return np.where(crossing, 0.0, dist)


def inside_polygon(p, poly):
    """Even-odd test of the point p against the closed polygon poly (no repeated end point)."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    straddle = (a[:, 1] > p[1]) != (b[:, 1] > p[1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x = a[:, 0] + (p[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return bool(np.count_nonzero(straddle & (p[0] < x)) % 2)


# ----------------------------------------------------------------------------------------------
# Exposure (seed 000 eq. 1-5, closed form per straight wire segment)


def relative(mid, a):
    """eq. 1: R = r_w - r_s from each panel midpoint to each segment start (N x M, x and y)."""
    return a[None, :, 0] - mid[:, 0:1], a[None, :, 1] - mid[:, 1:2]


def segment_integrals(tx, ty, rx, ry, w, seg, hi_cap, law, dmin):
    """Per panel, the sum over wire segments of the integral of chi*|t.w|/|R|^p over the part of
    each segment that is visible (eq. 3) and below `hi_cap` (the causal cut, per panel x
    segment, measured from the segment start). tx, ty: panel unit tangents (N x 1); rx, ry:
    `relative`; w: unit directions (M, 2) (0 for zero-length segments); seg: lengths (M,)."""
    wx = w[None, :, 0]
    wy = w[None, :, 1]
    x0 = rx * wx + ry * wy  # position of the segment start along its line, from the foot
    c0 = tx * ry - ty * rx  # eq. 2: C(sigma) = c0 + sigma * c1
    c1 = tx * wy - ty * wx
    with np.errstate(divide="ignore", invalid="ignore"):
        root = -c0 / c1
    lo = np.where(c1 < 0, np.maximum(root, 0.0), 0.0)  # chi = 1 where C <= 0 (eq. 3)
    hi = np.where(c1 > 0, np.minimum(root, seg), seg)
    hi = np.minimum(hi, hi_cap)
    visible = ~((c1 == 0) & (c0 > 0))
    weight = np.abs(tx * wx + ty * wy)  # eq. 4 with unit tangents
    ok = visible & (hi > lo) & (weight > 0) & (seg > 0)
    dist = np.maximum(np.abs(rx * wy - ry * wx), dmin)
    d2 = dist * dist
    xl = x0 + lo
    xh = x0 + hi
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if law == "paper":  # integral of 1/|R|: asinh difference, free of cancellation
            rl = np.sqrt(xl * xl + d2)
            rh = np.sqrt(xh * xh + d2)
            gl = np.where(xl >= 0, xl + rl, d2 / (rl - xl))
            gh = np.where(xh >= 0, xh + rh, d2 / (rh - xh))
            v = np.log(gh / gl)
        else:  # integral of 1/|R|^2
            v = np.arctan2(dist * (xh - xl), d2 + xl * xh) / dist
    return np.where(ok, weight * v, 0.0).sum(axis=1)  # eq. 5


def segments_of(points):
    a = points[:-1]
    d = points[1:] - a
    seg = np.hypot(d[:, 0], d[:, 1])
    safe = np.where(seg > 0, seg, 1.0)
    w = np.where(seg[:, None] > 0, d / safe[:, None], 0.0)
    return a, w, seg


class Surface:
    """The N panels of the closed surface polygon: midpoints, unit tangents, and the normalised
    arc position of each midpoint from point 0."""

    def __init__(self, pts):
        b = np.roll(pts, -1, axis=0)
        d = b - pts
        length = np.hypot(d[:, 0], d[:, 1])
        if np.any(length == 0):
            raise ProblemError(f"surface: panel {int(np.argmin(length))} has zero length")
        self.mid = 0.5 * (pts + b)
        t = d / length[:, None]
        self.tx = t[:, 0:1]
        self.ty = t[:, 1:2]
        self.u = (np.cumsum(length) - 0.5 * length) / length.sum()


def exposure(surface, loop_pts, lead_pts, law, dmin, window, causal=True):
    """E_i of every panel for the wire lead_pts (all counted: the wire runs on the lead-in before
    it cuts anything) followed by the closed loop loop_pts (counted up to each panel's cut point:
    the nearest loop point to s_i within +-window of normalised loop arc length around u_i)."""
    n = len(surface.u)
    lead = len(lead_pts) - 1 if len(lead_pts) >= 2 else 0  # lead-in segments
    # One N x M array pass over the lead-in's segments followed by the loop's.
    wire = np.vstack([lead_pts[:-1], loop_pts]) if lead else loop_pts
    a, w, seg = segments_of(wire)
    rx, ry = relative(surface.mid, a)
    if causal:
        lseg = seg[lead:]
        lw = w[lead:]
        lrx = rx[:, lead:]
        lry = ry[:, lead:]
        s0 = np.concatenate(([0.0], np.cumsum(lseg)[:-1]))  # loop arc length at segment starts
        length = lseg.sum()
        x0 = lrx * lw[None, :, 0] + lry * lw[None, :, 1]
        wlo = np.maximum(surface.u - window, 0.0)[:, None] * length
        whi = np.minimum(surface.u + window, 1.0)[:, None] * length
        p = np.maximum(wlo - s0, 0.0)  # the part of each segment inside the window
        q = np.minimum(whi - s0, lseg)
        sigma = np.minimum(np.maximum(-x0, p), q)  # nearest point of that part to s_i
        dx = lrx + sigma * lw[None, :, 0]
        dy = lry + sigma * lw[None, :, 1]
        d2 = np.where(p <= q, dx * dx + dy * dy, np.inf)
        jc = np.argmin(d2, axis=1)  # first on ties
        cut = s0[jc] + sigma[np.arange(n), jc]
        # Lead-in segments start at -inf on this scale: never capped.
        cap = cut[:, None] - np.concatenate((np.full(lead, -np.inf), s0))[None, :]
    else:
        cap = np.inf
    return segment_integrals(surface.tx, surface.ty, rx, ry, w, seg, cap, law, dmin)


# ----------------------------------------------------------------------------------------------
# The optimisation problem


class Problem:
    def __init__(self, p):
        self.p = p
        self.surface = Surface(p["surface"])
        self.loop = p["loop"]
        self.normals = p["normals"]
        self.k = p["control_points"]
        self.idx, self.w = bspline_basis(self.k, p["arc_u"])
        self.lead = p["lead_in"]
        self.outline = p["outline"]
        self.out_a = self.outline
        self.out_b = np.roll(self.outline, -1, axis=0)
        # Clearance pruning: a loop point moves by delta(u) with |delta| <= max|c| = D (the basis
        # is non-negative and sums to 1), so every point of a loop segment moves by <= D and a
        # (loop segment, outline segment) pair can only come closer than the margin if its
        # baseline distance is below margin + D. Pairs sorted by baseline distance: a prefix.
        m = len(self.loop) - 1
        jj, qq = np.meshgrid(np.arange(m), np.arange(len(self.outline)), indexing="ij")
        jj, qq = jj.ravel(), qq.ravel()
        base = segment_distance(self.loop[jj], self.loop[jj + 1], self.out_a[qq], self.out_b[qq])
        order = np.argsort(base, kind="stable")
        self.pair_dist = base[order]
        self.pair_loop = jj[order]
        self.pair_outline = qq[order]
        self.baseline_exposure = self.exposure(np.zeros(self.k))
        self.cse = p["cse"] if p["cse"] is not None else float(self.baseline_exposure.mean())

    def displacement(self, c):
        return (self.w * c[self.idx]).sum(axis=1)

    def loop_points(self, c):
        pts = self.loop + self.displacement(c)[:, None] * self.normals
        pts[-1] = pts[0]
        return pts

    def lead_points(self, loop_pts):
        if len(self.lead) == 0:
            return self.lead
        lead = self.lead.copy()
        lead[-1] = loop_pts[0]
        return lead

    def exposure(self, c, causal=True):
        pts = self.loop_points(c)
        p = self.p
        return exposure(
            self.surface,
            pts,
            self.lead_points(pts),
            p["law"],
            p["min_distance_mm"],
            p["window"],
            causal,
        )

    def feasible(self, c, pts):
        margin = self.p["min_clearance_mm"]
        reach = np.searchsorted(self.pair_dist, margin + np.max(np.abs(c)), side="left")
        if reach:
            j = self.pair_loop[:reach]
            q = self.pair_outline[:reach]
            d = segment_distance(pts[j], pts[j + 1], self.out_a[q], self.out_b[q])
            if np.any(d < margin):
                return False
        lead = self.lead_points(pts)
        if len(lead) >= 2 and self.lead_clearance(lead) < margin:
            return False
        # A loop wholly inside the foil crosses nothing: test one point.
        return not inside_polygon(pts[0], self.outline)

    def lead_clearance(self, lead):
        n, q = len(lead) - 1, len(self.outline)
        j = np.repeat(np.arange(n), q)
        k = np.tile(np.arange(q), n)
        return float(segment_distance(lead[j], lead[j + 1], self.out_a[k], self.out_b[k]).min())

    def clearance(self, c):
        """Least distance of the loop and the lead-in from the outline (0 if they cross)."""
        pts = self.loop_points(c)
        m, q = len(pts) - 1, len(self.outline)
        j = np.repeat(np.arange(m), q)
        k = np.tile(np.arange(q), m)
        d = float(segment_distance(pts[j], pts[j + 1], self.out_a[k], self.out_b[k]).min())
        lead = self.lead_points(pts)
        if len(lead) >= 2:
            d = min(d, self.lead_clearance(lead))
        return 0.0 if inside_polygon(pts[0], self.outline) else d

    def smoothness(self, c):
        return float(np.sum((np.roll(c, -1) - c) ** 2))

    def loss(self, c):
        """L = mean_i (E_i - CSE)^2 + smoothing * sum_k (c_{k+1} - c_k)^2, +inf if infeasible."""
        pts = self.loop_points(c)
        if not self.feasible(c, pts):
            return math.inf
        e = exposure(
            self.surface,
            pts,
            self.lead_points(pts),
            self.p["law"],
            self.p["min_distance_mm"],
            self.p["window"],
        )
        return float(np.mean((e - self.cse) ** 2)) + self.p["smoothing"] * self.smoothness(c)

    def stats(self, c):
        e = self.exposure(c)
        dev = np.abs(e - self.cse)
        mean = float(e.mean())
        return {
            "loss": self.loss(c),
            "cv": float(e.std() / mean) if mean != 0 else math.inf,
            "rms": float(np.sqrt(np.mean(dev**2))),
            "p95_abs_dev": float(np.percentile(dev, 95)),
            "max_abs_dev": float(dev.max()),
            "min": float(e.min()),
            "mean": mean,
            "clearance_mm": self.clearance(c),
        }


# ----------------------------------------------------------------------------------------------
# PSO (seed 000 §IV.C)


def pso(problem, cfg, iterations, seed):
    """The paper's swarm: all particles start at c = 0 with velocities uniform in
    +-initial_velocity_mm; each iteration v <- w v + c1 r1 (pbest - x) + c2 r2 (gbest - x),
    x <- x + v (r1, r2 uniform in [0, 1) per particle and control), then every particle is
    evaluated and only then are the personal and global bests updated (synchronous). After
    every `restart_every` iterations all particles restart at gbest with velocities uniform in
    +-restart_velocity_mm and their personal bests reset to gbest."""
    rng = np.random.default_rng(seed)
    n, k = cfg["particles"], problem.k
    x = np.zeros((n, k))
    v = rng.uniform(-cfg["initial_velocity_mm"], cfg["initial_velocity_mm"], (n, k))
    base = problem.loss(np.zeros(k))
    pbest = x.copy()
    pbest_loss = np.full(n, base)
    gbest = np.zeros(k)
    gbest_loss = base
    history = [[0, base]]
    losses = np.empty(n)
    for it in range(1, iterations + 1):
        r1 = rng.random((n, k))
        r2 = rng.random((n, k))
        v = (
            cfg["inertia"] * v
            + cfg["cognitive"] * r1 * (pbest - x)
            + cfg["social"] * r2 * (gbest - x)
        )
        x = x + v
        for i in range(n):
            losses[i] = problem.loss(x[i])
        better = losses < pbest_loss
        pbest[better] = x[better]
        pbest_loss[better] = losses[better]
        best = int(np.argmin(pbest_loss))
        if pbest_loss[best] < gbest_loss:
            gbest = pbest[best].copy()
            gbest_loss = float(pbest_loss[best])
            history.append([it, gbest_loss])
        if cfg["restart_every"] and it % cfg["restart_every"] == 0 and it < iterations:
            x = np.tile(gbest, (n, 1))
            v = rng.uniform(-cfg["restart_velocity_mm"], cfg["restart_velocity_mm"], (n, k))
            pbest = x.copy()
            pbest_loss = np.full(n, gbest_loss)
    return gbest, gbest_loss, history


def run(path, iterations=None, seed=None):
    p = read_problem(path)
    problem = Problem(p)
    cfg = p["pso"]
    iterations = cfg["iterations"] if iterations is None else iterations
    seed = cfg["seed"] if seed is None else seed
    zero = np.zeros(problem.k)
    if not math.isfinite(problem.loss(zero)):
        raise ProblemError(
            f"{path}: the baseline (zero controls) is infeasible: clearance "
            f"{problem.clearance(zero):.4f} mm < min_clearance_mm {p['min_clearance_mm']}"
        )
    start = time.perf_counter()
    controls, _, history = pso(problem, cfg, iterations, seed)
    seconds = time.perf_counter() - start
    return {
        "numpy": np.__version__,
        "iterations": iterations,
        "seconds": seconds,
        "seconds_per_iteration": seconds / max(iterations, 1),
        "evaluations": iterations * cfg["particles"] + 1,
        "seed": seed,
        "panels": len(problem.surface.u),
        "loop_segments": len(problem.loop) - 1,
        "baseline": problem.stats(zero),
        "optimised": problem.stats(controls),
        "cse": problem.cse,
        "controls": controls.tolist(),
        "history": history,
    }


# ----------------------------------------------------------------------------------------------
# Self-test


def self_test():
    """Concentric regular polygons: surface radius 10 (N = 64 panels), loop radius 10.5
    (M = 3N segments, so each panel midpoint faces a loop segment's midpoint: a unique nearest
    point on the mirror axis), no lead-in. Returns a list of failures."""
    failures = []
    n, m, r_s, r_w = 64, 192, 10.0, 10.5
    th_s = 2 * np.pi * np.arange(n) / n
    th_w = 2 * np.pi * np.arange(m + 1) / m
    surface = np.c_[r_s * np.cos(th_s), r_s * np.sin(th_s)]
    normals = np.c_[np.cos(th_w), np.sin(th_w)]
    loop = r_w * normals
    loop[-1] = loop[0]
    spec = {
        "surface": surface,
        "loop": loop,
        "normals": normals,
        "arc_u": th_w / (2 * np.pi),
        "lead_in": np.zeros((0, 2)),
        "outline": surface,
        "min_clearance_mm": 0.1,
        "min_distance_mm": 0.05,
        "window": 0.25,
        "law": "paper",
        "cse": None,
        "control_points": 16,
        "smoothing": 0.0,
    }

    def check(ok, what):
        if not ok:
            failures.append(what)

    for law in ("paper", "author_code"):
        spec["law"] = law
        prob = Problem(spec)
        zero = np.zeros(16)
        full = prob.exposure(zero, causal=False)
        spread = np.ptp(full) / full.mean()
        check(spread < 1e-9, f"{law}: unmasked exposure differs between panels by {spread:.2e}")
        # Closed form against a midpoint rule on the same loop, each segment split 4000 times
        # (the rule's error, from the pieces that straddle a visibility switch, is ~5e-6).
        f = np.linspace(0.0, 1.0, 4001)[:-1]
        fine = loop[:-1, None, :] + f[None, :, None] * (loop[1:] - loop[:-1])[:, None, :]
        fine = np.vstack([fine.reshape(-1, 2), loop[-1:]])
        mids = 0.5 * (fine[1:] + fine[:-1])
        ds = np.hypot(*(fine[1:] - fine[:-1]).T)
        dirs = (fine[1:] - fine[:-1]) / ds[:, None]
        s = prob.surface
        rx = mids[:, 0] - s.mid[0, 0]
        ry = mids[:, 1] - s.mid[0, 1]
        chi = (s.tx[0, 0] * ry - s.ty[0, 0] * rx) <= 0
        power = 1 if law == "paper" else 2
        integrand = np.abs(s.tx[0, 0] * dirs[:, 0] + s.ty[0, 0] * dirs[:, 1])
        quad = float(np.sum(chi * integrand / np.hypot(rx, ry) ** power * ds))
        check(
            abs(quad - full[0]) < 2e-5 * full[0],
            f"{law}: closed form {full[0]:.6f} vs quadrature {quad:.6f}",
        )
        # Causal mask: a panel whose visible wire lies wholly after the loop's start and before
        # its end sees exactly the half of the wire up to its cut point (mirror symmetry).
        masked = prob.exposure(zero)
        reach = math.acos(r_s / r_w) + 2 * np.pi / n
        middle = (s.u * 2 * np.pi > reach) & (s.u * 2 * np.pi < 2 * np.pi - reach)
        half = np.max(np.abs(masked[middle] - 0.5 * full[middle])) / full.mean()
        check(
            middle.sum() > n // 2 and half < 1e-9,
            f"{law}: masked exposure is not half the unmasked one away from the seam ({half:.2e})",
        )
        # Moving the loop outwards (delta = 0.2 mm everywhere: the basis sums to 1) lowers the
        # exposure of every panel.
        out = prob.exposure(np.full(16, 0.2))
        check(np.all(out < masked), f"{law}: moving outwards did not lower every panel")
        check(
            np.allclose(prob.loop_points(np.full(16, 0.2))[:-1], (r_w + 0.2) * normals[:-1]),
            f"{law}: a uniform 0.2 mm control does not give a 10.7 mm circle",
        )
        # Feasibility: 0.45 mm inwards leaves 0.05 mm < the 0.1 mm margin; 2 mm inwards crosses.
        check(math.isfinite(prob.loss(zero)), f"{law}: baseline infeasible")
        check(prob.loss(np.full(16, -0.45)) == math.inf, f"{law}: 0.05 mm clearance accepted")
        check(prob.loss(np.full(16, -2.0)) == math.inf, f"{law}: a path inside the foil accepted")
        bump = np.zeros(16)
        bump[5] = -1.5
        check(prob.loss(bump) == math.inf, f"{law}: a path crossing the foil accepted")
        # The loop's chords sag inwards by r_w (1 - cos(pi/M)) = 1.4e-3 mm.
        gap = prob.clearance(zero)
        check(r_w * math.cos(math.pi / m) - r_s - 1e-9 < gap <= r_w - r_s, f"{law}: gap {gap}")
    return failures


def main():
    _keep_freed_memory()
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("problem", nargs="?", help="problem JSON file")
    ap.add_argument("--iterations", type=int, help="override pso.iterations")
    ap.add_argument("--seed", type=int, help="override pso.seed")
    ap.add_argument("--self-test", action="store_true", help="run the built-in checks")
    args = ap.parse_args()
    if args.self_test:
        failures = self_test()
        for f in failures:
            print(f"FAIL {f}", file=sys.stderr)
        print("self-test " + ("failed" if failures else "passed"), file=sys.stderr)
        sys.exit(1 if failures else 0)
    if args.problem is None:
        ap.error("a problem file is required (or --self-test)")
    if args.iterations is not None and args.iterations < 0:
        ap.error("--iterations must be >= 0")
    try:
        print(json.dumps(run(args.problem, args.iterations, args.seed)))
    except ProblemError as e:
        print(f"pso_peer: {e}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
