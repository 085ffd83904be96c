"""A starting uncertainty box for any arm: every moving link's URDF values, with chosen widths.

:func:`box_template` writes the text of an uncertainty file (``docs/uncertainty-format.md``) in
which every moving link with a mass gets

* ``mass: 10%`` — the URDF mass ``m`` +- a relative half-width [kg];
* ``com_x/com_y/com_z: +-0.01`` — the URDF center of mass +- an absolute half-width [m];
* ``ixx, iyy, izz`` (and the nonzero products ``ixy, ixz, iyz``): ``20%`` — each entry of the
  URDF inertia about the center of mass +- a relative half-width [kg m^2],

plus, optionally, a payload of mass ``[0, KG]`` fixed to a chosen link. The nominal values stay
the URDF's (relative and offset forms keep them), and each entry carries a comment with the URDF
value and the resulting interval, so the file is ready to run and ready to edit.

**Physical consistency.** A body with mass ``m > 0`` is physical for every center of mass iff its
inertia about the center of mass ``I_C`` has principal moments obeying the triangle inequality,
i.e. ``Sigma(I_C) = tr(I_C)/2 * 1 - I_C`` is positive semi-definite. ``lambda_min(Sigma)`` is
concave in ``I_C`` (``Sigma`` is linear), so its minimum over the inertia box is reached at a
vertex. For a slender link (``I_xx ~ I_yy``, ``I_zz`` small) a 20 % box reaches non-physical
inertias; the template then narrows that link's inertia width to the largest one whose every
vertex is physical (written down to 0.1 %, and said in a comment), so that true plants drawn from
the box (``urpc simulate --true-params sample``, ``urpc campaign``) are rigid bodies.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, did_you_mean
from .inertia import inertia_problem
from .robot import Robot

#: The physical keys of the format with their index in ``physical_coordinates`` order.
_INERTIA_KEYS = (
    ("ixx", 0, 0),
    ("iyy", 1, 1),
    ("izz", 2, 2),
    ("ixy", 0, 1),
    ("ixz", 0, 2),
    ("iyz", 1, 2),
)
#: Column of the trailing comments.
_COMMENT_COLUMN = 30


@dataclass(frozen=True)
class BoxTemplateSettings:
    """The widths of a template box (units in brackets).

    Attributes:
        mass_relative: Half-width of every link mass relative to its URDF value, in ``[0, 1)``.
        com_half_width: Half-width of every center-of-mass coordinate [m], ``>= 0``.
        inertia_relative: Half-width of every inertia entry relative to its URDF value, in
            ``[0, 1)``; narrowed per link where needed to keep every vertex physical.
        payload_link: Link carrying an optional payload, or ``None``.
        payload_mass: Upper end of the payload's mass interval ``[0, payload_mass]`` [kg].
    """

    mass_relative: float = 0.10
    com_half_width: float = 0.01
    inertia_relative: float = 0.20
    payload_link: str | None = None
    payload_mass: float | None = None

    def __post_init__(self) -> None:
        for name in ("mass_relative", "inertia_relative"):
            value = getattr(self, name)
            if not (math.isfinite(value) and 0.0 <= value < 1.0):
                raise InputError(f"{value!r} must lie in [0, 1) (0 % to 99.9 %)", field=name)
        if not (math.isfinite(self.com_half_width) and self.com_half_width >= 0):
            raise InputError(f"{self.com_half_width!r} must be >= 0 [m]", field="com_half_width")
        if (self.payload_link is None) != (self.payload_mass is None):
            raise InputError("give both the payload link and its mass, or neither", field="payload")
        if self.payload_mass is not None and not (
            math.isfinite(self.payload_mass) and self.payload_mass > 0
        ):
            raise InputError(f"{self.payload_mass!r} must be > 0 [kg]", field="payload")


@dataclass(frozen=True)
class LinkTemplate:
    """What the template says about one moving link.

    Attributes:
        link: URDF link name.
        mass: URDF mass [kg].
        com: URDF center of mass in the link frame [m].
        inertia: URDF inertia about the center of mass, link axes [kg m^2].
        inertia_relative: Relative half-width written for its inertia entries (may be narrower
            than asked, see the module docstring); ``None`` if the link is left out.
        note: Why the link is left out or narrowed, or ``""``.
    """

    link: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    inertia_relative: float | None
    note: str = ""


def link_templates(robot: Robot, settings: BoxTemplateSettings) -> list[LinkTemplate]:
    """One :class:`LinkTemplate` per moving link of ``robot``, in URDF order."""
    templates = []
    for name in robot.moving_link_names:
        inertia = robot.link(name).inertia
        mass = float(inertia.mass)
        com = np.asarray(inertia.lever, dtype=float).copy()
        tensor = np.asarray(inertia.inertia, dtype=float).copy()
        if not mass > 0:
            templates.append(LinkTemplate(name, mass, com, tensor, None, "massless in the URDF"))
            continue
        problem = inertia_problem(tensor)
        if problem:
            note = (
                f"its URDF inertia is not physical ({problem}); fix the URDF to make it uncertain"
            )
            templates.append(LinkTemplate(name, mass, com, tensor, None, note))
            continue
        width = physical_inertia_width(tensor, settings.inertia_relative)
        note = ""
        if width < settings.inertia_relative:
            note = (
                f"inertia width narrowed from {_percent(settings.inertia_relative)} to "
                f"{_percent(width)}: a wider box holds non-physical inertias (triangle inequality)"
            )
        templates.append(LinkTemplate(name, mass, com, tensor, width, note))
    return templates


def physical_inertia_width(inertia_at_com: np.ndarray, relative: float) -> float:
    """The largest relative half-width ``s <= relative`` (rounded down to 0.1 %) such that every
    vertex of the box ``I_ij +- s |I_ij|`` is a physical inertia about the center of mass."""

    def physical(scale: float) -> bool:
        return all(_second_moment_psd(v) for v in _vertices(inertia_at_com, scale))

    if physical(relative):
        return relative
    low, high = 0.0, relative
    for _ in range(40):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if physical(middle) else (low, middle)
    return math.floor(low * 1000.0) / 1000.0


def _second_moment_psd(inertia_at_com: np.ndarray) -> bool:
    """Whether ``Sigma = tr(I)/2 * 1 - I`` is positive semi-definite (then ``I`` is too, and its
    principal moments obey the triangle inequality), up to rounding."""
    sigma = 0.5 * np.trace(inertia_at_com) * np.eye(3) - inertia_at_com
    eigenvalues = np.linalg.eigvalsh(sigma)
    return bool(eigenvalues[0] >= -1e-14 * max(float(np.abs(eigenvalues).max()), 1e-300))


def _vertices(tensor: np.ndarray, scale: float):
    entries = [(i, j) for _, i, j in _INERTIA_KEYS if tensor[i, j] != 0.0]
    for signs in itertools.product((-1.0, 1.0), repeat=len(entries)):
        vertex = tensor.copy()
        for (i, j), sign in zip(entries, signs, strict=True):
            vertex[i, j] = vertex[j, i] = tensor[i, j] * (1.0 + sign * scale)
        yield vertex


def box_template(
    robot: Robot,
    settings: BoxTemplateSettings,
    *,
    robot_source: str,
    locked_joints: tuple[str, ...] = (),
    schema: str | None = None,
) -> str:
    """The text of an uncertainty file for ``robot`` with the widths of ``settings``.

    Args:
        robot: The loaded robot (its moving links and URDF inertial values are used).
        settings: Widths and the optional payload.
        robot_source: How the user named the robot (a name or a URDF path), written as ``robot:``.
        locked_joints: Joints locked when loading ``robot`` (said in the header).
        schema: Path or URI of ``uncertainty.schema.json`` for the editor comment on line 1.

    Raises:
        InputError: an unknown or fixed payload link (naming the moving links).
    """
    templates = link_templates(robot, settings)
    lines = []
    if schema is not None:
        lines.append(f"# yaml-language-server: $schema={schema}")
    lines += _header(robot, settings, robot_source, locked_joints)
    lines.append(f"robot: {robot_source}")
    lines.append(
        f"description: starting box written by urpc init ({_settings_text(settings)}); edit me"
    )
    lines.append(_commented("disturbance: unknown", "or a bound on ||d|| [N m] you know, e.g. 10"))
    lines.append("links:")
    left_out = []
    for template in templates:
        if template.inertia_relative is None:
            left_out.append(template)
            continue
        lines += _link_lines(template, settings)
    if left_out:
        lines.append("# Moving links left exact (not listed):")
        for template in left_out:
            lines.append(f"#   {template.link}: {template.note}")
    lines += _payload_lines(robot, settings)
    return "\n".join(lines) + "\n"


def _header(robot, settings, robot_source, locked_joints) -> list[str]:
    lines = [
        f"# Uncertainty box for {robot.name} ({robot.dof} joints), URDF {robot.urdf_path}",
        "# Written by `urpc init`: every moving link's URDF values are the nominal values; the "
        "widths are",
        f"# {_settings_text(settings)}. Format: docs/uncertainty-format.md.",
        "# Edit freely: an entry is `10%` (relative), `+-0.01` (offset), `[lo, hi]` (absolute) or",
        "# a single value; delete an entry to make that parameter exact. The comments give the "
        "URDF",
        "# value and the interval each entry stands for.",
    ]
    if locked_joints:
        lines.append(
            f"# Joints locked when this box was written: {', '.join(locked_joints)} (give the same"
        )
        lines.append("# --lock to urpc check / simulate).")
    lines.append(f"# Check it with: urpc check {robot_source} --uncertainty THIS_FILE")
    return lines


def _link_lines(template: LinkTemplate, settings: BoxTemplateSettings) -> list[str]:
    m, com, tensor = template.mass, template.com, template.inertia
    lines = [_commented(f"  {template.link}:", template.note)]
    if settings.mass_relative > 0:
        r = settings.mass_relative
        lines.append(
            _commented(
                f"    mass: {_percent(r)}",
                f"URDF {_g(m)} kg -> [{_g(m * (1 - r))}, {_g(m * (1 + r))}]",
            )
        )
    if settings.com_half_width > 0:
        w = settings.com_half_width
        for k, axis in enumerate("xyz"):
            lines.append(
                _commented(
                    f"    com_{axis}: +-{_g(w)}",
                    f"URDF {_g(com[k])} m -> [{_g(com[k] - w)}, {_g(com[k] + w)}]",
                )
            )
    r = template.inertia_relative
    if r:
        for key, i, j in _INERTIA_KEYS:
            value = tensor[i, j]
            if value == 0.0:
                continue
            lo, hi = sorted((value * (1 - r), value * (1 + r)))
            lines.append(
                _commented(
                    f"    {key}: {_percent(r)}", f"URDF {_g(value)} kg m^2 -> [{_g(lo)}, {_g(hi)}]"
                )
            )
    if len(lines) == 1:
        lines.append("    mass: 0%                  # every width is 0: this link is exact")
    return lines


def _payload_lines(robot: Robot, settings: BoxTemplateSettings) -> list[str]:
    if settings.payload_link is None:
        return [
            "# A payload (a tool or a grasped object of uncertain mass) would go here, e.g.:",
            "# payload:",
            f"#   link: {robot.moving_link_names[-1]}",
            "#   mass: [0, 2]              # [kg]",
            "#   com_z: [0, 0.1]           # [m], in the frame of `link`",
        ]
    link = settings.payload_link
    if link not in robot.moving_link_names:
        raise InputError(
            f"no moving link '{link}' to carry the payload; "
            + did_you_mean(link, robot.moving_link_names),
            field="payload",
        )
    name = "payload"
    while name in robot.link_names:
        name = f"{name}_"
    return [
        "payload:",
        _commented(f"  name: {name}", "must not be a URDF link name"),
        _commented(f"  link: {link}", "the link it is fixed to"),
        _commented(
            f"  mass: [0, {_g(settings.payload_mass)}]",
            f"[kg]; the controller's nominal payload is the middle, {_g(settings.payload_mass / 2)} kg",
        ),
        "  # com_x, com_y, com_z: [lo, hi]   # [m], in the frame of `link` (default: its origin)",
        "  # ixx, iyy, izz: [0, hi]          # [kg m^2], about the payload's center of mass",
    ]


def _settings_text(settings: BoxTemplateSettings) -> str:
    text = (
        f"mass +-{_percent(settings.mass_relative)}, center of mass +-{_g(settings.com_half_width)} m, "
        f"inertia +-{_percent(settings.inertia_relative)}"
    )
    if settings.payload_link is not None:
        text += f", payload 0-{_g(settings.payload_mass)} kg at {settings.payload_link}"
    return text


def _commented(text: str, comment: str) -> str:
    if not comment:
        return text
    return f"{text.ljust(_COMMENT_COLUMN - 1)} # {comment}"


def _percent(fraction: float) -> str:
    return f"{100.0 * fraction:.4g}%"


def _g(value: float) -> str:
    return f"{value:.6g}"
