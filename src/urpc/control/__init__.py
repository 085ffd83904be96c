"""Controllers: the interval passivity controller, the r-alpha baseline, computed torque."""

#: The laws a sampled interval controller can run: ``implicit`` (the certified sampled-data law of
#: :mod:`urpc.control.interval`) or ``paper`` (the paper's law unchanged under the hold).
SAMPLED_LAWS = ("implicit", "paper")
