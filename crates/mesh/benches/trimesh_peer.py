#!/usr/bin/env python3
"""trimesh peer of the cell_mesh slice bench.

Usage: trimesh_peer.py MESH.stl FIRST_Z LAYER_HEIGHT LAYERS [REPEATS]

Slices with `mesh.section_multiplane` at z = FIRST_Z + k * LAYER_HEIGHT, k = 0..LAYERS-1, and
prints one JSON object: load time, median section time (segments to Path2D), median time of
section + polygon assembly (Path2D.area builds the shapely polygons with holes), and the net
area per layer (None for an empty layer is reported as 0).
"""
import json
import statistics
import sys
import time

import numpy as np
import trimesh


def main():
    path, first_z, h, n = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
    repeats = int(sys.argv[5]) if len(sys.argv) > 5 else 3
    t0 = time.perf_counter()
    mesh = trimesh.load(path, force="mesh")
    load_s = time.perf_counter() - t0
    heights = np.arange(n, dtype=np.float64) * h
    origin = [0.0, 0.0, first_z]
    normal = [0.0, 0.0, 1.0]

    section_times, total_times, areas = [], [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        sections = mesh.section_multiplane(plane_origin=origin, plane_normal=normal, heights=heights)
        t1 = time.perf_counter()
        layer_areas = [float(s.area) if s is not None else 0.0 for s in sections]
        t2 = time.perf_counter()
        section_times.append(t1 - t0)
        total_times.append(t2 - t0)
        areas = layer_areas
    print(
        json.dumps(
            {
                "trimesh": trimesh.__version__,
                "triangles": int(len(mesh.faces)),
                "load_s": load_s,
                "section_s": statistics.median(section_times),
                "section_area_s": statistics.median(total_times),
                "areas": areas,
            }
        )
    )


if __name__ == "__main__":
    main()
