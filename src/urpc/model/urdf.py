"""Reading a URDF beyond what Pinocchio keeps: per-link inertias (each URDF link, even when
Pinocchio merges links joined by fixed joints), joint-type checks, and locking joints."""

from __future__ import annotations

import sys
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import InputError, did_you_mean
from .inertia import inertia_problem

#: URDF joint types accepted.
_URDF_SUPPORTED = ("revolute", "continuous", "prismatic", "fixed")


def lock_joints(
    model: pin.Model, locked: Mapping[str, float | None], urdf: Path
) -> tuple[pin.Model, dict[str, float]]:
    """``model`` with the named joints removed (Pinocchio's ``buildReducedModel``), each fixed at
    its position [rad or m]; ``None`` means 0. A continuous joint (Pinocchio's ``cos, sin`` pair)
    is fixed at the angle. Returns the reduced model and the positions used.

    Raises:
        InputError: an unknown joint, a position outside the joint's limits (no silent clipping),
            a joint type that cannot be locked.
    """
    names = [model.names[j] for j in range(1, model.njoints)]
    reference = pin.neutral(model)
    ids, positions = [], {}
    for name, value in locked.items():
        if name not in names:
            raise InputError(
                f"cannot lock unknown joint '{name}'; " + did_you_mean(name, names),
                source=urdf,
                field="locked_joints",
            )
        j = model.getJointId(name)
        joint = model.joints[j]
        position = 0.0 if value is None else float(value)
        if not np.isfinite(position):
            raise InputError(
                f"cannot lock joint '{name}' at {position}: give a finite position [rad or m]",
                source=urdf,
                field=f"locked_joints.{name}",
            )
        if joint.nq == 2 and joint.nv == 1:  # continuous: (cos, sin) of the angle
            reference[joint.idx_q] = np.cos(position)
            reference[joint.idx_q + 1] = np.sin(position)
        elif joint.nq == 1:
            lo = model.lowerPositionLimit[joint.idx_q]
            hi = model.upperPositionLimit[joint.idx_q]
            if not lo <= position <= hi:
                given = (
                    "0 (a lock given by name only locks at 0)"
                    if value is None
                    else f"{position:.6g}"
                )
                raise InputError(
                    f"cannot lock joint '{name}' at {given}: outside its limits "
                    f"[{lo:.6g}, {hi:.6g}] [rad or m]; give a position inside them (the API's "
                    f"locked_joints={{'{name}': {np.clip(0.0, lo, hi):.6g}}} or a scenario's "
                    f"locked_joints: {{{name}: ...}})",
                    source=urdf,
                    field=f"locked_joints.{name}",
                )
            reference[joint.idx_q] = position
        else:
            raise InputError(
                f"joint '{name}' ({joint.shortname()}) cannot be locked: only revolute, "
                "prismatic and continuous joints can",
                source=urdf,
                field="locked_joints",
            )
        ids.append(j)
        positions[name] = position
    return pin.buildReducedModel(model, ids, reference), positions


def check_tree(root, path: Path) -> None:
    """Refuse a closed kinematic loop: a link that is the child of two joints, or links that
    form a cycle (no root, or links no root reaches). urpc models open chains (trees)."""
    parents: dict[str, list[str]] = {}
    children: dict[str, list[str]] = {}
    for joint in root.findall("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            continue  # yourdfpy names the malformed joint
        parents.setdefault(child.get("link"), []).append(joint.get("name"))
        children.setdefault(parent.get("link"), []).append(child.get("link"))
    for link, joints in parents.items():
        if len(joints) > 1:
            raise InputError(
                f"closed kinematic loop: link '{link}' is the child of joints "
                + " and ".join(f"'{j}'" for j in joints)
                + "; urpc supports open chains (every link has at most one parent joint)",
                source=path,
                field=f"joint.{joints[1]}",
            )
    links = [link.get("name") for link in root.findall("link")]
    reached = [link for link in links if link not in parents]  # the roots
    for link in reached:  # reached grows while it is walked
        reached.extend(c for c in children.get(link, ()) if c not in reached)
    cycle = [link for link in links if link not in reached and link in parents]
    if cycle:
        raise InputError(
            "closed kinematic loop: the links "
            + ", ".join(f"'{link}'" for link in cycle)
            + " form a cycle of joints ("
            + ", ".join(f"'{parents[link][0]}'" for link in cycle)
            + ") that no root link reaches; urpc supports open chains",
            source=path,
            field=f"joint.{parents[cycle[0]][0]}",
        )


#: The numeric attributes of a URDF, by element path below <link> or <joint>.
_NUMBERS = {
    "link": {
        "inertial/origin": ("xyz", "rpy"),
        "inertial/mass": ("value",),
        "inertial/inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
    },
    "joint": {
        "origin": ("xyz", "rpy"),
        "axis": ("xyz",),
        "limit": ("lower", "upper", "effort", "velocity"),
        "dynamics": ("damping", "friction"),
    },
}


def check_numbers(root, path: Path) -> None:
    """Refuse a numeric attribute that is not numbers (``<mass value="heavy"/>``, an ``xyz``
    with two entries), naming the element, instead of the parsers' bare conversion error."""
    for tag, elements in _NUMBERS.items():
        for element in root.findall(tag):
            name = element.get("name")
            for where, attributes in elements.items():
                found = element.find(where)
                if found is None:
                    continue
                for attribute in attributes:
                    text = found.get(attribute)
                    if text is None:
                        continue
                    count = 3 if attribute in ("xyz", "rpy") else 1
                    try:
                        values = [float(x) for x in text.split()]
                    except ValueError:
                        values = []
                    if len(values) != count:
                        what = "3 numbers" if count == 3 else "a number"
                        raise InputError(
                            f'{attribute}="{text}" of <{where.split("/")[-1]}> in {tag} '
                            f"'{name}' is not {what}",
                            source=path,
                            field=f"{tag}.{name}.{where.replace('/', '.')}.{attribute}",
                        )


def check_link_names(root, path: Path) -> None:
    """Refuse a joint whose parent or child is not a link of the file (the tree check would
    otherwise call it a closed loop)."""
    links = [link.get("name") for link in root.findall("link")]
    for joint in root.findall("joint"):
        for end in ("parent", "child"):
            element = joint.find(end)
            if element is None or element.get("link") in links:
                continue  # yourdfpy names a missing element
            raise InputError(
                f"joint '{joint.get('name')}' names unknown link '{element.get('link')}' as its "
                f"{end}; " + did_you_mean(str(element.get("link")), links),
                source=path,
                field=f"joint.{joint.get('name')}.{end}",
            )


def mimic_joints(path: Path) -> dict[str, str]:
    """``{follower: leader}`` for every moving joint with a ``<mimic joint=...>`` element (a fixed
    joint never moves, so its mimic element has no effect: talos's gripper carries such ones)."""
    import xml.etree.ElementTree as ElementTree

    mimics = {}
    for joint in ElementTree.parse(path).getroot().findall("joint"):
        mimic = joint.find("mimic")
        if mimic is not None and joint.get("type") != "fixed":
            mimics[joint.get("name")] = mimic.get("joint")
    return mimics


def check_mimic_joints(path: Path, locked: Mapping[str, float]) -> None:
    """Refuse a mimic joint unless it and the joint it mimics are both locked: urpc would model
    them as two independent degrees of freedom, which the real mechanism is not. The error names
    the first such pair and gives one ``--lock`` list that covers every pair (with the joints
    already locked), so that a URDF with several grippers is fixed in one step."""
    pairs = [
        (follower, leader)
        for follower, leader in mimic_joints(path).items()
        if not (follower in locked and leader in locked)
    ]
    if not pairs:
        return
    follower, leader = pairs[0]
    joints = list(dict.fromkeys([*locked, *(j for pair in pairs for j in pair[::-1])]))
    more = len(pairs) - 1
    others = (
        f" ({more} more mimic pair{'s are' if more > 1 else ' is'} in that list)" if more else ""
    )
    raise InputError(
        f"joint '{follower}' mimics joint '{leader}' (<mimic> in the URDF); urpc does not "
        "model mimic joints and would simulate two independent joints: lock both "
        f"(--lock {','.join(joints)}, or locked_joints={joints}){others} or "
        "remove the <mimic> element",
        source=path,
        field=f"joint.{follower}.mimic",
    )


def robot_display_name(robot: str) -> str:
    """The name to show for ``robot`` (a URDF path or a robot name): a URDF file's ``<robot
    name>`` (read from its first element only), else the file stem; a name as given."""
    import xml.etree.ElementTree as ElementTree

    path = Path(robot)
    if path.suffix.lower() != ".urdf" or not path.is_file():
        return path.stem if path.suffix.lower() == ".urdf" else robot
    try:
        for _, element in ElementTree.iterparse(path, events=("start",)):
            return element.get("name") or path.stem
    except (ElementTree.ParseError, OSError):
        pass
    return path.stem


#: Largest URDF read [bytes] (the shipped and example-robot-data arms are 5-100 kB).
MAX_URDF_BYTES = 8 << 20


def yourdfpy_module():
    """``yourdfpy``, imported with Ctrl-C held back: its import pulls in trimesh, whose optional
    imports catch every exception, a ``KeyboardInterrupt`` too, and go on half-imported. A
    SIGINT meanwhile is only noted, and handed to the previous handler once the import is done
    (the default one raises ``KeyboardInterrupt`` then). A Python handler runs in the main
    thread whichever thread the signal reaches (a mask would not do: BLAS's threads take it)."""
    import signal
    import threading

    previous = signal.getsignal(signal.SIGINT)
    if (
        "yourdfpy" in sys.modules
        or threading.current_thread() is not threading.main_thread()
        or not callable(previous)  # ignored, or the C default: nothing to hold back
    ):
        import yourdfpy

        return yourdfpy
    noted: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, frame: noted.append(signum))
    try:
        import yourdfpy
    finally:
        signal.signal(signal.SIGINT, previous)
    if noted:
        previous(signal.SIGINT, None)
    return yourdfpy


def read_urdf_inertials(path: Path) -> dict[str, pin.Inertia]:
    """Per-link inertias from the URDF (yourdfpy), in link frames, with joint-type checks."""
    import xml.etree.ElementTree as ElementTree

    yourdfpy = yourdfpy_module()

    # A hostile size first (a URDF is text of a few hundred kB at most), then well-formedness:
    # the C++ URDF parser prints its own lines on stderr otherwise.
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise InputError(f"cannot read the file ({exc.strerror})", source=path) from None
    if size > MAX_URDF_BYTES:
        raise InputError(
            f"the file is too large for a URDF ({size / 2**20:.3g} MiB; at most "
            f"{MAX_URDF_BYTES // 2**20} MiB): meshes belong in their own files",
            source=path,
        )
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as exc:
        raise InputError(f"malformed XML ({exc})", source=path) from None
    except OSError as exc:
        raise InputError(f"cannot read the file ({exc})", source=path) from None
    if root.tag != "robot" or not root.get("name"):
        raise InputError(
            f"not a URDF: the root element must be <robot name=...>, found <{root.tag}>",
            source=path,
        )
    check_numbers(root, path)
    check_link_names(root, path)
    # Before yourdfpy and Pinocchio: a link with two parents crashes the C++ parser.
    check_tree(root, path)
    for joint in root.findall("joint"):
        kind = joint.get("type")
        if kind in ("revolute", "prismatic") and joint.find("limit") is None:
            raise InputError(
                f"joint '{joint.get('name')}' is {kind} but has no <limit> (the URDF format "
                'requires <limit lower=".." upper=".." effort=".." velocity=".."/>); add it, or '
                "make the joint continuous",
                source=path,
                field=f"joint.{joint.get('name')}.limit",
            )
        limit = joint.find("limit")
        name = joint.get("name")
        axis = joint.find("axis")
        if kind in ("revolute", "continuous", "prismatic") and axis is not None:
            if not any(float(x) for x in axis.get("xyz", "1 0 0").split()):
                raise InputError(
                    f"joint '{name}' has the axis xyz=\"{axis.get('xyz')}\": a {kind} joint "
                    'needs a non-zero axis (a unit vector, e.g. xyz="0 0 1")',
                    source=path,
                    field=f"joint.{name}.axis.xyz",
                )
        # Bounds and dissipation are >= 0 (Pinocchio's own messages name neither joint nor field).
        for tag, attributes, what in (
            ("limit", ("effort", "velocity"), "{} limit ({:g}); the {} limit is a bound >= 0"),
            (
                "dynamics",
                ("damping", "friction"),
                "{} ({:g}); a joint's {} is >= 0 (it dissipates)",
            ),
        ):
            element = joint.find(tag)
            for attribute in attributes if element is not None and kind != "fixed" else ():
                value = element.get(attribute)
                if value is not None and float(value) < 0:
                    raise InputError(
                        f"joint '{name}' has a negative "
                        + what.format(attribute, float(value), attribute),
                        source=path,
                        field=f"joint.{name}.{tag}.{attribute}",
                    )
        if kind in ("revolute", "prismatic"):
            lower, upper = (float(limit.get(end, "0")) for end in ("lower", "upper"))
            if lower > upper:
                raise InputError(
                    f"joint '{joint.get('name')}' has limit lower {lower:g} above upper "
                    f"{upper:g}; write lower <= upper",
                    source=path,
                    field=f"joint.{joint.get('name')}.limit",
                )
    try:
        urdf = yourdfpy.URDF.load(
            str(path), load_meshes=False, build_scene_graph=False, load_collision_meshes=False
        )
    except Exception as exc:
        raise InputError(f"not a readable URDF ({exc})", source=path) from None
    if urdf.robot is None or not urdf.robot.links:
        raise InputError("the URDF defines no link", source=path)
    for joint in urdf.robot.joints:
        if joint.type not in _URDF_SUPPORTED:
            raise InputError(
                f"joint '{joint.name}' has type '{joint.type}'; urpc supports fixed-base arms with "
                f"joint types {', '.join(_URDF_SUPPORTED)}",
                source=path,
                field=f"joint.{joint.name}.type",
            )
    inertias = {}
    for link in urdf.robot.links:
        inertial = link.inertial
        if inertial is None:
            inertias[link.name] = pin.Inertia.Zero()
            continue
        mass = float(inertial.mass if inertial.mass is not None else 0.0)
        origin = np.eye(4) if inertial.origin is None else np.asarray(inertial.origin, dtype=float)
        tensor = np.zeros((3, 3)) if inertial.inertia is None else np.asarray(inertial.inertia)
        rotated = origin[:3, :3] @ tensor @ origin[:3, :3].T
        field = f"link.{link.name}.inertial"
        if not np.isfinite(mass) or mass < 0:
            raise InputError(
                f"mass {mass} must be a finite number >= 0 [kg]", source=path, field=field
            )
        # Real URDFs often carry tiny triangle-inequality violations on massless frames, so only
        # an inertia that is not positive semi-definite is refused here; the uncertainty file
        # checks the full physical consistency of the links it makes uncertain.
        problem = inertia_problem(rotated, triangle=False)
        if problem:
            raise InputError(f"non-physical inertia: {problem}", source=path, field=field)
        try:
            inertias[link.name] = pin.Inertia(mass, origin[:3, 3].copy(), rotated)
        except RuntimeError:  # Pinocchio needs every principal moment >= 0, with no tolerance
            moments = np.linalg.eigvalsh(rotated)
            raise InputError(
                f"non-physical inertia: principal moment {moments[0]:.3g} is negative (principal "
                f"moments {', '.join(f'{m:.3g}' for m in moments)}), which Pinocchio refuses: make every "
                "principal moment >= 0",
                source=path,
                field=field,
            ) from None
    return inertias
