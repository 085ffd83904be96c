"""The result of identification: the identified fields, widths, coverage checks, the file."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..model.joint_dynamics import JOINT_FIELDS
from ..model.parameter_box import ParameterBox
from ..model.point import ParameterPoint
from ..model.robot import Robot


@dataclass(frozen=True)
class FieldBound:
    """One field of the identified box.

    Attributes:
        body: Link or payload name, or joint name for a drive parameter.
        field: ``mass``, ``com_x``, ..., ``izz``, or ``armature``, ``damping``, ``friction``
            (``m``, ``h_x``, ... for a barycentric link).
        prior: ``(lo, hi)`` of the prior box.
        identified: ``(lo, hi)`` enclosing every consistent parameter vector.
        payload: Whether the body is the payload.
    """

    body: str
    field: str
    prior: tuple[float, float]
    identified: tuple[float, float]
    payload: bool = False
    joint: bool = False

    @property
    def width_ratio(self) -> float:
        prior = self.prior[1] - self.prior[0]
        return (self.identified[1] - self.identified[0]) / prior if prior > 0 else 1.0

    @property
    def constrained(self) -> bool:
        """Whether the data narrowed the prior interval (by more than one part in 10^6)."""
        return self.width_ratio < 1.0 - 1e-6

    @property
    def group(self) -> str:
        if self.joint:
            return self.field
        if self.field in ("mass", "m"):
            return "mass"
        if self.field.startswith(("com_", "h_")):
            return "com" if self.field.startswith("com_") else "first moment"
        return "inertia"

    def contains(self, value: float) -> bool:
        return self.identified[0] <= value <= self.identified[1]


@dataclass
class Identification:
    """The result of :func:`identify`.

    Attributes:
        robot: The robot (as loaded).
        prior: The prior box.
        fields: One :class:`FieldBound` per uncertain field of the identified bodies and drives.
        samples: Number of samples used.
        seconds: Wall time of the identification [s].
        linear_programs: Number of linear programs solved.
        standard: Identified intervals of each body's standard parameters ``(lo, hi)`` (10
            each), when asked for.
        nominal_assumed: Uncertain prior parameters taken at their nominal value (payload mode).
        rank: Rank of the stacked regressor of the unknowns (scaled by the prior widths), and
            ``unknowns``, its number of columns.
    """

    robot: Robot
    prior: ParameterBox
    fields: list[FieldBound]
    samples: int
    seconds: float
    linear_programs: int
    noise: np.ndarray
    sources: str
    standard: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    nominal_assumed: list[str] = field(default_factory=list)
    rank: int = 0
    unknowns: int = 0
    payload_nominal: dict[str, float] = field(default_factory=dict)

    def field_bound(self, body: str, name: str) -> FieldBound:
        for f in self.fields:
            if f.body == body and f.field == name:
                return f
        raise KeyError(f"{body}.{name}")

    @property
    def unconstrained(self) -> list[str]:
        """``body.field`` of the fields the data did not narrow (they keep the prior interval)."""
        return [f"{f.body}.{f.field}" for f in self.fields if not f.constrained]

    def width_ratios(self) -> dict[str, float]:
        """Largest identified/prior width ratio per parameter group (mass, com, inertia, ...)."""
        groups: dict[str, float] = {}
        for f in self.fields:
            groups[f.group] = max(groups.get(f.group, 0.0), f.width_ratio)
        return groups

    def mean_width_ratios(self) -> dict[str, float]:
        """Mean identified/prior width ratio per parameter group."""
        sums: dict[str, list[float]] = {}
        for f in self.fields:
            sums.setdefault(f.group, []).append(f.width_ratio)
        return {g: float(np.mean(v)) for g, v in sums.items()}

    def contains(self, point: ParameterPoint | Mapping[str, np.ndarray]) -> bool:
        """Whether a parameter point (a :class:`~urpc.model.point.ParameterPoint` of the prior
        box, or its older ``dict`` form) lies in the identified box, on every identified
        field."""
        return not self.misses(point)

    def misses(self, point: ParameterPoint | Mapping[str, np.ndarray]) -> list[str]:
        """``body.field`` of the identified fields a point lies outside of."""
        point = ParameterPoint.coerce(point, self.robot.dof)
        missed = []
        for f in self.fields:
            if f.joint:
                values = point.joints
                if values is None:
                    values = self.prior.joint_box(self.robot).nominal
                value = values[JOINT_FIELDS.index(f.field), self.robot.joint_names.index(f.body)]
            else:
                box = self.prior.link_box(f.body)
                value = point.links.get(f.body, box.nominal)[box.fields.index(f.field)]
            if not f.contains(float(value)):
                missed.append(f"{f.body}.{f.field}")
        return missed

    def summary(self) -> dict:
        """A JSON-able summary (what ``urpc identify --json`` prints)."""
        return {
            "robot": self.robot.name,
            "samples": self.samples,
            "data": self.sources,
            "torque_noise": self.noise.tolist(),
            "seconds": self.seconds,
            "linear_programs": self.linear_programs,
            "rank": self.rank,
            "unknowns": self.unknowns,
            "fields": [
                {
                    "body": f.body,
                    "field": f.field,
                    "prior": list(f.prior),
                    "identified": list(f.identified),
                    "width_ratio": f.width_ratio,
                    "constrained": f.constrained,
                }
                for f in self.fields
            ],
            "width_ratios": self.width_ratios(),
            "mean_width_ratios": self.mean_width_ratios(),
            "unconstrained": self.unconstrained,
            "nominal_assumed": self.nominal_assumed,
        }

    def box_text(self, robot_source: str | None = None, schema: str | None = None) -> str:
        """The identified box as an uncertainty file (:mod:`urpc.identify.writer`)."""
        from .writer import box_text

        return box_text(self, robot_source or self.robot.name, schema)

    def box(self) -> ParameterBox:
        """The identified box, read back from :meth:`box_text` as ``urpc check`` reads it."""
        import yaml

        from ..model.uncertainty import parse_uncertainty

        return parse_uncertainty(yaml.safe_load(self.box_text()), self.robot, "<identified>")
