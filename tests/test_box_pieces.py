"""urpc.control.box_pieces: the pieces of a box cover it exactly, within the number asked for,
and the cuts go to the widest mass intervals."""

from __future__ import annotations

import numpy as np
import pytest

import urpc
from urpc.control.box_pieces import PIECES, split_box


def _inside(piece, point) -> bool:
    return all(
        np.all(point.links[b.link] >= b.lower) and np.all(point.links[b.link] <= b.upper)
        for b in piece.links
    )


@pytest.mark.parametrize("arm", ["rr_planar", "ur5"])
def test_the_pieces_cover_the_box_and_lie_in_it(arm):
    robot = urpc.load_robot(arm)
    box = urpc.load_uncertainty(arm, robot)
    pieces = split_box(box)
    assert 1 < len(pieces) <= PIECES
    for piece in pieces:  # every piece is inside the box
        for mine, whole in zip(piece.links, box.links, strict=True):
            assert np.all(mine.lower >= whole.lower) and np.all(mine.upper <= whole.upper)
    rng = np.random.default_rng(0)
    points = [box.sample(rng) for _ in range(300)]
    points += [box.vertex(k) for k in range(min(2**box.n_uncertain, 256))]
    for point in points:  # and every point of the box is in a piece
        assert any(_inside(piece, point) for piece in pieces)


def test_a_wide_payload_is_cut_before_narrow_link_masses():
    """The UR5's 0-3 kg payload is cut in four; its wrist links' +-10 % masses are not cut."""
    robot = urpc.load_robot("ur5")
    box = urpc.load_uncertainty("ur5", robot)
    pieces = split_box(box, 4)
    masses = {
        link.link: sorted({(p.links[k].lower[0], p.links[k].upper[0]) for p in pieces})
        for k, link in enumerate(box.links)
    }
    assert masses["payload"] == [(0.0, 0.75), (0.75, 1.5), (1.5, 2.25), (2.25, 3.0)]
    assert all(len(v) == 1 for k, v in masses.items() if k != "payload")
