"""The certificate cache (urpc.control.certificate_cache, certificate_key): a hit is the
certificate a fresh computation gives, any change of what the certificate depends on misses, and
a cache that cannot be used never fails a run.

Every test has its own empty cache folder (the autouse fixture of conftest.py)."""

from __future__ import annotations

import dataclasses
import json
import math
import sqlite3
import warnings

import numpy as np
import pytest

import urpc
from urpc.control import certificate as certificate_module
from urpc.control.certificate import Certificate, Condition, certify
from urpc.control.certificate_cache import (
    FILE_NAME,
    CertificateCache,
    cached_certify,
    default_directory,
)
from urpc.control.certificate_key import (
    NoKey,
    canonical,
    certificate_key,
    trajectory_fingerprint,
)
from urpc.trajectories import PaperTrajectory, QuinticTrajectory, SinusoidTrajectory
from urpc.trajectory_sources import from_samples

#: Short enough that one certificate of the RR arm takes about half a second.
DURATION = 0.2
DISTURBANCE = 10.0


@pytest.fixture(scope="module")
def base(rr, rr_box):
    """The base configuration: RR arm, shipped box, implicit law at 1 kHz."""
    return {
        "controller": urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3),
        "trajectory": PaperTrajectory(),
        "duration": DURATION,
        "disturbance_bound": DISTURBANCE,
    }


def _call(function, configuration, **kwargs):
    """``function(controller, trajectory, duration=..., ...)`` of a configuration."""
    c = configuration
    return function(
        c["controller"], c["trajectory"], duration=c["duration"],
        disturbance_bound=c["disturbance_bound"], cells=c.get("cells"),
        **({"require_efforts": True} if c.get("require_efforts") else {}), **kwargs,
    )  # fmt: skip


def _certify(configuration, **kwargs):
    return _call(cached_certify, configuration, **kwargs)


def _fresh(configuration):
    return _call(certify, configuration)


def _key(configuration):
    return _call(certificate_key, configuration)


# ============================================================================ the record
def test_to_dict_and_from_dict_round_trip_exactly_with_non_finite_numbers():
    certificate = Certificate(
        False, 1e-2, math.inf, 8.7e-4, 1e-3, "implicit",
        (
            Condition("ultimate bound below epsilon", False, math.inf, 1e-2, "shorten"),
            Condition("disturbance bound given", False, math.nan, math.nan, "give d"),
            Condition("Theorem 2: phi_I > 0", True, 1e6, 0.0, "choose phi_I > 0"),
        ),
        {"margin": -math.inf, "cells": 27.0, "slow_cell": 3, "dominant_term": "deviation",
         "term_shares": {"mismatch": 0.25, "deviation": 0.75}},
    )  # fmt: skip
    data = certificate.to_dict()
    assert data["epsilon_floor"] is None and data["figures"]["margin"] is None  # JSON-safe
    assert data["non_finite"] == {
        "/epsilon_floor": "inf",
        "/conditions/0/value": "inf",
        "/conditions/1/value": "nan",
        "/conditions/1/limit": "nan",
        "/figures/margin": "-inf",
    }
    text = json.dumps(data, allow_nan=False)
    again = Certificate.from_dict(json.loads(text))
    assert again == certificate
    assert again.to_dict() == data
    assert math.isinf(again.epsilon_floor) and again.epsilon_floor > 0
    assert math.isnan(again.conditions[1].value) and again.figures["margin"] == -math.inf
    assert type(again.figures["slow_cell"]) is int and type(again.figures["cells"]) is float
    assert again.sample_period == 1e-3 and again.conditions == certificate.conditions


def test_from_dict_names_a_missing_field():
    data = Certificate(True, 1e-2, 0.0, 0.0, None, "continuous", ()).to_dict()
    del data["epsilon_floor"]
    with pytest.raises(urpc.InputError, match="epsilon_floor"):
        Certificate.from_dict(data)


def test_a_computed_certificate_round_trips(base):
    certificate = _fresh(base)
    assert Certificate.from_dict(json.loads(json.dumps(certificate.to_dict()))) == certificate


# ============================================================================ hits and misses
def test_a_hit_is_the_certificate_a_fresh_computation_gives(base, counted):
    first = _certify(base)
    assert not first.from_cache and len(counted) == 1 and first.key is not None
    second = _certify(base)
    assert second.from_cache and len(counted) == 1  # not computed again
    assert second.key == first.key
    fresh = _fresh(base)  # computed now, not read from anywhere
    assert second.certificate == fresh
    assert second.certificate.to_dict() == fresh.to_dict()
    assert second.describe().startswith(f"cached (key {first.key[:12]}")
    assert first.describe().startswith("computed in ") and first.key[:12] in first.describe()


def _variants(rr, rr_box, tmp_path):
    """One configuration per key ingredient, each differing from ``base`` in that one."""
    T = 1e-3
    box_d = dataclasses.replace(rr_box, disturbance_bound=10.0)
    wider = urpc.parse_uncertainty(
        {"links": {"link2": {"mass": [5, 11], "com_x": [0.5, 0.525], "iyy": [5 / 12, 20 / 12]}}},
        rr,
    )
    urdf = tmp_path / "rr.urdf"
    urdf.write_text(
        (rr.urdf_path.read_text()).replace('<origin xyz="1.0 0 0"', '<origin xyz="1.01 0 0"')
    )
    longer = urpc.load_robot(urdf)
    longer_box = urpc.load_uncertainty(rr_box.source, longer)
    synth = urpc.synthesize
    return {
        "Kr": {"controller": synth(rr, rr_box, 1e-2, sample_period=T, Kr=31.0)},
        "phi_I": {"controller": synth(rr, rr_box, 1e-2, sample_period=T, phi_I=2e6)},
        "kappa_P": {"controller": synth(rr, rr_box, 1e-2, sample_period=T, kappa_P=3.0)},
        "epsilon": {"controller": synth(rr, rr_box, 2e-2, sample_period=T, Kr=30.0)},
        "sample_period": {"controller": synth(rr, rr_box, 1e-2, sample_period=5e-4)},
        "law": {"controller": synth(rr, rr_box, 1e-2, sample_period=T, sampled_law="paper")},
        "method": {"controller": synth(rr, rr_box, 1e-2, sample_period=T, method="hull")},
        "box": {"controller": synth(rr, wider, 1e-2, sample_period=T)},
        "box disturbance": {"controller": synth(rr, box_d, 1e-2, sample_period=T)},
        "robot": {"controller": synth(longer, longer_box, 1e-2, sample_period=T)},
        "trajectory amplitude": {"trajectory": PaperTrajectory((math.pi / 4, -math.pi / 9))},
        "trajectory kind": {
            "trajectory": SinusoidTrajectory((0.0, 0.0), (math.pi / 4, -math.pi / 8), 0.25)
        },
        "duration": {"duration": DURATION + 0.05},
        "disturbance": {"disturbance_bound": 9.0},
        "cells": {"cells": 20},
        "require_efforts": {"require_efforts": True},
    }


def test_changing_any_one_ingredient_misses_and_computes_afresh(
    base, rr, rr_box, tmp_path, counted
):
    variants = _variants(rr, rr_box, tmp_path)
    base_key = _key(base)
    keys = {"base": base_key}
    for name, change in variants.items():
        keys[name] = _key({**base, **change})
    assert len(set(keys.values())) == len(keys), keys  # every ingredient changes the key
    _certify(base)
    assert len(counted) == 1
    for name in ("Kr", "epsilon", "sample_period", "box", "trajectory amplitude", "duration",
                 "disturbance"):  # fmt: skip
        outcome = _certify({**base, **variants[name]})
        assert not outcome.from_cache, name
    assert len(counted) == 8  # each one computed
    assert _certify(base).from_cache and len(counted) == 8  # the base is still there


def test_equal_configurations_share_the_key(base, rr, rr_box, tmp_path):
    """What the certificate does not read leaves the key alone: the box's file, a copy of the
    trajectory, a float written as an integer or a numpy scalar."""
    copy = tmp_path / "box.yaml"
    copy.write_text(open(rr_box.source).read())
    same_box = urpc.load_uncertainty(copy, rr)
    again = {
        "controller": urpc.synthesize(rr, same_box, np.float64(1e-2), sample_period=1e-3),
        "trajectory": PaperTrajectory([math.pi / 4, -math.pi / 8]),
        "duration": DURATION,
        "disturbance_bound": int(DISTURBANCE),
    }
    assert _key(again) == _key(base)
    assert canonical(0.1) == canonical(np.float64(0.1)) != canonical(np.nextafter(0.1, 1.0))


def test_trajectory_fingerprints():
    """Samples and spline for a file reference, points and times for a quintic."""
    t = np.linspace(0.0, 1.0, 11)
    q = np.stack([np.sin(t), np.cos(t)], axis=1)
    a, b = from_samples(t, q), from_samples(t, q.copy())
    c = from_samples(t, q + 1e-9)
    assert a.fingerprint() is not None
    assert trajectory_fingerprint(a) == trajectory_fingerprint(b) != trajectory_fingerprint(c)
    quintic = QuinticTrajectory([[0, 0], [1, 1]], [0, 1])
    other = QuinticTrajectory([[0, 0], [1, 1]], [0, 2])
    assert trajectory_fingerprint(quintic) != trajectory_fingerprint(other)


class _Overriding(PaperTrajectory):
    """Inherits PaperTrajectory.fingerprint but changes what the certificate reads."""

    def evaluate(self, t):
        q, qd, qdd = super().evaluate(t)
        return 2 * q, 2 * qd, 2 * qdd

    def jerk_bound(self, start, stop):
        return 2 * super().jerk_bound(start, stop)


class _Declared(_Overriding):
    def fingerprint(self):
        return {"amplitude": self.amplitude, "scale": 2.0}


def test_a_reference_without_its_own_fingerprint_is_computed_every_time(base, counted):
    overriding = {**base, "trajectory": _Overriding()}
    with pytest.raises(NoKey, match="_Overriding overrides evaluate"):
        _key(overriding)
    first, second = _certify(overriding), _certify(overriding)
    assert not first.from_cache and not second.from_cache and len(counted) == 2
    assert first.key is None and "not cached" in first.describe()
    assert "fingerprint" in first.describe()
    declared = {**base, "trajectory": _Declared()}
    assert _key(declared) != _key(base)
    assert not _certify(declared).from_cache and _certify(declared).from_cache


def test_refresh_computes_again_and_replaces_the_record(base, counted):
    _certify(base)
    again = _certify(base, refresh=True)
    assert not again.from_cache and len(counted) == 2
    assert _certify(base).from_cache and len(counted) == 2


def test_no_cache_reads_and_writes_nothing(base, counted, certificate_cache_dir):
    assert not _certify(base, cache=False).from_cache
    assert not _certify(base, cache=False).from_cache and len(counted) == 2
    assert not (certificate_cache_dir / FILE_NAME).exists()


# ============================================================================ never in the way
def test_a_corrupt_cache_file_degrades_to_computing(base, counted, certificate_cache_dir):
    (certificate_cache_dir / FILE_NAME).write_bytes(b"this is not a database" * 100)
    with pytest.warns(UserWarning) as caught:
        outcome = _certify(base)
    assert len(caught) == 1  # one warning, though neither reading nor writing works
    assert "cannot be read (file is not a database)" in str(caught[0].message)
    assert not outcome.from_cache and outcome.certificate == _fresh(base)
    assert "not cached: the cache cannot be written" in outcome.describe()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # warned once per file, not at every run
        assert not _certify(base).from_cache
    assert len(counted) == 2


def test_an_unwritable_cache_folder_degrades_to_computing(base, counted, tmp_path, monkeypatch):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("URPC_CACHE_DIR", str(blocker / "cache"))
    with pytest.warns(UserWarning, match="certificate cache .* cannot be"):
        outcome = _certify(base)
    assert not outcome.from_cache and outcome.certificate == _fresh(base)
    assert len(counted) == 1


def test_a_record_that_is_no_certificate_is_computed_again_and_replaced(
    base, counted, certificate_cache_dir
):
    first = _certify(base)
    with sqlite3.connect(certificate_cache_dir / FILE_NAME) as connection:
        connection.execute("UPDATE certificates SET certificate = '{\"certified\": 1}'")
    with pytest.warns(UserWarning, match="no certificate"):
        again = _certify(base)
    assert not again.from_cache and again.certificate == first.certificate
    assert _certify(base).from_cache and len(counted) == 2


def test_the_cache_file_is_sqlite_in_wal_mode(base, certificate_cache_dir):
    _certify(base)
    cache = CertificateCache()
    assert cache.directory == certificate_cache_dir and len(cache) == 1
    with sqlite3.connect(certificate_cache_dir / FILE_NAME) as connection:
        assert connection.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        description, version = connection.execute(
            "SELECT description, certificate_version FROM certificates"
        ).fetchone()
    assert description.startswith("rr_planar: implicit law, T = 0.001 s, epsilon = 0.01")
    assert version == certificate_module.CERTIFICATE_VERSION


def test_the_default_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("URPC_CACHE_DIR", str(tmp_path / "mine"))
    assert default_directory() == tmp_path / "mine"
    monkeypatch.delenv("URPC_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert default_directory() == tmp_path / "xdg" / "urpc"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_directory() == tmp_path / "home" / ".cache" / "urpc"


def test_a_bad_cache_argument_is_named(base):
    with pytest.raises(urpc.InputError, match="cache"):
        _certify(base, cache="yes")
