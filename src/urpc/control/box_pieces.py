"""The parameter box cut into pieces for the certificate (:mod:`urpc.control.cells`): each piece
gets its own inertia bounds, vertices and metric, which are tighter than the whole box's."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..model.uncertainty import ParameterBox

#: At most this many pieces of the box (the certificate's cost grows linearly with it).
PIECES = 4


def split_box(box: ParameterBox, pieces: int = PIECES) -> list[ParameterBox]:
    """The box cut along its mass intervals into at most ``pieces`` boxes whose union is the
    box: greedily, each further cut goes to the link whose pieces are widest (relative to the
    interval's upper end), as long as the number of pieces stays within ``pieces`` (a 0-3 kg
    payload next to +-10 % link masses is cut in four, not twice each way)."""
    widths = [(link.upper[0] - link.lower[0]) / link.upper[0] for link in box.links]
    cuts = [1] * len(box.links)
    while True:
        candidates = [k for k, w in enumerate(widths) if w > 0]
        if not candidates:
            break
        k = max(candidates, key=lambda j: widths[j] / cuts[j])
        if math.prod(cuts) // cuts[k] * (cuts[k] + 1) > pieces:
            break
        cuts[k] += 1
    result = [box]
    for k, count in enumerate(cuts):
        if count == 1:
            continue
        split = []
        for piece in result:
            link = piece.links[k]
            edges = np.linspace(link.lower[0], link.upper[0], count + 1)
            for low, high in zip(edges[:-1], edges[1:], strict=True):
                lower, upper = link.lower.copy(), link.upper.copy()
                lower[0], upper[0] = low, high
                links = list(piece.links)
                links[k] = dataclasses.replace(link, lower=lower, upper=upper)
                split.append(dataclasses.replace(piece, links=tuple(links)))
        result = split
    return result
