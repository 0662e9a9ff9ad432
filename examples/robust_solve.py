#!/usr/bin/env python3
"""Robust pose-graph optimisation from Python: a simulated Manhattan world
with injected false loop closures, solved by every method, each scored
against the truth; or your own g2o file.

    python3 robust_solve.py                 # simulated world
    python3 robust_solve.py in.g2o out.g2o  # your graph: solve, list rejections, write
"""
import sys

import catgraph as cg


def simulated():
    graph, truth = cg.simulate_manhattan(poses=500, seed=1)
    labels = cg.inject_outliers(graph, 50, policy="random-grouped", group_size=10, seed=2)
    print(f"{graph.num_vertices} poses, {len(graph.loop_closures())} loop closures, 50 of them false")
    print(f"{'method':<12}{'ATE (m)':>9}{'precision':>11}{'recall':>8}{'time (s)':>10}")
    for method in ["none", "switchable", "dcs", "cauchy", "huber", "gnc"]:
        result = cg.optimize(graph, method=method)
        ate = cg.evaluate_trajectory(result.graph, truth).ate_m.rmse
        scores = cg.score_closures(result.graph, labels)
        print(f"{method:<12}{ate:9.3f}{scores.precision:11.3f}{scores.recall:8.3f}{result.time_s:10.2f}")


def own(path_in, path_out):
    graph = cg.read_graph(path_in)
    result = cg.optimize(graph)
    print(result.summary.brief_report())
    print(f"{result.accepted} loop closures accepted, {result.rejected} rejected")
    for d in result.closures:
        if not d.accepted:
            print(f"  rejected {d.from_id} -> {d.to_id} (weight {d.weight:.3f})")
    result.graph.write_g2o(path_out)  # with each closure's decision


if __name__ == "__main__":
    if len(sys.argv) == 3:
        own(sys.argv[1], sys.argv[2])
    elif len(sys.argv) == 1:
        simulated()
    else:
        sys.exit(__doc__)
