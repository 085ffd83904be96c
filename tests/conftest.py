"""Shared fixtures: robots are loaded once per test session (loading parses URDFs); every test
gets its own certificate cache folder (``URPC_CACHE_DIR``), so that the suite never writes into
the user's cache and no test sees another's certificates."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from urpc.model.robot import load_robot
from urpc.model.uncertainty import load_parameter_point, load_uncertainty

ROOT = Path(__file__).resolve().parents[1]
RR_DIR = ROOT / "robots" / "rr_planar"
PANDA_FINGERS = ["panda_finger_joint1", "panda_finger_joint2"]


@pytest.fixture(scope="session", autouse=True)
def session_certificate_cache_dir(tmp_path_factory):
    """``URPC_CACHE_DIR`` for the whole session, set before any module or session fixture runs
    (a module fixture that runs a campaign computes a certificate before a test's own fixture)."""
    with pytest.MonkeyPatch.context() as patch:
        folder = tmp_path_factory.mktemp("urpc-cache-session")
        patch.setenv("URPC_CACHE_DIR", str(folder))
        yield folder


@pytest.fixture(autouse=True)
def certificate_cache_dir(session_certificate_cache_dir, tmp_path_factory, monkeypatch) -> Path:
    """A fresh, empty certificate cache folder for each test (``URPC_CACHE_DIR``; outside the
    test's ``tmp_path``, which some tests list)."""
    folder = tmp_path_factory.mktemp("urpc-cache")
    monkeypatch.setenv("URPC_CACHE_DIR", str(folder))
    return folder


@pytest.fixture(scope="session")
def rr():
    return load_robot("rr_planar")


@pytest.fixture(scope="session")
def rr_box(rr):
    return load_uncertainty(RR_DIR / "uncertainty.yaml", rr)


@pytest.fixture(scope="session")
def rr_true_point(rr, rr_box):
    return load_parameter_point(RR_DIR / "true_parameters.yaml", rr, rr_box)


@pytest.fixture(scope="session")
def ur5():
    return load_robot("ur5")


@pytest.fixture(scope="module")
def rr_rig():
    """The paper's arm for the robot-loop tests: the URDF robot, its shipped true plant and a
    1 kHz interval controller."""
    robot = load_robot("rr_planar")
    from urpc.control.synthesis import synthesize

    box = load_uncertainty("rr_planar", robot)
    plant = box.plant(robot, load_parameter_point("rr_planar", robot, box))
    return robot, plant, synthesize(robot, box, 1e-2, sample_period=1e-3)


@pytest.fixture
def counted(monkeypatch):
    """The certificates actually computed (calls of urpc.control.certificate.certify), for the
    tests of the certificate cache."""
    from urpc.control import certificate as certificate_module

    calls = []
    real = certificate_module.certify

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(certificate_module, "certify", counting)
    return calls


@pytest.fixture(scope="session")
def panda():
    return load_robot("panda", locked_joints=PANDA_FINGERS)


#: A one-joint robot: a cart on a prismatic joint (constant scalar inertia, 2 kg).
SLIDER = """<robot name="slider"><link name="base"/>
<link name="cart"><inertial><origin xyz="0 0 0"/><mass value="2.0"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
<joint name="x" type="prismatic"><parent link="base"/><child link="cart"/><axis xyz="1 0 0"/>
<limit lower="-1" upper="1" effort="100" velocity="2"/></joint></robot>"""


def rr_closed_form(q, qd, m2, lc2, I2, m1=10.0, lc1=0.5, I1=10 / 12, l1=1.0, g0=9.81):
    """The textbook RR arm (Spong et al. Sec. 7.4), written independently of Pinocchio:
    returns M, C (Christoffel), g."""
    c2 = np.cos(q[1])
    M11 = m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * c2) + I1 + I2
    M12 = m2 * (lc2**2 + l1 * lc2 * c2) + I2
    M22 = m2 * lc2**2 + I2
    h = -m2 * l1 * lc2 * np.sin(q[1])
    C = np.array([[h * qd[1], h * (qd[0] + qd[1])], [-h * qd[0], 0.0]])
    g1 = (m1 * lc1 + m2 * l1) * g0 * np.cos(q[0]) + m2 * lc2 * g0 * np.cos(q[0] + q[1])
    g2 = m2 * lc2 * g0 * np.cos(q[0] + q[1])
    return np.array([[M11, M12], [M12, M22]]), C, np.array([g1, g2])
