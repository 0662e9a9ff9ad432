"""The bindings against what the C++ library and the command line give."""
import math
import os
import subprocess

import numpy as np
import pytest

import catgraph as cg


def test_pose2_composes_and_inverts():
    a = cg.Pose2(1.0, 2.0, math.pi / 2)
    b = cg.Pose2(1.0, 0.0, 0.0)
    c = a * b
    assert c.x == pytest.approx(1.0) and c.y == pytest.approx(3.0) and c.theta == pytest.approx(math.pi / 2)
    identity = a.inverse() * a
    assert np.allclose(identity.vector(), 0.0, atol=1e-12)
    assert np.allclose(a.between(c).vector(), b.vector())


def test_pose3_keeps_g2o_quaternion_order():
    half = math.sqrt(0.5)
    p = cg.Pose3([1.0, 2.0, 3.0], [0.0, 0.0, half, half])  # 90 degrees about z, (x, y, z, w)
    assert np.allclose(p.quaternion, [0.0, 0.0, half, half])
    moved = p * cg.Pose3([1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
    assert np.allclose(moved.translation, [1.0, 3.0, 3.0])
    with pytest.raises(ValueError):
        cg.Pose3([0, 0, 0], [0, 0, 0, 0])


def square_with_false_closure():
    """A 4 x 4 m square driven twice (1 m steps), one true and one false closure, each switchable."""
    values, graph = cg.Values(), cg.FactorGraph()
    info = np.diag([100.0, 100.0, 400.0])
    pose = cg.Pose2()
    values.insert_pose(0, pose)
    for i in range(1, 32):
        move = cg.Pose2(1.0, 0.0, math.pi / 2 if i % 4 == 0 else 0.0)
        graph.add_between(i - 1, i, move, info)
        pose = pose * cg.Pose2(1.02 * move.x, move.y, move.theta)
        values.insert_pose(i, pose)
    graph.set_constant_pose(0)
    gate = cg.chi_square_quantile(3, 0.999)
    for switch_id, (a, b) in {1000: (0, 16), 1001: (2, 22)}.items():
        graph.add_switchable_between(a, b, switch_id, cg.Pose2(), info)
        graph.add_switch_prior(switch_id, 1.0, gate)
        values.insert_switch(switch_id, 1.0)
    return graph, values


def test_factor_graph_switches_the_false_closure_off():
    graph, values = square_with_false_closure()
    assert len(graph) == 31 + 4
    solved, summary = cg.optimize_factor_graph(graph, values)
    assert summary.usable
    assert summary.final_cost < summary.initial_cost
    assert solved.switch(1000) > 0.99
    assert solved.switch(1001) < 0.05
    # Pose 16 returns to pose 0; the rejected closure, scaled by its switch
    # (about 0.01), still pulls a little.
    assert np.allclose(solved.pose2(16).vector()[:2], [0.0, 0.0], atol=1e-3)


def test_every_method_decides_the_injected_outliers_and_the_graph_carries_it(tmp_path):
    graph, truth = cg.simulate_manhattan(poses=400, seed=3)
    labels = cg.inject_outliers(graph, 40, seed=5)
    assert sum(label.outlier for label in labels) == 40
    for method in ["switchable", "dcs", "cauchy", "huber", "gnc"]:
        result = cg.optimize(graph, method=method)
        assert result.summary.usable, method
        rejected = {d.id for d in result.closures if not d.accepted}
        outliers = {label.id for label in labels if label.outlier}
        assert outliers <= rejected, method
        # The decisions travel with the corrected graph, through a g2o file.
        path = tmp_path / f"{method}.g2o"
        result.graph.write_g2o(path)
        read = cg.read_graph(path)
        assert {c.id for c in read.loop_closures() if not c.accepted} == rejected, method
        scores = cg.score_closures(read, labels)
        assert scores.true_negatives == 40 and scores.false_positives == 0, method
        ate = cg.evaluate_trajectory(read, truth).ate_m.rmse
        assert ate < cg.evaluate_trajectory(graph, truth).ate_m.rmse, method


def test_optimize_matches_the_command_line(tmp_path):
    binary = os.environ.get("CATGRAPH_BINARY")
    if not binary:
        pytest.skip("CATGRAPH_BINARY is not set (ctest sets it)")
    graph, truth = cg.simulate_manhattan(poses=300, seed=2)
    cg.inject_outliers(graph, 20, policy="local-grouped", group_size=5, seed=4)
    graph.write_g2o(tmp_path / "in.g2o")
    subprocess.run([binary, "optimize", str(tmp_path / "in.g2o"), "-o", str(tmp_path / "cli.g2o")],
                   check=True, capture_output=True)
    ours = cg.optimize(graph)
    cli = cg.read_graph(tmp_path / "cli.g2o")
    assert np.allclose(ours.graph.poses(), cli.poses(), atol=1e-6)
    assert [c.accepted for c in ours.graph.loop_closures()] == [c.accepted for c in cli.loop_closures()]
    stages = [s.stage for s in ours.stages]
    assert stages[:3] == ["noise_scale", "initial_guess", "robust_solve"] and stages[-1] == "costs"
    assert ours.stages[2].iterations == ours.summary.iterations
    assert ours.wall_time_s == pytest.approx(sum(s.time_s for s in ours.stages))


def test_bad_input_raises_named_errors(tmp_path):
    with pytest.raises(cg.FileError, match="no-such.g2o"):
        cg.read_graph(tmp_path / "no-such.g2o")
    bad = tmp_path / "bad.g2o"
    bad.write_text("VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 1 x\n")
    with pytest.raises(cg.FileError, match=r"bad.g2o:2"):
        cg.read_graph(bad)
    assert isinstance(cg.FileError("x"), OSError)
    with pytest.raises(ValueError, match="method"):
        cg.optimize(cg.PoseGraph(), method="magic")
    g = cg.PoseGraph(2)
    g.add_vertex(0, cg.Pose2())
    with pytest.raises(ValueError, match="pose 1 is not a vertex"):
        g.add_constraint(0, 1, cg.Pose2(1, 0, 0))
    with pytest.raises(ValueError, match="3 x 3"):
        cg.FactorGraph().add_between(0, 1, cg.Pose2(), np.eye(4))


def test_a_graph_built_in_python_round_trips(tmp_path):
    g = cg.PoseGraph(3)
    for i in range(3):
        g.add_vertex(i, cg.Pose3([float(i), 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]), fixed=(i == 0))
    g.add_constraint(0, 1, cg.Pose3([1.0, 0.0, 0.0], [0, 0, 0, 1]), kind="odometry")
    g.add_constraint(1, 2, cg.Pose3([1.0, 0.0, 0.0], [0, 0, 0, 1]), kind="odometry")
    closure = g.add_constraint(0, 2, cg.Pose3([2.0, 0.0, 0.0], [0, 0, 0, 1]), np.eye(6) * 4.0, kind="visual")
    g.write_g2o(tmp_path / "g.g2o")
    read = cg.read_graph(tmp_path / "g.g2o")
    assert read.dimension == 3 and read.num_vertices == 3 and read.num_constraints == 3
    (c,) = read.loop_closures()
    assert c.id == closure and c.kind == "visual" and np.allclose(c.information, np.eye(6) * 4.0)
    assert read.poses().shape == (3, 7)
    assert np.allclose(read.poses(), g.poses())
