"""The cell enclosures do not depend on how the cells are batched: the Coriolis forms, computed
chunk by chunk to bound memory, give every cell the enclosure it gets in one batch."""

from __future__ import annotations

import numpy as np

import urpc
import urpc.control.cell_bounds as cell_bounds
from urpc.control.cells import CellFloor
from urpc.trajectories import generic_trajectory


def test_chunked_coriolis_forms_equal_one_batch(monkeypatch):
    robot = urpc.load_robot("ur5")
    box = urpc.load_uncertainty("ur5", robot)
    controller = urpc.synthesize(robot, box, 1e-2, sample_period=1e-3)
    trajectory = generic_trajectory(box.nominal_robot(robot))

    def pieces(chunk_bytes):
        monkeypatch.setattr(cell_bounds, "CORIOLIS_CHUNK_BYTES", chunk_bytes)
        floor = CellFloor(controller, trajectory, 0.5, cells=16)
        return floor.quantities(1e-2, 0.5, 2e-3)["pieces"]

    whole, chunked = pieces(2**40), pieces(1)  # one batch; one cell per chunk
    for a, b in zip(whole, chunked, strict=True):
        for name in ("coriolis", "metric_rate"):
            np.testing.assert_allclose(b[name], a[name], rtol=1e-12)
            assert np.all(np.isfinite(a[name])) and np.all(a[name] > 0)
