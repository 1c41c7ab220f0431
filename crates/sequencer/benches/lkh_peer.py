#!/usr/bin/env python3
"""LKH-3 peer for the sequencing bench (issue 7: idle length within 3 % of LKH-3 on the same
pierce points; issue 19: the same with lead-ins). Reads lines "px py [ex ey]" from stdin, one
per cut: where it is pierced and where its lead-out ends (the first line is the start point).
Solves the closed tour with the PyPI `elkai` package (LKH-3) and prints its length in mm.

Without exits (or all equal to the pierces) the tour is a symmetric TSP over the pierce points,
given as EUC_2D scaled by 100 (LKH rounds to integers). With lead-outs the travel from cut i to
cut j runs from i's exit to j's pierce: an asymmetric TSP, given as an explicit matrix of those
distances in hundredths of a mm. Either way the length printed is recomputed in floating
point. Bench-only: not a runtime dependency.
"""
import math
import sys

import elkai

runs = int(sys.argv[1]) if len(sys.argv) > 1 else 10
rows = [tuple(map(float, line.split())) for line in sys.stdin if line.strip()]
pierce = [(r[0], r[1]) for r in rows]
exit_ = [(r[2], r[3]) if len(r) >= 4 else (r[0], r[1]) for r in rows]
asymmetric = any(math.dist(p, e) > 1e-9 for p, e in zip(pierce, exit_))


def travel(i, j):
    return math.dist(exit_[i], pierce[j])


n = len(pierce)
if asymmetric:
    matrix = [[0 if i == j else round(travel(i, j) * 100.0) for j in range(n)] for i in range(n)]
    tour = list(elkai.DistanceMatrix(matrix).solve_tsp(runs=runs))
else:
    coords = {str(i): (x * 100.0, y * 100.0) for i, (x, y) in enumerate(pierce)}
    tour = [int(k) for k in elkai.Coordinates2D(coords).solve_tsp(runs=runs)]
if tour[0] == tour[-1]:
    tour = tour[:-1]
length = sum(travel(tour[i], tour[(i + 1) % len(tour)]) for i in range(len(tour)))
print(f"{length:.3f}")
