"""The reconfigurable-arm demo: controllers synthesized on the fly for modular arms.

Two demonstrations of the paper's closing promise (automatic synthesis for modular arms):

* :func:`reconfigure_demo` runs a sequence of arm configurations (default: the shipped assemblies
  ``arm_3dof``, ``arm_4dof``, ``arm_4dof_vacuum``) as if the arm were reassembled between runs.
  Each one is composed from its modules, loaded and given a controller with the same default
  settings (:func:`urpc.control.synthesis.synthesize` with ``epsilon`` only), then simulated sampled at
  1 kHz on a true plant drawn from its box, under an input disturbance the controller does not
  know. Its ``synthesis_time`` [s] is URDF composition + model load + controller construction.
* :func:`tool_change_run` changes the payload during a run: at ``t_change`` the true plant takes a
  heavier payload and the controller switches to the new configuration's box (re-synthesized with
  the same gains) while keeping its internal state, the integral ``s`` of ``f(||e||)`` behind
  ``phi`` and ``kappa``. The run continues from the plant's state, on the same (time-shifted)
  trajectory, without a restart.

Computation is separate from drawing: :func:`run_configuration` and :func:`tool_change_run` return
values, :func:`plot_reconfigure` and :func:`plot_tool_change` return matplotlib figures, and
:func:`reconfigure_demo` and :func:`tool_change_demo` run everything and write the files.

Modules: ``settings`` (defaults, what a configuration is), ``synthesis`` (compose, load,
synthesize, timed), ``configuration_run`` (one configuration simulated), ``tool_change`` (a payload
change during a run), ``drawing`` (a side view of an arm), ``figures``, ``progress`` and ``demos``
(the two demos end to end, with their files).
"""

from .configuration_run import ConfigurationRun, run_configuration
from .demos import reconfigure_demo, tool_change_demo
from .drawing import draw_arm
from .figures import plot_reconfigure, plot_tool_change
from .settings import (
    DEFAULT_CONFIGURATIONS,
    DISTURBANCE_BOUND,
    DURATION,
    EPSILON,
    SAMPLE_PERIOD,
    TIMING_REPEATS,
    TOOL_CHANGE,
    ConfigurationLike,
    configuration_name,
)
from .synthesis import SynthesisTiming, SynthesizedArm, synthesize_configuration
from .tool_change import ToolChangeRun, concatenate, tool_change_run

__all__ = [
    "DEFAULT_CONFIGURATIONS",
    "DISTURBANCE_BOUND",
    "DURATION",
    "EPSILON",
    "SAMPLE_PERIOD",
    "TIMING_REPEATS",
    "TOOL_CHANGE",
    "ConfigurationLike",
    "ConfigurationRun",
    "SynthesisTiming",
    "SynthesizedArm",
    "ToolChangeRun",
    "concatenate",
    "configuration_name",
    "draw_arm",
    "plot_reconfigure",
    "plot_tool_change",
    "reconfigure_demo",
    "run_configuration",
    "synthesize_configuration",
    "tool_change_demo",
    "tool_change_run",
]
