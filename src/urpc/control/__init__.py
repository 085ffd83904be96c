"""Controllers: the interval passivity controller, the r-alpha baseline, computed torque."""
