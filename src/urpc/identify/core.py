"""``urpc.identify(...)``: the tightest enclosing box of the parameters consistent with the data.

The feasible set (:mod:`urpc.identify.problem`) is a polytope in the unknowns; its enclosing box is
found by two linear programs per bound (:mod:`urpc.identify.lp`). The file's fields are bounded
from it soundly:

* ``mass``, ``I_C`` entries and the drive parameters are variables of the polytope: their ranges
  are linear programs;
* ``com_k = h_k / m`` is bounded twice, as the range of the relaxation variable ``c_k`` and as
  the exact range of the linear-fractional ``h_k / m`` over the polytope (Charnes-Cooper, when
  the identified mass is bounded away from 0); both are sound, their intersection is kept.

Then the McCormick envelopes are rebuilt over the tightened bounds and the programs solved again
(``rounds``, default 2): each round's box contains every consistent parameter vector, so the next
round's envelopes are still valid and tighter.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..errors import InputError, did_you_mean
from ..formats.uncertainty import PHYSICAL_FIELDS
from ..model.joint_dynamics import JOINT_FIELDS
from ..model.parameter_box import ParameterBox
from ..model.robot import Robot
from .data import DerivativeBounds, Samples, load_samples
from .envelopes import LinkBounds
from .lp import InfeasibleData
from .problem import COM, INERTIA_C, Problem
from .result import FieldBound, Identification

#: Parameter groups of the width report.
GROUPS = {"mass": "mass", "com_x": "com", "com_y": "com", "com_z": "com"}


def identify(
    robot: Robot,
    prior: ParameterBox,
    data,
    torque_noise,
    *,
    payload: str | None = None,
    derivative_bounds: DerivativeBounds | None = None,
    rounds: int = 2,
    rigid_body_cuts: bool = True,
    standard_parameters: bool = False,
) -> Identification:
    """The tightest enclosing box of the parameters of ``prior`` consistent with ``data``.

    Args:
        robot: The robot, as loaded (``urpc.load_robot``).
        prior: The prior box (``urpc.load_uncertainty``); its uncertain link, payload and drive
            parameters are the unknowns, every other parameter is known.
        data: :class:`~urpc.identify.data.Samples`, or data file paths (CSV/NPZ).
        torque_noise: Bound ``N`` of ``|tau_measured - tau_true|`` per sample [N m], a number or
            one per joint.
        payload: Payload mode: the link carrying the payload; only the payload's parameters are
            unknown, every other parameter is taken at its nominal value (said in
            :attr:`Identification.nominal_assumed`).
        derivative_bounds: Bounds for derivatives estimated from ``q`` (files without ``qd``).
        rounds: Rounds of envelope tightening (>= 1).
        rigid_body_cuts: Add the rigid-body cuts (every true link is a rigid body).
        standard_parameters: Also bound each body's 10 standard parameters.

    Raises:
        InputError: bad data or noise, an unknown payload link, data inconsistent with the prior
            box and the noise bound (:class:`~urpc.identify.lp.InfeasibleData`).
    """
    start = time.perf_counter()
    noise = _noise(torque_noise, robot)
    if isinstance(data, Samples):
        samples, sources = data, data.source
    else:
        paths = [data] if isinstance(data, str | Path) else list(data)
        samples = load_samples(paths, robot.dof, derivative_bounds, robot.joint_names)
        sources = ", ".join(str(p) for p in paths)
    if samples.dof != robot.dof:
        raise InputError(
            f"the samples have {samples.dof} joints, robot {robot.name} has {robot.dof} "
            f"({', '.join(robot.joint_names)})",
            source=samples.source,
            field="q",
        )
    if not isinstance(rounds, int) or rounds < 1:
        raise InputError(f"rounds must be an integer >= 1, got {rounds!r}", field="rounds")
    unknown_links, assumed, identify_joints = _unknowns(robot, prior, payload)
    problem = Problem(robot, prior, samples, noise, unknown_links, identify_joints, rigid_body_cuts)
    if problem.size == 0:
        raise InputError(
            "the prior box has no uncertain parameter, so there is nothing to identify",
            source=prior.source,
            field="links",
        )
    solves = 0
    ranges: dict = {}
    try:
        for round_index in range(rounds):
            polytope = problem.polytope()
            final = round_index == rounds - 1
            ranges = _round(problem, polytope, final=final, standard=standard_parameters)
            solves += polytope.solves
    except InfeasibleData as exc:  # name the data
        raise InfeasibleData(exc.detail, source=sources, field="torque_noise") from None
    fields = _fields(problem, ranges)
    rank = _rank(problem)
    result = Identification(
        robot=robot,
        prior=prior,
        fields=fields,
        samples=samples.count,
        seconds=0.0,
        linear_programs=solves,
        noise=noise,
        sources=sources,
        standard=ranges.get("standard", {}),
        nominal_assumed=assumed,
        rank=rank,
        unknowns=10 * len(problem.unknowns) + len(problem.joint_unknowns),
        payload_nominal=ranges.get("feasible", {}),
    )
    result.seconds = time.perf_counter() - start
    return result


def _noise(torque_noise, robot: Robot) -> np.ndarray:
    noise = np.asarray(torque_noise, dtype=float).reshape(-1)
    if noise.size == 1:
        noise = np.full(robot.dof, float(noise[0]))
    if noise.size != robot.dof or not np.all(np.isfinite(noise)) or np.any(noise < 0):
        raise InputError(
            f"the torque noise bound must be one number >= 0 or {robot.dof} (one per joint: "
            f"{', '.join(robot.joint_names)}), got {np.asarray(torque_noise).tolist()}",
            field="torque_noise",
        )
    return noise


def _unknowns(robot: Robot, prior: ParameterBox, payload: str | None):
    if payload is None:
        return None, [], True
    links = [p for p in prior.payloads if p.link == payload]
    if not links and payload not in robot.link_names:
        raise InputError(
            f"'{payload}' is not a link of {robot.name}; "
            + did_you_mean(payload, robot.moving_link_names),
            field="payload",
        )
    if not links:
        if not prior.payloads:
            raise InputError(
                f"payload mode needs a prior box with a payload: section at '{payload}' (mass, "
                f"center of mass and inertia intervals); this box has none (urpc init "
                f"{robot.name} --payload {payload}:KG writes one)",
                source=prior.source,
                field="payload",
            )
        valid = [p.link for p in prior.payloads]
        raise InputError(
            f"the prior box has no payload at '{payload}'; " + did_you_mean(payload, valid),
            source=prior.source,
            field="payload.link",
        )
    name = links[0].name
    assumed = []
    for box in prior.uncertain_links:
        if box.link != name:
            assumed += [
                f"{box.link}.{f}" for f, u in zip(box.fields, box.uncertain, strict=True) if u
            ]
    if prior.joints is not None:
        joints = prior.joints
        assumed += [joints.name(r, c) for r, c in np.argwhere(joints.uncertain)]
    return [name], assumed, False


def _round(problem: Problem, polytope, final: bool, standard: bool) -> dict:
    """One round: ranges of every reported quantity; tightens the problem's bounds."""
    out: dict = {"links": {}, "joints": [], "standard": {}, "feasible": {}}
    for unknown in problem.unknowns:
        name = unknown.box.link
        if not unknown.physical:
            lo, hi = np.empty(10), np.empty(10)
            for k in range(10):
                if unknown.box.uncertain[k]:
                    lo[k], hi[k] = polytope.range(problem.objective(unknown, k), f"{name}.{k}")
                else:
                    lo[k] = hi[k] = unknown.box.nominal[k]
            lo, hi = np.maximum(lo, unknown.box.lower), np.minimum(hi, unknown.box.upper)
            out["links"][name] = (lo, hi)
            out["standard"][name] = (lo, hi)
            continue
        bounds = problem.bounds[name]
        mass = _tight(polytope.range(problem.objective(unknown, 0), f"{name}.mass"), bounds.mass)
        h = [
            _tight(polytope.range(problem.objective(unknown, 1 + k), f"{name}.h"), bounds.h[k])
            for k in range(3)
        ]
        com = []
        for k in range(3):
            interval = bounds.com[k]
            if interval[1] > interval[0]:
                interval = _tight(polytope.range(problem.objective(unknown, COM + k)), interval)
                if mass[0] > 0:
                    ratio = polytope.ratio_range(
                        problem.objective(unknown, 1 + k), problem.objective(unknown, 0), mass[0]
                    )
                    if ratio is not None:
                        interval = _tight(ratio, interval)
            com.append(interval)
        inertia = []
        for k in range(6):
            interval = bounds.inertia[k]
            if interval[1] > interval[0]:
                interval = _tight(
                    polytope.range(problem.objective(unknown, INERTIA_C + k)), interval
                )
            inertia.append(interval)
        problem.bounds[name] = LinkBounds(mass, com, inertia, h)
        out["links"][name] = (
            np.array([mass[0], *(c[0] for c in com), *(i[0] for i in inertia)]),
            np.array([mass[1], *(c[1] for c in com), *(i[1] for i in inertia)]),
        )
        if final and standard:
            lo, hi = np.empty(10), np.empty(10)
            for k in range(10):
                lo[k], hi[k] = polytope.range(problem.objective(unknown, k))
            out["standard"][name] = (lo, hi)
    for n, (row, column) in enumerate(problem.joint_unknowns):
        joints = problem.joints
        prior = (float(joints.lower[row, column]), float(joints.upper[row, column]))
        out["joints"].append(_tight(polytope.range(problem.joint_objective(n)), prior))
    return out


def _tight(found: tuple[float, float], prior: tuple[float, float]) -> tuple[float, float]:
    """``found`` intersected with ``prior`` (both contain every consistent value)."""
    lo, hi = max(found[0], prior[0]), min(found[1], prior[1])
    if lo > hi:  # only by the outward margins' failure; keep the sound union's overlap point
        lo = hi = 0.5 * (lo + hi)
    return float(lo), float(hi)


def _fields(problem: Problem, ranges: dict) -> list[FieldBound]:
    fields = []
    payload_names = {p.name for p in problem.prior.payloads}
    for unknown in problem.unknowns:
        box = unknown.box
        lo, hi = ranges["links"][box.link]
        for k, name in enumerate(box.fields):
            if not box.uncertain[k]:
                continue
            fields.append(
                FieldBound(
                    box.link,
                    name,
                    (float(box.lower[k]), float(box.upper[k])),
                    (float(lo[k]), float(hi[k])),
                    payload=box.link in payload_names,
                )
            )
    joints = problem.joints
    for (row, column), identified in zip(problem.joint_unknowns, ranges["joints"], strict=True):
        fields.append(
            FieldBound(
                joints.joint_names[column],
                JOINT_FIELDS[row],
                (float(joints.lower[row, column]), float(joints.upper[row, column])),
                identified,
                joint=True,
            )
        )
    return fields


def _rank(problem: Problem) -> int:
    """Numerical rank of the stacked regressor of the unknowns, columns scaled by the prior
    widths of the standard parameters (the identifiable combinations)."""
    W, _ = problem.regressor_matrix()
    if W.size == 0:
        return 0
    scale = []
    for unknown in problem.unknowns:
        lo, hi = problem._standard_box(unknown)
        scale.extend(0.5 * (hi - lo))
    for row, column in problem.joint_unknowns:
        scale.append(0.5 * (problem.joints.upper[row, column] - problem.joints.lower[row, column]))
    W = W * np.asarray(scale)[None, :]
    singular = np.linalg.svd(W, compute_uv=False)
    if singular.size == 0 or singular[0] == 0:
        return 0
    return int(np.sum(singular > 1e-9 * singular[0]))


__all__ = ["FieldBound", "Identification", "identify", "PHYSICAL_FIELDS"]
