"""The certificate of a scenario: its controller, reference, duration and disturbance.

:func:`urpc.control.certificate.certify` works on a synthesized controller; a scenario supplies
everything else (the reference it tracks, for how long, and the disturbance bound its plant sees).
The certificate is computed once per configuration and read back from the certificate cache
after that (:mod:`urpc.control.certificate_cache`; ``cache=False`` computes it without the
cache, ``refresh=True`` computes it again and replaces the record). Runs and campaigns record the
outcome with :func:`certificate_fields` (or :func:`guarantee_of`, which also says where the
certificate came from); ``certify=False`` skips it, and the fields say so.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..control.base import Controller
from ..control.certificate import Certificate
from ..control.certificate_cache import CachedCertificate, CertificateCache, cached_certify
from ..control.certificate_report import most_exceeded
from ..control.interval import IntervalPassivityController
from ..errors import InputError
from .certification_progress import CertificateProgress

#: ``not_certified`` of a run whose certificate was skipped (``--no-certify``, ``certify=False``).
NOT_COMPUTED = "not computed (--no-certify)"


@dataclass(frozen=True)
class Guarantee:
    """What a run records about its guarantee, and where the certificate came from.

    Attributes:
        fields: ``certified`` (``True``, ``False``, or ``None`` when not computed),
            ``certificate`` (its fields, or ``None``) and ``not_certified`` (one line saying why,
            or ``None``): the same whether the certificate was computed or read from the cache.
        source: How the certificate was obtained, or ``None`` (no certificate computed).
    """

    fields: dict[str, Any]
    source: CachedCertificate | None = None

    @property
    def source_line(self) -> str | None:
        """``cached (key 1a2b3c4d5e6f; ...)``, ``computed in 2.1 s, cached (key ...)``, or
        ``None``."""
        return None if self.source is None else self.source.describe()


def certify_setup(
    setup,
    controller: Controller,
    *,
    cache: bool | CertificateCache = True,
    refresh: bool = False,
    progress: Any = None,
) -> Certificate:
    """The certificate of ``controller`` (an interval controller) in a built scenario ``setup``
    (read from the cache when it holds it; module docstring)."""
    return cached_setup(
        setup, controller, cache=cache, refresh=refresh, progress=progress
    ).certificate


def cached_setup(
    setup,
    controller: Controller,
    *,
    cache: bool | CertificateCache = True,
    refresh: bool = False,
    cells: int | None = None,
    require_efforts: bool = False,
    progress: Any = None,
    announce: bool = True,
) -> CachedCertificate:
    """:func:`certify_setup` with where the certificate came from.

    Args:
        setup: A built scenario (:func:`urpc.studies.scenario.build`).
        controller: Its interval controller.
        cache: ``True`` (the default folder), a :class:`CertificateCache`, or ``False``.
        refresh: Compute even when cached, and replace the record.
        cells: The first cells of time (:func:`urpc.control.certificate.certify`; default
            chosen from the reference's speed).
        require_efforts: The commanded torque within the effort limits as a condition
            (:func:`urpc.control.certificate.certify`).
        progress: ``True`` for a status line on stderr while it runs and one closing line
            (``certificate: computed in 2.1 s, ...``); a callable receiving those lines; ``None``.
        announce: Give ``progress`` the closing line (a command that prints it in its own
            output passes ``False``).

    Raises:
        InputError: not an interval controller; a reference the certificate cannot bound.
    """
    if not isinstance(controller, IntervalPassivityController):
        raise InputError(
            f"only the interval controller has a certificate, not '{controller.name}'",
            field="controller",
        )
    scenario = setup.scenario
    with CertificateProgress(progress) as report:
        outcome = cached_certify(
            controller,
            setup.trajectory,
            duration=scenario.duration,
            disturbance_bound=scenario.disturbance,
            actuation_delay=scenario.actuation_delay,
            cells=cells,
            require_efforts=require_efforts,
            progress=report.stage if report.active else None,
            cache=cache,
            refresh=refresh,
        )
        report.finish(f"certificate: {outcome.describe()}" if announce else None)
    return outcome


def guarantee_of(
    setup,
    controller: Controller,
    *,
    certify: bool = True,
    cache: bool | CertificateCache = True,
    refresh: bool = False,
    progress: Any = None,
) -> Guarantee:
    """The :class:`Guarantee` of a run of ``controller`` in ``setup``: the certificate's fields
    (:func:`certificate_fields`) and its source. ``certify=False``: not computed, ``certified``
    is ``None`` and ``not_certified`` is :data:`NOT_COMPUTED`."""
    if not certify:
        return Guarantee({"certified": None, "certificate": None, "not_certified": NOT_COMPUTED})
    if not isinstance(controller, IntervalPassivityController):
        why = f"not certified: the {controller.name} controller carries no guarantee (only interval does)"
        return Guarantee({"certified": False, "certificate": None, "not_certified": why})
    try:
        outcome = cached_setup(setup, controller, cache=cache, refresh=refresh, progress=progress)
    except (NotImplementedError, InputError) as exc:  # a reference the certificate cannot bound
        why = f"not certified: {exc}"
        return Guarantee({"certified": False, "certificate": None, "not_certified": why})
    certificate = outcome.certificate
    clipped = clipped_beyond_the_bound(setup, certificate)
    fields = {
        "certified": certificate.certified and clipped is None,
        "certificate": certificate.to_dict(),
        "not_certified": (
            None if certificate.certified and clipped is None
            else clipped if certificate.certified
            else certificate.summary()
        ),
    }  # fmt: skip
    return Guarantee(fields, outcome)


def clipped_beyond_the_bound(setup, certificate: Certificate) -> str | None:
    """Why a run that clips its torque (the scenario's ``torque_limit``) is not covered by a
    certified configuration's guarantee, or ``None``: the argument assumes an unclipped torque,
    and a joint's limit lies below the certificate's bound of the torque the law commands in
    the floor's regime (``torque_bound``)."""
    limit = getattr(setup, "torque_limit", None)
    bound = certificate.figures.get("torque_bound")
    if limit is None or bound is None:
        return None
    bound = np.asarray(bound, dtype=float)
    limit = np.broadcast_to(np.asarray(limit, dtype=float), bound.shape)
    j = most_exceeded(bound, limit, np.isfinite(limit) & (limit > 0))
    if j is None:
        return None
    joint = setup.robot.joint_names[j]
    return (
        f"not covered: this run clips the torque at {limit[j]:.4g} N m on joint '{joint}', "
        f"below the certificate's bound {bound[j]:.4g} N m of the torque the law commands "
        "(the argument assumes an unclipped torque; the configuration itself is certified)"
    )


def certificate_fields(setup, controller: Controller, **options: Any) -> dict[str, Any]:
    """``certified`` (bool, or ``None`` when not computed), ``certificate`` (its fields, or
    ``None``) and ``not_certified`` (one line saying why, or ``None``) of a run of ``controller``
    in ``setup``; ``options`` as for :func:`guarantee_of` (``certify``, ``cache``, ``refresh``,
    ``progress``)."""
    return guarantee_of(setup, controller, **options).fields
