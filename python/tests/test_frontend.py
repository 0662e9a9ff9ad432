"""Datasets, images and CAT-Graph from Python, on a simulated office."""
import numpy as np
import pytest

import catgraph as cg

FIXTURE = __import__("pathlib").Path(__file__).resolve().parents[2] / "tests" / "fixtures"


@pytest.fixture(scope="module")
def office(tmp_path_factory):
    # office-change-short at 3 frames/s: 375 frames over two traversals.
    text = (FIXTURE / "office-change-short.yaml").read_text().replace("frame_rate_hz: 5.0", "frame_rate_hz: 3.0")
    root = tmp_path_factory.mktemp("office")
    (root / "office.yaml").write_text(text)
    frames = cg.simulate(str(root / "office.yaml"), root / "data")
    assert frames == 375
    return cg.read_dataset(root / "data")


def test_a_simulated_dataset_reads_back(office):
    assert len(office.frames) == 375
    assert {f.traversal for f in office.frames} == {1, 2}
    assert office.odometry.shape[1] == 4 and office.ground_truth.shape[1] == 4
    assert np.all(np.diff(office.odometry[:, 0]) > 0)
    image = cg.read_image(office.image_path(0))
    assert image.dtype == np.uint8 and image.shape == (101, 261, 3)


def test_an_image_folder_imports_with_its_times_and_poses(office, tmp_path):
    times = tmp_path / "times.txt"
    times.write_text("".join(f"{f.timestamp_s:.9f}\n" for f in office.frames))
    frames, left_out, traversals, synthetic = cg.import_dataset(
        "folder", office.root / "images", tmp_path / "imported", times=times,
        poses=office.root / "groundtruth.csv")
    assert (frames, left_out, synthetic) == (375, 0, True)
    t = np.array([f.timestamp_s for f in office.frames])
    assert traversals == 1 + int(np.sum(np.diff(t) > 5.0))
    imported = cg.read_dataset(tmp_path / "imported")
    assert len(imported.frames) == 375
    for column in (1, 2, 3):
        a = np.interp(t, imported.ground_truth[:, 0], imported.ground_truth[:, column])
        b = np.interp(t, office.ground_truth[:, 0], office.ground_truth[:, column])
        assert np.max(np.abs(a - b)) < 1e-5
    with pytest.raises(ValueError, match="folder, kitti or tum"):
        cg.import_dataset("rosbag", office.root, tmp_path / "x")


def test_localize_closes_loops_near_the_true_place(office):
    result = cg.localize(office)
    visual = [c for c in result.closures if c.kind == "visual"]
    inferred = [c for c in result.closures if c.kind == "inferred"]
    assert len(visual) > 0 and len(inferred) > 0
    assert all(len(c.parents) == 2 for c in inferred)
    assert np.median([c.error_m for c in result.closures]) < 1.0
    # The front end's graph goes straight to the back end.
    solved = cg.optimize(result.graph)
    assert solved.summary.usable
    assert solved.accepted + solved.rejected == len(result.closures)


def test_a_corrupt_image_is_a_file_error(tmp_path):
    path = tmp_path / "frame.png"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\x00" * 40)
    with pytest.raises(cg.FileError, match="frame.png"):
        cg.read_image(path)


def _at(rows, t):
    """Poses [x, y, theta] of timed rows [t, x, y, theta] at times t."""
    theta = np.unwrap(rows[:, 3])
    return np.stack([np.interp(t, rows[:, 0], rows[:, c]) for c in (1, 2)] + [np.interp(t, rows[:, 0], theta)], 1)


def _aligned_rmse(estimate, truth):
    """Position RMSE after the best rigid alignment of estimate onto truth."""
    a, b = estimate[:, :2] - estimate[:, :2].mean(0), truth[:, :2] - truth[:, :2].mean(0)
    u, _, vt = np.linalg.svd(a.T @ b)
    r = (u @ vt).T
    if np.linalg.det(r) < 0:
        r = (u @ np.diag([1.0, -1.0]) @ vt).T
    return float(np.sqrt(np.mean(np.sum((a @ r.T - b) ** 2, 1))))


def test_the_mapper_takes_frames_one_at_a_time_and_corrects_the_map(office):
    vocabulary = cg.train_map_vocabulary(office)
    assert vocabulary.size == 1000
    mapper = cg.Mapper(vocabulary)
    t = np.array([f.timestamp_s for f in office.frames])
    odometry, truth = _at(office.odometry, t), _at(office.ground_truth, t)
    closures = []
    for k in range(len(t)):
        image = cg.read_image(office.image_path(k))
        r = mapper.add_frame(t[k], cg.Pose2(*odometry[k]), image)
        assert r.frame == k
        assert r.solved == (len(r.closures) > 0)
        if r.solved:
            assert r.accepted + r.rejected == len(closures) + len(r.closures)
        closures += r.closures
    visual = [c for c in closures if c.kind == "visual"]
    assert len(visual) > 0 and any(c.kind == "inferred" for c in closures)
    # Each closure's measurement against the true relative pose of its frames.
    def error(c):
        true = cg.Pose2(*truth[c.frame]).between(cg.Pose2(*truth[c.matched_frame]))
        return np.hypot(*(true.vector()[:2] - c.relative_pose.vector()[:2]))
    # Measured: 23 visual closures, median 0.24 m, two at 1.13 m (this office at 3 frames/s).
    assert np.median([error(c) for c in visual]) < 0.5
    assert [c.id for c in mapper.closures] == [c.id for c in closures]
    online = mapper.map()
    assert online.shape == (len(t), 3)
    assert _aligned_rmse(online, truth) < 0.5 * _aligned_rmse(odometry, truth)
    solved = mapper.solve()
    assert solved.summary.usable and solved.accepted + solved.rejected == len(closures)
    with pytest.raises(ValueError, match="H x W"):
        mapper.add_frame(t[-1] + 1.0, cg.Pose2(0, 0, 0), np.zeros((4, 4, 2), np.uint8))
