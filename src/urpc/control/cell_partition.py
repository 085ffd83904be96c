"""The cells of time the certificate bounds over (:mod:`urpc.control.cells`), and how they are
refined: batches of cells, each cell active until it is split in two halves.

The first cells are cut uniformly over the covered span; the search
(:mod:`urpc.control.sampled_search`) splits the cells that decide the floor. Each split adds a
batch of halves; the split cells stay in their batch, inactive, so that every batch's
enclosures (computed once, :class:`~urpc.control.cells.CellFloor`) stay valid. The partition's
cells (the active ones, batch by batch) are the cell axis of the certificate's quantities. The
halves of a cell cover its span, so the partition covers the whole reference at every step.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..model.ball_arithmetic import U
from ..model.regressor_balls import Ball

#: A cell is split at most this many times (its width at least 2^-MAX_DEPTH of its first cell).
MAX_DEPTH = 5


@dataclasses.dataclass(frozen=True)
class CellBatch:
    """Cells enclosed together: their spans ``[start, end]`` [s] (before the widening by the
    period that follows), their refinement depth, the curvature group of each (the box of first
    cells whose second derivatives of ``M`` the cell reuses) and whether it takes them over its
    own box instead (``own``: the halves of a cell split because an inertia model failed on it,
    and their halves)."""

    start: np.ndarray
    end: np.ndarray
    depth: np.ndarray
    group: np.ndarray
    own: np.ndarray

    def __len__(self) -> int:
        return len(self.start)

    def __getitem__(self, index) -> CellBatch:
        return CellBatch(*(getattr(self, name)[index] for name in _FIELDS))

    @staticmethod
    def concatenate(parts: list[CellBatch]) -> CellBatch:
        """The cells of ``parts``, in order."""
        return CellBatch(*(np.concatenate([getattr(p, name) for p in parts]) for name in _FIELDS))


_FIELDS = ("start", "end", "depth", "group", "own")


class Partition:
    """The cells of ``[0, span]``: ``first`` uniform cells, grouped ``group_size`` by
    ``group_size`` for the second derivatives of ``M``, then the halves of the cells split.

    Attributes:
        batches: Every batch of cells, the first cells first.
        active: Per batch, which of its cells are in the partition (not split).
        generation: How many times cells were split (the certificate's quantities are cached per
            generation).
    """

    def __init__(self, span: float, first: int, group_size: int):
        edges = np.linspace(0.0, span, first + 1)
        self.batches = [
            CellBatch(
                edges[:-1],
                edges[1:],
                np.zeros(first, dtype=int),
                np.arange(first) // group_size,
                np.zeros(first, dtype=bool),
            )
        ]
        self.active = [np.ones(first, dtype=bool)]
        self.generation = 0

    @property
    def count(self) -> int:
        """The number of cells."""
        return int(sum(int(mask.sum()) for mask in self.active))

    def used(self) -> list[int]:
        """The batches that hold cells of the partition (their indices)."""
        return [k for k, mask in enumerate(self.active) if mask.any()]

    def cells(self) -> CellBatch:
        """Every cell of the partition, in the order of the cell axis (batch by batch)."""
        return CellBatch.concatenate([b[m] for b, m in zip(self.batches, self.active, strict=True)])

    def split(self, cells, own: bool = False) -> int:
        """Split the given cells (indices along the cell axis) in two halves each, except those
        already split :data:`MAX_DEPTH` times; with ``own``, the halves take the second
        derivatives of ``M`` over their own boxes (so do the halves of a cell that does).
        Returns how many cells were split."""
        chosen = np.zeros(self.count, dtype=bool)
        chosen[np.asarray(cells, dtype=int)] = True
        offset, parts = 0, []
        for batch, active in zip(self.batches, self.active, strict=True):
            local = np.flatnonzero(active)
            take = local[chosen[offset : offset + len(local)]]
            offset += len(local)
            take = take[batch.depth[take] < MAX_DEPTH]
            active[take] = False
            parts.append(batch[take])
        split = CellBatch.concatenate(parts)
        if not len(split):
            return 0
        middle = 0.5 * (split.start + split.end)
        self.batches.append(
            CellBatch(
                np.concatenate([split.start, middle]), np.concatenate([middle, split.end]),
                np.concatenate([split.depth + 1] * 2), np.concatenate([split.group] * 2),
                np.concatenate([split.own | own] * 2),
            )
        )  # fmt: skip
        self.active.append(np.ones(2 * len(split), dtype=bool))
        self.generation += 1
        return len(split)


#: The entries of the certificate's quantities whose cell axis is the last (the others': the
#: first; numbers that are not arrays are the same for every cell).
LAST_AXIS = frozenset({"R", "RM", "V", "Rs", "R_links"})


def merge_cells(outs: list[dict], masks: list[np.ndarray]) -> dict:
    """One set of quantities from the batches' (the cells where ``masks`` hold), the cells in
    batch order."""

    def merge(key, values):
        first = values[0]
        if isinstance(first, list):
            return [
                {k: merge(k, [v[j][k] for v in values]) for k in first[j]}
                for j in range(len(first))
            ]
        if not isinstance(first, np.ndarray) or first.ndim == 0:
            return first
        if key in LAST_AXIS:
            return np.concatenate([v[..., m] for v, m in zip(values, masks, strict=True)], axis=-1)
        return np.concatenate([v[m] for v, m in zip(values, masks, strict=True)], axis=0)

    return {key: merge(key, [out[key] for out in outs]) for key in outs[0]}


def outward(box: Ball, side: int) -> np.ndarray:
    """The end of a ball on ``side`` (-1 lower, +1 upper), rounded outward (beyond it)."""
    return box.mid + side * (box.rad * (1 + 4 * U) + 4 * U * np.abs(box.mid))


def inward(box: Ball, side: int) -> np.ndarray:
    """The end of a ball on ``side``, rounded inward (within it)."""
    return box.mid + side * (box.rad * (1 - 4 * U) - 4 * U * np.abs(box.mid))
