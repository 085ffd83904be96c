"""The identified box as an uncertainty file (``docs/uncertainty-format.md``), with comments.

Every identified interval is written as an absolute ``[lo, hi]`` rounded *outward* to 9
significant digits (decimal rounding toward minus and plus infinity, so the written interval
contains the computed one), with a comment giving the prior interval and the width ratio, or
saying that the data did not constrain the field. A link's nominal value is its URDF value, which
the format requires inside the interval: where the identified interval excludes it, the interval
is widened to reach it and the comment says so (the box stays sound, a superset). The payload and
the drives get a ``nominal:`` inside their identified intervals.
"""

from __future__ import annotations

from decimal import ROUND_CEILING, ROUND_FLOOR, Context, Decimal

import numpy as np

from ..formats.uncertainty import PHYSICAL_FIELDS
from ..model.inertia import inertia_problem
from ..model.joint_dynamics import JOINT_FIELDS
from ..model.parameter_box import inertia_from_physical

_COLUMN = 34
_DIGITS = 9


def outward(lo: float, hi: float) -> tuple[str, str]:
    """Decimal strings of ``lo`` rounded down and ``hi`` rounded up (9 significant digits);
    each parses to a double on the outer side of the original (rounding is monotone)."""
    down = Context(prec=_DIGITS, rounding=ROUND_FLOOR)
    up = Context(prec=_DIGITS, rounding=ROUND_CEILING)
    return _text(down.plus(Decimal(lo))), _text(up.plus(Decimal(hi)))


def _text(value: Decimal) -> str:
    text = format(value.normalize(), "g")
    return "0" if text in ("-0", "0E+1") else text


def _interval(lo: float, hi: float, prior: tuple[float, float] | None = None) -> str:
    """``[lo, hi]`` rounded outward; an end at the prior's end is written as the prior's exact
    value (the prior contains every consistent value, so no rounding slack is needed there)."""
    a, b = outward(lo, hi)
    if prior is not None:
        if lo <= prior[0]:
            a = repr(float(prior[0]))
        if hi >= prior[1]:
            b = repr(float(prior[1]))
    return f"[{a}, {b}]"


def _ends(box, k: int) -> tuple[float, float]:
    return float(box.lower[k]), float(box.upper[k])


def _g(value: float) -> str:
    return f"{value:.6g}"


def _commented(text: str, comment: str) -> str:
    return f"{text.ljust(_COLUMN - 1)} # {comment}" if comment else text


def _comment(field) -> str:
    prior = f"prior [{_g(field.prior[0])}, {_g(field.prior[1])}]"
    if not field.constrained:
        return f"{prior} kept: not constrained by the data"
    return f"{prior}; identified, {100 * field.width_ratio:.3g} % of the prior width"


def box_text(result, robot_source: str, schema: str | None = None) -> str:
    """The text of the identified box (module docstring)."""
    prior, robot = result.prior, result.robot
    lines = [] if schema is None else [f"# yaml-language-server: $schema={schema}"]
    noise = result.noise
    noise_text = _g(noise[0]) if np.all(noise == noise[0]) else ", ".join(_g(v) for v in noise)
    lines += [
        f"# Identified box for {robot.name} ({robot.dof} joints), written by `urpc identify` from",
        f"# {result.samples} samples ({result.sources}) with torque noise bound {noise_text} N m.",
        f"# Prior: {prior.source or '(given in the API)'}. Every parameter vector of the prior box",
        "# whose rigid bodies explain every sample and joint within the noise lies in this box",
        "# (linear programs with HiGHS, outward-rounded; docs/identification.md). Fields the data",
        "# did not constrain keep their prior interval and say so.",
    ]
    if result.nominal_assumed:
        lines.append(
            "# Payload mode: taken at their nominal values during identification (intervals "
            "copied from the prior): " + ", ".join(result.nominal_assumed)
        )
    lines.append(f"# Check it with: urpc check {robot_source} --uncertainty THIS_FILE")
    lines.append(f"robot: {robot_source}")
    lines.append(f"description: identified by urpc identify from {result.samples} samples")
    disturbance = prior.disturbance_bound
    lines.append(f"disturbance: {'unknown' if disturbance is None else repr(float(disturbance))}")
    identified = {(f.body, f.field): f for f in result.fields}
    payloads = {p.name: p for p in prior.payloads}
    link_lines = []
    for box in prior.links:
        if box.link in payloads:
            continue
        entries = _body_entries(box, identified, widen_to_nominal=True)
        if not entries:
            continue
        key = "barycentric" if box.kind == "barycentric" else None
        link_lines.append(f"  {box.link}:")
        if key:
            link_lines.append(f"    {key}:")
        indent = "      " if key else "    "
        link_lines += [indent + line for line in entries]
    lines.append("links:" if link_lines else "links: {}")
    lines += link_lines
    for payload in prior.payloads:
        lines += _payload_lines(result, prior.link_box(payload.name), payload, identified)
    if prior.joints is not None:
        lines += _joint_lines(result, identified)
    return "\n".join(lines) + "\n"


def _body_entries(box, identified, widen_to_nominal: bool) -> list[str]:
    entries = []
    for k, name in enumerate(box.fields):
        if not box.uncertain[k]:
            continue
        field = identified.get((box.link, name))
        if field is None:  # not identified (payload mode): the prior interval as it was
            entries.append(
                _commented(
                    f"{name}: {_interval(*_ends(box, k), _ends(box, k))}", "prior, unchanged"
                )
            )
            continue
        lo, hi = field.identified
        comment = _comment(field)
        nominal = float(box.nominal[k])
        if widen_to_nominal and not lo <= nominal <= hi:
            comment += f"; widened to the URDF value {_g(nominal)} (the format's nominal)"
            lo, hi = min(lo, nominal), max(hi, nominal)
        entries.append(_commented(f"{name}: {_interval(lo, hi, field.prior)}", comment))
    return entries


def _payload_lines(result, box, payload, identified) -> list[str]:
    lines = [
        "payload:",
        f"  name: {payload.name}",
        f"  link: {payload.link}",
    ]
    nominal = {}
    center = box.nominal.copy()
    for k, name in enumerate(PHYSICAL_FIELDS):
        field = identified.get((box.link, name))
        if field is not None:
            lo, hi = field.identified
            lines.append(_commented(f"  {name}: {_interval(lo, hi, field.prior)}", _comment(field)))
            center[k] = 0.5 * (lo + hi)
        elif box.uncertain[k]:
            lines.append(
                _commented(
                    f"  {name}: {_interval(*_ends(box, k), _ends(box, k))}", "prior, unchanged"
                )
            )
        elif box.nominal[k] != 0.0 or name == "mass":
            lines.append(f"  {name}: {box.nominal[k]!r}")
    # The nominal: the middle of each interval if it is a rigid body, else the prior's nominal
    # moved into the intervals, else the feasible point of the last linear program.
    candidates = [center]
    clipped = box.nominal.copy()
    for k, name in enumerate(PHYSICAL_FIELDS):
        field = identified.get((box.link, name))
        if field is not None:
            clipped[k] = min(max(clipped[k], field.identified[0]), field.identified[1])
    candidates.append(clipped)
    for candidate in candidates:
        if candidate[0] >= 0 and not inertia_problem(
            np.asarray(inertia_from_physical(candidate).inertia)
        ):
            nominal = {
                name: float(candidate[k])
                for k, name in enumerate(PHYSICAL_FIELDS)
                if (box.link, name) in identified or box.uncertain[k]
            }
            break
    if nominal:
        parts = ", ".join(f"{k}: {v!r}" for k, v in nominal.items())
        lines.append(_commented(f"  nominal: {{{parts}}}", "the controller's nominal payload"))
    return lines


def _joint_lines(result, identified) -> list[str]:
    robot = result.robot
    joints = result.prior.joint_box(robot)
    urdf = np.vstack([np.zeros(robot.dof), robot.urdf_dynamics])
    lines = ["joints:"]
    written = False
    for column, joint in enumerate(joints.joint_names):
        entries, nominal = [], {}
        for row, key in enumerate(JOINT_FIELDS):
            field = identified.get((joint, key))
            if field is not None:
                lo, hi = field.identified
                entries.append(
                    _commented(f"    {key}: {_interval(lo, hi, field.prior)}", _comment(field))
                )
                nominal[key] = 0.5 * (lo + hi)
            elif joints.uncertain[row, column]:
                lo, hi = joints.lower[row, column], joints.upper[row, column]
                entries.append(
                    _commented(f"    {key}: {_interval(lo, hi, (lo, hi))}", "prior, unchanged")
                )
                nominal[key] = float(joints.nominal[row, column])
            elif joints.nominal[row, column] != urdf[row, column]:
                entries.append(f"    {key}: {float(joints.nominal[row, column])!r}")
        if not entries:
            continue
        written = True
        lines.append(f"  {joint}:")
        lines += entries
        if nominal:
            parts = ", ".join(f"{k}: {v!r}" for k, v in nominal.items())
            lines.append(f"    nominal: {{{parts}}}")
    if not written:  # a joints: section with every drive at the URDF's values
        lines.append(f"  {joints.joint_names[0]}: {{}}")
    return lines
