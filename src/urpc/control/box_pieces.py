"""The parameter box cut into pieces for the certificate (:mod:`urpc.control.cells`): each piece
gets its own inertia bounds, vertices and metric, which are tighter than the whole box's."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..model.uncertainty import ParameterBox

#: At most this many pieces of the box (the certificate's cost grows linearly with it).
PIECES = 4


def split_box(box: ParameterBox, pieces: int = PIECES) -> list[ParameterBox]:
    """The box cut along its widest mass intervals (at most 3, relative to their upper end) into
    at most ``pieces`` boxes whose union is the box."""
    masses = [(link.upper[0] - link.lower[0]) / link.upper[0] for link in box.links]
    order = [k for k in np.argsort(masses)[::-1] if masses[k] > 0][:3]
    if not order:
        return [box]
    cuts = max(2, int(round(pieces ** (1.0 / len(order)))))
    while cuts ** len(order) > pieces and len(order) > 1:
        order = order[:-1]
        cuts = max(2, int(round(pieces ** (1.0 / len(order)))))
    result = [box]
    for k in order:
        split = []
        for piece in result:
            link = piece.links[k]
            edges = np.linspace(link.lower[0], link.upper[0], cuts + 1)
            for low, high in zip(edges[:-1], edges[1:], strict=True):
                lower, upper = link.lower.copy(), link.upper.copy()
                lower[0], upper[0] = low, high
                links = list(piece.links)
                links[k] = dataclasses.replace(link, lower=lower, upper=upper)
                split.append(dataclasses.replace(piece, links=tuple(links)))
        result = split
    return result
