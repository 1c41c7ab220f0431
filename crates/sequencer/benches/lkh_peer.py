#!/usr/bin/env python3
"""LKH-3 peer for the sequencing bench (issue 7: idle length within 3 % of LKH-3 on the same
pierce points). Reads "x y" lines from stdin (the first is the start point), solves the closed
tour with the PyPI `elkai` package (LKH-3) and prints its length in mm.

Coordinates go to LKH as EUC_2D scaled by 100 (LKH rounds to integers); the length printed is
recomputed in floating point. Bench-only: not a runtime dependency.
"""
import math
import sys

import elkai

pts = [tuple(map(float, line.split())) for line in sys.stdin if line.strip()]
coords = {str(i): (x * 100.0, y * 100.0) for i, (x, y) in enumerate(pts)}
tour = [int(k) for k in elkai.Coordinates2D(coords).solve_tsp(runs=int(sys.argv[1]) if len(sys.argv) > 1 else 10)]
if tour[0] == tour[-1]:
    tour = tour[:-1]
length = sum(math.dist(pts[tour[i]], pts[tour[(i + 1) % len(tour)]]) for i in range(len(tour)))
print(f"{length:.3f}")
