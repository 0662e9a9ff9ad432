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
