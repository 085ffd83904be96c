"""Parameter boxes: which link inertial parameters are uncertain, and by how much.

The file format is documented in ``docs/uncertainty-format.md``. In short::

    disturbance: unknown            # or a bound on ||d|| [N m]
    links:
      link2:                        # a URDF link name
        mass: [5, 10]               # absolute interval [kg]
        com_x: ["+0", "+0.025"]     # offsets from the URDF nominal [m]
        iyy: [0%, +300%]            # relative to the URDF nominal
      link3:
        barycentric:                # or a box on the 10 standard parameters
          m: 10%
    payload:
      name: payload
      link: link2
      mass: [0, 3]
      com_z: [0, 0.05]

A *physical* box bounds ``mass`` [kg], the center of mass ``com_x, com_y, com_z`` in the link frame
[m] and the rotational inertia about the center of mass, in link-frame axes, ``ixx, ixy, ixz, iyy,
iyz, izz`` [kg m^2]. A *barycentric* box bounds the standard parameters about the link origin,
``m, h_x, h_y, h_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz`` (``h = m c``), Pinocchio's order.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pinocchio as pin
import yaml

from ..errors import InputError, did_you_mean
from ..expressions import evaluate
from .robot import Robot, inertia_problem

#: Physical coordinates, stored in this order: mass, CoM in the link frame, inertia about the CoM
#: in Pinocchio's component order (xx, xy, yy, xz, yz, zz).
PHYSICAL_FIELDS = ("mass", "com_x", "com_y", "com_z", "ixx", "ixy", "iyy", "ixz", "iyz", "izz")
#: Standard (barycentric) parameters about the link origin, Pinocchio's order.
BARYCENTRIC_FIELDS = ("m", "h_x", "h_y", "h_z", "I_xx", "I_xy", "I_yy", "I_xz", "I_yz", "I_zz")
UNITS = {
    "mass": "kg", "com_x": "m", "com_y": "m", "com_z": "m",
    "m": "kg", "h_x": "kg m", "h_y": "kg m", "h_z": "kg m",
}  # fmt: skip

Kind = Literal["physical", "barycentric"]


def physical_coordinates(inertia: pin.Inertia) -> np.ndarray:
    """``[mass, com_x, com_y, com_z, ixx, ixy, iyy, ixz, iyz, izz]`` of a spatial inertia."""
    I = np.asarray(inertia.inertia)
    c = np.asarray(inertia.lever)
    return np.array(
        [inertia.mass, c[0], c[1], c[2], I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]]
    )


def inertia_from_physical(values: np.ndarray) -> pin.Inertia:
    """The spatial inertia of physical coordinates (inverse of :func:`physical_coordinates`)."""
    m, cx, cy, cz, ixx, ixy, iyy, ixz, iyz, izz = (float(v) for v in values)
    tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return pin.Inertia(m, np.array([cx, cy, cz]), tensor)


def barycentric_from_physical(values: np.ndarray) -> np.ndarray:
    """Standard parameters ``[m, m c, I_O]`` (about the link origin) of physical coordinates."""
    return np.asarray(inertia_from_physical(values).toDynamicParameters()).copy()


@dataclass(frozen=True, eq=False)
class LinkBox:
    """The uncertain inertial parameters of one link (or payload), in its link frame.

    Attributes:
        link: URDF link name (or payload name).
        kind: ``"physical"`` (coordinates :data:`PHYSICAL_FIELDS`) or ``"barycentric"``
            (coordinates :data:`BARYCENTRIC_FIELDS`).
        nominal: The nominal point, 10 coordinates of ``kind``.
        lower, upper: The box, 10 coordinates of ``kind`` each; exact fields have lower == upper.
    """

    link: str
    kind: Kind
    nominal: np.ndarray
    lower: np.ndarray
    upper: np.ndarray

    @property
    def fields(self) -> tuple[str, ...]:
        return PHYSICAL_FIELDS if self.kind == "physical" else BARYCENTRIC_FIELDS

    @property
    def uncertain(self) -> np.ndarray:
        """Boolean mask of the coordinates with a non-zero width."""
        return self.upper > self.lower

    def inertia(self, values: np.ndarray) -> pin.Inertia:
        """The spatial inertia (link frame) at a point given in this box's coordinates."""
        if self.kind == "physical":
            return inertia_from_physical(values)
        return pin.Inertia.FromDynamicParameters(np.asarray(values, dtype=float))

    def standard_parameters(self, values: np.ndarray) -> np.ndarray:
        """Standard parameters (about the link origin, link frame) at a point of this box."""
        if self.kind == "physical":
            return barycentric_from_physical(values)
        return np.asarray(values, dtype=float).copy()

    @property
    def nominal_inertia(self) -> pin.Inertia:
        return self.inertia(self.nominal)


@dataclass(frozen=True)
class Payload:
    """A rigid body fixed to a link whose parameters are uncertain (a tool, a grasped object)."""

    name: str
    link: str


@dataclass(frozen=True, eq=False)
class ParameterBox:
    """Everything a controller may not know: link parameter intervals and the disturbance bound.

    Attributes:
        links: One :class:`LinkBox` per uncertain link or payload (others are exact).
        payloads: Payload bodies, attached to their links by :meth:`nominal_robot`.
        disturbance_bound: Bound on the input disturbance ``||d||`` [N m], or ``None`` when it is
            unknown (the paper's Theorem 2 case).
        source: The file the box was read from, if any.
    """

    links: tuple[LinkBox, ...]
    payloads: tuple[Payload, ...] = ()
    disturbance_bound: float | None = None
    source: str | None = None
    robot_name: str | None = field(default=None, compare=False)

    def link_box(self, name: str) -> LinkBox:
        for box in self.links:
            if box.link == name:
                return box
        raise KeyError(name)

    @property
    def uncertain_links(self) -> tuple[LinkBox, ...]:
        return tuple(b for b in self.links if b.uncertain.any())

    def nominal_robot(self, robot: Robot) -> Robot:
        """The controller's model: ``robot`` with every payload attached at its nominal point.

        Idempotent: a robot that already carries the payloads is returned unchanged.
        """
        for payload in self.payloads:
            if payload.name not in robot.link_names:
                box = self.link_box(payload.name)
                robot = robot.with_payload(payload.name, payload.link, box.nominal_inertia)
        return robot

    def plant(self, robot: Robot, point: Mapping[str, np.ndarray] | None = None) -> Robot:
        """The robot at a parameter point (link or payload name -> coordinates of its box's kind);
        links not named stay nominal. ``point=None`` gives the nominal robot."""
        robot = self.nominal_robot(robot)
        if not point:
            return robot
        boxed = {b.link: b for b in self.links}
        inertias = {}
        for name, values in point.items():
            values = np.asarray(values, dtype=float)
            # Links without a box are given in physical coordinates.
            inertias[name] = (
                boxed[name].inertia(values) if name in boxed else inertia_from_physical(values)
            )
        return robot.with_link_inertias(inertias)

    def vertex(self, index: int) -> dict[str, np.ndarray]:
        """The ``index``-th vertex of the box over the uncertain coordinates (bit ``k`` of
        ``index`` picks lower (0) or upper (1) of the ``k``-th uncertain coordinate)."""
        point, bit = {}, 0
        for box in self.links:
            values = box.nominal.copy()
            for k in np.flatnonzero(box.uncertain):
                values[k] = box.upper[k] if (index >> bit) & 1 else box.lower[k]
                bit += 1
            point[box.link] = values
        return point

    @property
    def n_uncertain(self) -> int:
        """Number of uncertain coordinates (the box has ``2 ** n_uncertain`` vertices)."""
        return int(sum(int(b.uncertain.sum()) for b in self.links))

    def sample(self, rng: np.random.Generator) -> dict[str, np.ndarray]:
        """A point drawn uniformly from the box (not necessarily physically consistent)."""
        return {b.link: rng.uniform(b.lower, b.upper) for b in self.links}


# ============================================================================ parsing
_PAYLOAD_KEYS = ("name", "link", "nominal", *PHYSICAL_FIELDS, "barycentric")
_TOP_KEYS = ("robot", "disturbance", "links", "payload", "description")


def load_uncertainty(path: str | Path, robot: Robot) -> ParameterBox:
    """Read and validate an uncertainty file for ``robot``.

    Raises:
        InputError: naming the file and the field, for: malformed YAML, an unknown key or link,
            a wrong type, lo > hi, a non-positive mass, a nominal outside its box, a
            non-physical nominal inertia.
    """
    path = Path(path)
    document = read_yaml(path)
    return parse_uncertainty(document, robot, source=str(path))


#: libyaml's safe loader when PyYAML was built with it (5-10x faster), else the Python one.
_SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def read_yaml(path: Path) -> Any:
    """Load a YAML file, turning every I/O or syntax problem into an :class:`InputError`."""
    if not path.is_file():
        raise InputError("file does not exist", source=path)
    try:
        with path.open() as stream:
            return yaml.load(stream, Loader=_SafeLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise InputError(f"YAML syntax error{where}: {problem}", source=path) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the file ({exc})", source=path) from None


def parse_uncertainty(document: Any, robot: Robot, source: str | None = None) -> ParameterBox:
    """Validate an uncertainty document (already parsed YAML) against ``robot``."""
    document = {} if document is None else document
    _require_mapping(document, source, "(top level)")
    _check_keys(document, _TOP_KEYS, source, "")
    disturbance = _parse_disturbance(document.get("disturbance", "unknown"), source)
    links_doc = document.get("links") or {}
    _require_mapping(links_doc, source, "links")
    boxes: list[LinkBox] = []
    payloads: list[Payload] = []
    if "payload" in document and document["payload"] is not None:
        payload, payload_box = _parse_payload(document["payload"], robot, source)
        payloads.append(payload)
        robot = robot.with_payload(payload.name, payload.link, payload_box.nominal_inertia)
        boxes.append(payload_box)
    for name, entry in links_doc.items():
        name = str(name)
        if name not in robot.link_names:
            raise InputError(
                f"unknown link '{name}'; " + did_you_mean(name, robot.moving_link_names),
                source=source,
                field=f"links.{name}",
            )
        link = robot.link(name)
        if link.joint_index == 0:
            raise InputError(
                f"link '{name}' is fixed to the base, so its parameters do not enter the dynamics; "
                f"uncertain links must be moving: {', '.join(robot.moving_link_names)}",
                source=source,
                field=f"links.{name}",
            )
        boxes.append(parse_link_box(entry, name, link.inertia, source, f"links.{name}"))
    return ParameterBox(
        links=tuple(boxes),
        payloads=tuple(payloads),
        disturbance_bound=disturbance,
        source=source,
        robot_name=robot.name,
    )


def _parse_disturbance(value: Any, source: str | None) -> float | None:
    if isinstance(value, str) and value.strip().lower() == "unknown":
        return None
    number = parse_number(value, source, "disturbance", "a bound on ||d|| [N m] or 'unknown'")
    if not np.isfinite(number) or number < 0:
        raise InputError(
            f"{value!r} is not a valid bound: give a finite number >= 0 [N m] or 'unknown'",
            source=source,
            field="disturbance",
        )
    return number


def _parse_payload(doc: Any, robot: Robot, source: str | None) -> tuple[Payload, LinkBox]:
    _require_mapping(doc, source, "payload")
    _check_keys(doc, _PAYLOAD_KEYS, source, "payload.")
    if "link" not in doc:
        raise InputError(
            "a payload needs the link it is fixed to; " + did_you_mean("", robot.moving_link_names),
            source=source,
            field="payload.link",
        )
    link = str(doc["link"])
    if link not in robot.link_names or robot.link(link).joint_index == 0:
        raise InputError(
            f"unknown or fixed link '{link}'; " + did_you_mean(link, robot.moving_link_names),
            source=source,
            field="payload.link",
        )
    name = str(doc.get("name", "payload"))
    if name in robot.link_names:
        raise InputError(
            f"the payload name '{name}' is already a link name; choose another",
            source=source,
            field="payload.name",
        )
    entry = {k: v for k, v in doc.items() if k not in ("name", "link", "nominal")}
    if "barycentric" in entry:
        raise InputError(
            "a payload box is physical (mass, com_*, i**); barycentric payloads are not supported",
            source=source,
            field="payload.barycentric",
        )
    # The payload's nominal: explicit values, else the middle of each absolute interval.
    nominal_doc = doc.get("nominal") or {}
    _require_mapping(nominal_doc, source, "payload.nominal")
    _check_keys(nominal_doc, PHYSICAL_FIELDS, source, "payload.nominal.")
    center = np.zeros(10)
    for k, key in enumerate(PHYSICAL_FIELDS):
        if key in nominal_doc:
            center[k] = parse_number(nominal_doc[key], source, f"payload.nominal.{key}", "a number")
        elif key in entry:
            lo, hi = _interval(entry[key], None, source, f"payload.{key}")
            center[k] = 0.5 * (lo + hi)
    if "mass" not in entry:
        raise InputError(
            "a payload needs a mass interval [kg]", source=source, field="payload.mass"
        )
    box = parse_link_box(
        entry, name, inertia_from_physical(center), source, "payload", allow_zero_mass=True
    )
    return Payload(name, link), box


def parse_link_box(
    entry: Any,
    name: str,
    nominal_inertia: pin.Inertia,
    source: str | None,
    prefix: str,
    allow_zero_mass: bool = False,
) -> LinkBox:
    _require_mapping(entry, source, prefix)
    if "barycentric" in entry:
        extra = [k for k in entry if k != "barycentric"]
        if extra:
            raise InputError(
                f"a link box is either physical or barycentric, not both (also found {extra})",
                source=source,
                field=f"{prefix}.barycentric",
            )
        sub = entry["barycentric"]
        _require_mapping(sub, source, f"{prefix}.barycentric")
        _check_keys(sub, BARYCENTRIC_FIELDS, source, f"{prefix}.barycentric.")
        kind: Kind = "barycentric"
        keys, values, doc, fprefix = (
            BARYCENTRIC_FIELDS,
            np.asarray(nominal_inertia.toDynamicParameters(), dtype=float).copy(),
            sub,
            f"{prefix}.barycentric",
        )
    else:
        _check_keys(entry, (*PHYSICAL_FIELDS, "barycentric"), source, f"{prefix}.")
        kind = "physical"
        keys, values, doc, fprefix = (
            PHYSICAL_FIELDS,
            physical_coordinates(nominal_inertia),
            entry,
            prefix,
        )
    lower, upper = values.copy(), values.copy()
    for k, key in enumerate(keys):
        if key in doc:
            lower[k], upper[k] = _interval(doc[key], values[k], source, f"{fprefix}.{key}")
            if not lower[k] <= values[k] <= upper[k] and not np.isclose(
                values[k], np.clip(values[k], lower[k], upper[k]), rtol=1e-12, atol=1e-15
            ):
                raise InputError(
                    f"the nominal value {values[k]:.6g} lies outside the box "
                    f"[{lower[k]:.6g}, {upper[k]:.6g}]; widen the interval or change the URDF",
                    source=source,
                    field=f"{fprefix}.{key}",
                )
    mass_index = 0
    min_mass = 0.0 if allow_zero_mass else np.finfo(float).tiny
    if lower[mass_index] < min_mass or (not allow_zero_mass and lower[mass_index] <= 0):
        raise InputError(
            f"mass interval [{lower[mass_index]:.6g}, {upper[mass_index]:.6g}] kg must be "
            + ("non-negative" if allow_zero_mass else "strictly positive (m > 0)"),
            source=source,
            field=f"{fprefix}.{keys[mass_index]}",
        )
    box = LinkBox(name, kind, values, lower, upper)
    _check_nominal_physical(box, source, fprefix)
    return box


def _check_nominal_physical(box: LinkBox, source: str | None, prefix: str) -> None:
    inertia = box.nominal_inertia
    if box.kind == "physical":
        tensor = np.asarray(inertia.inertia)
    else:
        # Barycentric: I_C = I_O - m S(c)^T S(c); physical iff the pseudo-inertia is PSD.
        tensor = np.asarray(inertia.inertia) if inertia.mass > 0 else np.zeros((3, 3))
    problem = inertia_problem(tensor)
    if problem:
        raise InputError(
            f"the nominal inertia of '{box.link}' is not physical: {problem}",
            source=source,
            field=f"{prefix}",
        )


# ---------------------------------------------------------------------------- value grammar
def parse_number(value: Any, source: str | None, fieldname: str, expected: str) -> float:
    if isinstance(value, bool):
        raise InputError(f"{value!r} is not a number; expected {expected}", source, fieldname)
    if isinstance(value, int | float):
        return float(value)
    if isinstance(value, str):
        try:
            return evaluate(value)
        except ValueError:
            pass
    raise InputError(f"{value!r} is not a number; expected {expected}", source, fieldname)


_INTERVAL_HELP = (
    "an interval [lo, hi], a relative width '10%', an offset '+-0.05', or a one-sided range "
    "such as [0%, +100%] or ['+0', '+0.025']"
)


def _interval(
    value: Any, nominal: float | None, source: str | None, fieldname: str
) -> tuple[float, float]:
    """Parse one interval entry around ``nominal`` (``None``: only absolute forms allowed)."""

    def bad(why: str) -> InputError:
        return InputError(f"{why}; expected {_INTERVAL_HELP}", source, fieldname)

    def relative_allowed() -> None:
        if nominal is None:
            raise bad(f"{value!r} is relative, but this field has no nominal to be relative to")

    def end(item: Any) -> float:
        if isinstance(item, str):
            text = item.strip()
            if text.endswith("%"):
                relative_allowed()
                return nominal * (
                    1.0 + parse_number(text[:-1], source, fieldname, "a percentage") / 100
                )
            if text[:1] in "+-" and not text.startswith("+-"):
                relative_allowed()
                return nominal + parse_number(text, source, fieldname, "an offset")
        return parse_number(item, source, fieldname, "a number")

    if isinstance(value, list | tuple):
        if len(value) != 2:
            raise bad(f"{value!r} has {len(value)} entries, not 2")
        lo, hi = end(value[0]), end(value[1])
    elif isinstance(value, str) and value.strip().endswith("%"):
        relative_allowed()
        text = value.strip()[:-1].strip()
        text = text[2:] if text.startswith("+-") else text
        fraction = parse_number(text, source, fieldname, "a percentage") / 100
        if fraction < 0:
            raise bad(f"{value!r} is a negative width")
        lo, hi = nominal - abs(nominal) * fraction, nominal + abs(nominal) * fraction
    elif isinstance(value, str) and value.strip().startswith("+-"):
        relative_allowed()
        width = parse_number(value.strip()[2:], source, fieldname, "an offset")
        if width < 0:
            raise bad(f"{value!r} is a negative width")
        lo, hi = nominal - width, nominal + width
    elif isinstance(value, int | float | str) and not isinstance(value, bool):
        lo = hi = parse_number(value, source, fieldname, _INTERVAL_HELP)
    else:
        raise bad(f"{value!r} is not an interval")
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise bad(f"{value!r} has a non-finite end")
    if lo > hi:
        raise InputError(
            f"lower end {lo:.6g} is greater than upper end {hi:.6g}; write [lo, hi] with lo <= hi",
            source,
            fieldname,
        )
    return float(lo), float(hi)


def _require_mapping(value: Any, source: str | None, fieldname: str) -> None:
    if not isinstance(value, Mapping):
        raise InputError(
            f"expected a mapping (key: value lines), got {type(value).__name__} {value!r}",
            source,
            fieldname,
        )


def _check_keys(doc: Mapping, valid: tuple[str, ...], source: str | None, prefix: str) -> None:
    for key in doc:
        if str(key) not in valid:
            raise InputError(
                f"unknown key '{key}'; " + did_you_mean(str(key), valid),
                source,
                f"{prefix}{key}",
            )


# ============================================================================ parameter points
def load_parameter_point(
    path: str | Path, robot: Robot, box: ParameterBox
) -> dict[str, np.ndarray]:
    """Read a parameter-point file (a true plant) for ``robot`` and ``box``.

    The file uses the names of the uncertainty format, with single numbers::

        links:
          link2: {mass: 10, com_x: 0.525, iyy: 20/12}
        payload: {mass: 2.0, com_z: 0.03}

    Links not listed stay at their nominal values. Returns link or payload name -> coordinates
    (in the kind of that link's box, physical for links without a box), for
    :meth:`ParameterBox.plant`.
    """
    path = Path(path)
    document = read_yaml(path) or {}
    source = str(path)
    _require_mapping(document, source, "(top level)")
    _check_keys(document, ("links", "payload", "description", "robot"), source, "")
    nominal_robot = box.nominal_robot(robot)
    point: dict[str, np.ndarray] = {}
    entries = dict(document.get("links") or {})
    _require_mapping(entries, source, "links")
    if document.get("payload") is not None:
        if not box.payloads:
            raise InputError("this uncertainty box has no payload", source=source, field="payload")
        entries[box.payloads[0].name] = document["payload"]
    for name, values in entries.items():
        name = str(name)
        if name not in nominal_robot.moving_link_names:
            raise InputError(
                f"unknown link '{name}'; " + did_you_mean(name, nominal_robot.moving_link_names),
                source=source,
                field=f"links.{name}",
            )
        try:
            link_box = box.link_box(name)
        except KeyError:
            nominal = physical_coordinates(nominal_robot.link(name).inertia)
            link_box = LinkBox(name, "physical", nominal, nominal, nominal)
        _require_mapping(values, source, f"links.{name}")
        coordinates = link_box.nominal.copy()
        for key, value in values.items():
            if key == "barycentric" and link_box.kind == "barycentric":
                _require_mapping(value, source, f"links.{name}.barycentric")
                for bkey, bvalue in value.items():
                    _check_keys({bkey: 0}, BARYCENTRIC_FIELDS, source, f"links.{name}.barycentric.")
                    k = BARYCENTRIC_FIELDS.index(bkey)
                    coordinates[k] = parse_number(
                        bvalue, source, f"links.{name}.{bkey}", "a number"
                    )
                continue
            _check_keys({key: 0}, link_box.fields, source, f"links.{name}.")
            k = link_box.fields.index(key)
            coordinates[k] = parse_number(value, source, f"links.{name}.{key}", "a number")
        if coordinates[0] <= 0 and name not in [p.name for p in box.payloads]:
            raise InputError("mass must be > 0", source=source, field=f"links.{name}.mass")
        problem = inertia_problem(np.asarray(link_box.inertia(coordinates).inertia))
        if problem:
            raise InputError(
                f"the inertia of '{name}' is not physical: {problem}",
                source=source,
                field=f"links.{name}",
            )
        point[name] = coordinates
    return point


def outside_box(box: ParameterBox, point: Mapping[str, np.ndarray]) -> list[str]:
    """Names ``link.field`` of the coordinates of ``point`` that lie outside ``box``."""
    outside = []
    for name, values in point.items():
        try:
            link_box = box.link_box(name)
        except KeyError:
            continue
        for k in np.flatnonzero(
            (values < link_box.lower - 1e-12) | (values > link_box.upper + 1e-12)
        ):
            outside.append(f"{name}.{link_box.fields[k]}")
    return outside
