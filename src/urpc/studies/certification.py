"""The certificate of a scenario: its controller, reference, duration and disturbance.

:func:`urpc.control.certificate.certify` works on a synthesized controller; a scenario supplies
everything else (the reference it tracks, for how long, and the disturbance bound its plant sees).
Runs and campaigns record the outcome with :func:`certificate_fields`.
"""

from __future__ import annotations

from typing import Any

from ..control.base import Controller
from ..control.certificate import Certificate, certify
from ..control.interval import IntervalPassivityController
from ..errors import InputError


def certify_setup(setup, controller: Controller) -> Certificate:
    """The certificate of ``controller`` (an interval controller) in a built scenario ``setup``."""
    if not isinstance(controller, IntervalPassivityController):
        raise InputError(
            f"only the interval controller has a certificate, not '{controller.name}'",
            field="controller",
        )
    scenario = setup.scenario
    return certify(
        controller,
        setup.trajectory,
        duration=scenario.duration,
        disturbance_bound=scenario.disturbance,
    )


def certificate_fields(setup, controller: Controller) -> dict[str, Any]:
    """``certified`` (bool), ``certificate`` (its fields, or ``None``) and ``not_certified``
    (one line saying why, or ``None``) of a run of ``controller`` in ``setup``."""
    if not isinstance(controller, IntervalPassivityController):
        why = f"not certified: the {controller.name} controller carries no guarantee (only interval does)"
        return {"certified": False, "certificate": None, "not_certified": why}
    try:
        certificate = certify_setup(setup, controller)
    except (NotImplementedError, InputError) as exc:  # a reference the certificate cannot bound
        why = f"not certified: {exc}"
        return {"certified": False, "certificate": None, "not_certified": why}
    return {
        "certified": certificate.certified,
        "certificate": certificate.to_dict(),
        "not_certified": None if certificate.certified else certificate.summary(),
    }
