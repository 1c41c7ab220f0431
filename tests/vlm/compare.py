#!/usr/bin/env python3
"""An independent vortex-lattice solution of an AVL geometry file (issue 24, seed 002).

Reads the `.avl` file that `cell_wing::avl` writes (parsed here, field by field, after AVL's
user guide `avl_doc.txt`, so a wrong file fails here), builds the same wing as an AeroSandbox
`Airplane` and solves it with AeroSandbox's `VortexLatticeMethod` (horseshoe vortices on the
camber surface, Kutta–Joukowski forces). Prints one JSON object:

- `c_l_design`: C_L at the file's incidences (freestream alpha = 0, the design point);
- `lift_slope_per_rad`: (C_L(alpha = step) - C_L(0)) / step;
- `strips`: per spanwise strip, root to tip over the whole span, its centre `y_over_b` and
  `gamma_hat` = Gamma / (V b), the strip's summed chordwise vortex strengths (its bound
  circulation), at the design point;
- `cdi_trefftz` and `span_efficiency`: induced drag from the strips' trailing vortices in the
  Trefftz plane, D = 1/2 rho sum Gamma_i w_i dy_i, w_i the downwash of the trailing legs as
  2-D vortices (Katz and Plotkin, Low-Speed Aerodynamics, 2nd ed., sec. 12.1.3), and
  e = C_L^2 / (pi AR C_Di); `cdi_near_field` is AeroSandbox's own (forces on the bound legs);
- `camber_alpha_l0_deg`: the thin-airfoil zero-lift angle of the first section's camber line
  (0 for a flat one): alpha_L0 = -(1/pi) int_0^pi dz/dx (cos theta - 1) dtheta.

Usage: compare.py WING.avl [--alpha-step-deg 2]
"""

import argparse
import json
import math
import pathlib
import sys
import time

import aerosandbox as asb
import aerosandbox.numpy as anp
import numpy as np


class AvlFormatError(Exception):
    """The file is not an AVL geometry file this script can model."""


def significant_lines(text):
    """Non-blank lines without comments ('#' or '!' lines; '!' starts an inline comment)."""
    out = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("!", 1)[0].strip()
        if line and not line.startswith("#"):
            out.append((number, line))
    return out


def floats(line, count, what, number):
    """The first `count` numbers of a data line."""
    parts = line.split()
    try:
        values = [float(p) for p in parts[:count]]
    except ValueError:
        values = []
    if len(values) < count:
        raise AvlFormatError(f"line {number}: expected {what}, got {line!r}")
    return values


def read_dat(path):
    """An XFOIL/Selig coordinate file: a name line, then x y pairs until a line that is not."""
    lines = pathlib.Path(path).read_text().splitlines()
    points = []
    for line in lines[1:]:
        parts = line.split()
        try:
            x, y = float(parts[0]), float(parts[1])
        except (ValueError, IndexError):
            if points:
                break
            continue
        points.append((x, y))
    if len(points) < 5:
        raise AvlFormatError(f"{path}: fewer than 5 coordinate pairs")
    pts = np.array(points)
    # AeroSandbox wants the upper surface first (TE -> LE -> TE counter-clockwise); AVL takes
    # either direction.
    le = int(np.argmin(pts[:, 0]))
    if np.mean(pts[:le + 1, 1]) < np.mean(pts[le:, 1]):
        pts = pts[::-1]
    return pts


def parse_avl(path):
    """The header and surfaces of an AVL geometry file (avl_doc.txt, "Geometry Input File")."""
    path = pathlib.Path(path)
    lines = significant_lines(path.read_text())
    if len(lines) < 5:
        raise AvlFormatError(f"{path}: needs the 5 header lines")
    title = lines[0][1]
    (mach,) = floats(lines[1][1], 1, "Mach", lines[1][0])
    iysym, izsym, _zsym = floats(lines[2][1], 3, "iYsym iZsym Zsym", lines[2][0])
    sref, cref, bref = floats(lines[3][1], 3, "Sref Cref Bref", lines[3][0])
    xyz_ref = floats(lines[4][1], 3, "Xref Yref Zref", lines[4][0])
    i = 5
    if i < len(lines) and lines[i][1][:4].upper() not in ("SURF", "BODY"):
        floats(lines[i][1], 1, "CDp", lines[i][0])
        i += 1
    if iysym != 0 or izsym != 0:
        raise AvlFormatError("only iYsym = iZsym = 0 (no image planes) is modelled")
    surfaces = []
    while i < len(lines):
        number, line = lines[i]
        key = line[:4].upper()
        i += 1
        if key == "SURF":
            name = lines[i][1]
            numbers = lines[i + 1][1].split()
            nchord, cspace = floats(lines[i + 1][1], 2, "Nchord Cspace", lines[i + 1][0])
            nspan = sspace = None
            if len(numbers) >= 4:
                nspan, sspace = floats(lines[i + 1][1], 4, "Nspan Sspace", lines[i + 1][0])[2:]
            surfaces.append(
                dict(name=name, nchord=int(nchord), cspace=cspace, nspan=nspan,
                     sspace=sspace, ydup=None, sections=[])
            )
            i += 2
        elif key == "YDUP":
            surfaces[-1]["ydup"] = floats(lines[i][1], 1, "Ydupl", lines[i][0])[0]
            i += 1
        elif key == "SECT":
            xle, yle, zle, chord, ainc = floats(lines[i][1], 5, "Xle Yle Zle Chord Ainc",
                                                lines[i][0])
            surfaces[-1]["sections"].append(
                dict(xle=xle, yle=yle, zle=zle, chord=chord, ainc=ainc, afile=None, claf=1.0)
            )
            i += 1
        elif key == "AFIL":
            name = lines[i][1].strip().strip('"')
            surfaces[-1]["sections"][-1]["afile"] = str(path.parent / name)
            i += 1
        elif key == "CLAF":
            surfaces[-1]["sections"][-1]["claf"] = floats(lines[i][1], 1, "CLaf",
                                                          lines[i][0])[0]
            i += 1
        else:
            raise AvlFormatError(f"line {number}: keyword {line!r} is not modelled here")
    if not surfaces:
        raise AvlFormatError(f"{path}: no SURFACE")
    for s in surfaces:
        if len(s["sections"]) < 2:
            raise AvlFormatError(f"surface {s['name']}: needs at least 2 sections")
        if s["nspan"] is None:
            raise AvlFormatError(f"surface {s['name']}: per-section Nspan is not modelled")
        if any(abs(sec["claf"] - 1.0) > 1e-9 for sec in s["sections"]):
            raise AvlFormatError("CLAF != 1 cannot be modelled by AeroSandbox's VLM")
    return dict(title=title, mach=mach, sref=sref, cref=cref, bref=bref, xyz_ref=xyz_ref,
                surfaces=surfaces)


def spacing(n, parameter):
    """AVL's node fractions 0..1 for a spacing parameter (avl_doc.txt, "Vortex Lattice
    Spacing Distributions"): 0 or 3 equal, 1 cosine, 2 sine, -2 -sine (dense at the end)."""
    t = np.linspace(0.0, 1.0, n + 1)
    p = round(parameter)
    if abs(parameter - p) > 1e-9:
        raise AvlFormatError(f"blended spacing {parameter} is not modelled")
    if p in (0, 3, -3):
        return t
    if p in (1, -1):
        return 0.5 * (1.0 - np.cos(np.pi * t))
    if p == 2:
        return 1.0 - np.cos(0.5 * np.pi * t)
    return np.sin(0.5 * np.pi * t)  # -2


def thin_airfoil_alpha_l0_deg(coords):
    """Zero-lift angle of the camber line, thin-airfoil theory (Anderson, Fundamentals of
    Aerodynamics, eq. 4.61)."""
    le = int(np.argmin(coords[:, 0]))
    upper, lower = coords[:le + 1][::-1], coords[le:]
    theta = np.linspace(1e-6, np.pi - 1e-6, 4001)
    x = 0.5 * (1.0 - np.cos(theta))
    camber = 0.5 * (np.interp(x, upper[:, 0], upper[:, 1]) + np.interp(x, lower[:, 0],
                                                                       lower[:, 1]))
    slope = np.gradient(camber, x)
    f = slope * (np.cos(theta) - 1.0)
    integral = np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(theta))
    return math.degrees(-integral / math.pi)


def airplane(avl):
    """The AeroSandbox Airplane of the parsed file: per surface one Wing whose cross-sections
    sit on AVL's spanwise vortex edges (Nspan, Sspace), with chord, leading edge and Ainc
    interpolated linearly between the file's sections as AVL does."""
    flat = asb.Airfoil("naca0012")  # AeroSandbox meshes the camber line only: zero camber.
    wings = []
    for s in avl["surfaces"]:
        secs = s["sections"]
        ys = np.array([sec["yle"] for sec in secs])
        if np.any(np.diff(ys) <= 0):
            raise AvlFormatError(f"surface {s['name']}: sections must run outward in y")
        edges = ys[0] + (ys[-1] - ys[0]) * spacing(int(s["nspan"]), s["sspace"])
        # AVL moves the nearest vortex edge onto each section.
        for y in ys:
            edges[np.argmin(np.abs(edges - y))] = y
        edges = np.unique(edges)
        foils = {}
        xsecs = []
        for y in edges:
            k = min(np.searchsorted(ys, y, side="right") - 1, len(secs) - 2)
            t = (y - ys[k]) / (ys[k + 1] - ys[k])
            lerp = lambda key: (1 - t) * secs[k][key] + t * secs[k + 1][key]  # noqa: E731
            afile = secs[k]["afile"] if t < 1.0 else secs[k + 1]["afile"]
            if afile and afile not in foils:
                foils[afile] = asb.Airfoil(name=pathlib.Path(afile).stem,
                                           coordinates=read_dat(afile))
            xsecs.append(asb.WingXSec(
                xyz_le=[lerp("xle"), y, lerp("zle")],
                chord=lerp("chord"),
                twist=lerp("ainc"),
                airfoil=foils[afile] if afile else flat,
            ))
        if s["ydup"] not in (None, 0.0):
            raise AvlFormatError("YDUPLICATE about a plane other than y = 0 is not modelled")
        wings.append(asb.Wing(name=s["name"], symmetric=s["ydup"] is not None, xsecs=xsecs))
    return asb.Airplane(name=avl["title"], xyz_ref=avl["xyz_ref"], wings=wings,
                        s_ref=avl["sref"], c_ref=avl["cref"], b_ref=avl["bref"])


def solve(avl, plane, alpha_deg, velocity):
    """One VLM solution at freestream angle alpha."""
    s = avl["surfaces"][0]
    cspace = round(s["cspace"])
    chordwise = {1: anp.cosspace, -1: anp.cosspace, 0: anp.linspace, 3: anp.linspace}
    if cspace not in chordwise or abs(s["cspace"] - cspace) > 1e-9:
        raise AvlFormatError(f"chordwise spacing {s['cspace']} is not modelled")
    vlm = asb.VortexLatticeMethod(
        airplane=plane,
        op_point=asb.OperatingPoint(velocity=velocity, alpha=alpha_deg),
        spanwise_resolution=1,
        chordwise_resolution=s["nchord"],
        chordwise_spacing_function=chordwise[cspace],
    )
    return vlm, vlm.run()


def strips(vlm, nchord, velocity, span):
    """Per spanwise strip (the panels are stored chordwise-fastest): edges and Gamma/(V b)."""
    gamma = np.asarray(vlm.vortex_strengths).reshape(-1, nchord).sum(axis=1)
    y_left = vlm.left_vortex_vertices[::nchord, 1]
    y_right = vlm.right_vortex_vertices[::nchord, 1]
    lo, hi = np.minimum(y_left, y_right), np.maximum(y_left, y_right)
    order = np.argsort(lo)
    lo, hi, gamma = lo[order], hi[order], gamma[order]
    if np.max(np.abs(lo[1:] - hi[:-1])) > 1e-9 * span:
        raise AvlFormatError("the strips do not tile the span")
    return lo, hi, gamma / (velocity * span)


def trefftz_cdi(lo, hi, gamma_hat, span, sref):
    """Induced drag coefficient in the Trefftz plane from the strips' circulation
    (Gamma in units of V b, so C_Di = 2 b^2/S sum Gamma_i w_i dy_i with w in units of V)."""
    edges = np.append(lo, hi[-1]) / span
    g = np.concatenate(([0.0], gamma_hat, [0.0]))
    shed = g[:-1] - g[1:]  # trailing vortex at each edge: circulation inboard minus outboard
    centre = 0.5 * (lo + hi) / span
    downwash = -np.sum(shed[None, :] / (2 * np.pi * (centre[:, None] - edges[None, :])),
                       axis=1)
    return float(np.sum(gamma_hat * downwash * (hi - lo) / span)) * span**2 / sref


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("avl_file")
    parser.add_argument("--alpha-step-deg", type=float, default=2.0)
    args = parser.parse_args()
    started = time.monotonic()
    try:
        avl = parse_avl(args.avl_file)
        plane = airplane(avl)
    except (AvlFormatError, OSError) as e:
        print(f"compare.py: {args.avl_file}: {e}", file=sys.stderr)
        return 65
    velocity = 10.0
    nchord = avl["surfaces"][0]["nchord"]
    vlm, design = solve(avl, plane, 0.0, velocity)
    _, stepped = solve(avl, plane, args.alpha_step_deg, velocity)
    span = avl["bref"]
    lo, hi, gamma_hat = strips(vlm, nchord, velocity, span)
    cdi = trefftz_cdi(lo, hi, gamma_hat, span, avl["sref"])
    aspect_ratio = span**2 / avl["sref"]
    c_l = float(design["CL"])
    first = avl["surfaces"][0]["sections"][0]["afile"]
    print(json.dumps({
        "file": args.avl_file,
        "aerosandbox": asb.__version__,
        "panels": int(len(vlm.vortex_strengths)),
        "aspect_ratio": aspect_ratio,
        "c_l_design": c_l,
        "c_l_from_strips": float(2 * np.sum(gamma_hat * (hi - lo)) * span / avl["sref"]),
        "lift_slope_per_rad": (float(stepped["CL"]) - c_l) / math.radians(args.alpha_step_deg),
        "cdi_trefftz": cdi,
        "cdi_near_field": float(design["CD"]),
        "span_efficiency": c_l**2 / (math.pi * aspect_ratio * cdi),
        "camber_alpha_l0_deg": thin_airfoil_alpha_l0_deg(read_dat(first)) if first else 0.0,
        "strips": {
            "y_over_b": (0.5 * (lo + hi) / span).tolist(),
            "width_over_b": ((hi - lo) / span).tolist(),
            "gamma_hat": gamma_hat.tolist(),
        },
        "seconds": time.monotonic() - started,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
