"""Controllers: the interval passivity controller, the r-alpha baseline, computed torque."""

from ..names import SAMPLED_LAWS

__all__ = ["SAMPLED_LAWS"]
