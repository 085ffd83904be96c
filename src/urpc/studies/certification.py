"""The certificate of a scenario: its controller, reference, duration and disturbance.

:func:`urpc.control.certificate.certify` works on a synthesized controller; a scenario supplies
everything else (the reference it tracks, for how long, and the disturbance bound its plant sees).
"""

from __future__ import annotations

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
