"""The result of one simulation run: time series, metadata, metrics, files and figures.

A :class:`SimulationResult` holds raw numpy arrays, one row per recorded sample (every control
sample of a sampled run, the output grid of a continuous one). Computation is separate from
reporting: :attr:`~SimulationResult.metrics` and :meth:`~SimulationResult.summary` derive numbers,
:meth:`~SimulationResult.save` writes files, :meth:`~SimulationResult.plot` returns figures.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ..atomic import write_files
from ..errors import InputError
from ..jsonsafe import finite_or_none
from .metrics import series_metrics

#: File names written by :meth:`SimulationResult.save`.
NPZ_NAME, CSV_NAME, SUMMARY_NAME = "result.npz", "result.csv", "summary.json"

_SERIES = ("t", "q", "qd", "q_desired", "qd_desired", "torque", "disturbance", "saturated")
#: Prefix of a diagnostic series in ``result.npz`` (``diagnostic.phi``).
_DIAGNOSTIC = "diagnostic."


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Time series and metadata of one closed-loop run.

    Series (``K`` samples, ``n = dof``):

    Attributes:
        t: Sample times [s], ``(K,)``.
        q, qd: Joint positions [rad] and velocities [rad/s] of the plant, ``(K, n)``.
        q_desired, qd_desired: The reference position [rad] and velocity [rad/s], ``(K, n)``.
        torque: Commanded torque ``u`` [N m] (the controller's output, before any torque limit),
            ``(K, n)``; held over the following sample period in a sampled run, or over the
            period ``d`` samples later with an actuation delay of ``d`` samples
            (``info["actuation_delay"]``; zero torque before the first command arrives).
        disturbance: Input disturbance ``d`` [N m] added at the plant input, ``(K, n)``.
        saturated: True where the torque limit clipped the command, ``(K,)``.
        diagnostics: The controller's named diagnostic series (``Controller.diagnostics``),
            name -> ``(K,)``, e.g. the interval law's gains ``phi`` [N m s/rad] and ``kappa``
            [s/rad]; their units are ``info["diagnostic_units"]``. Empty for a law with none.
        controller: Controller name.
        epsilon: Required precision [rad] the run is judged against.
        duration: Simulated time [s].
        sample_period: Control period [s], ``None`` for continuous time.
        seed: Seed of the disturbance generator.
        scenario: Scenario name (free text, may be empty).
        plant: Description of the true plant's parameters.
        disturbance_bound: Radius of the disturbance ball [N m].
        torque_limit: Per-joint torque limit [N m], ``None`` when unlimited.
        step_time_median: Median wall time of one control step [s].
        wall_time: Wall time of the whole simulation [s].
        info: Extra metadata (integrator, tolerances, counters), JSON-serializable.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    q_desired: np.ndarray
    qd_desired: np.ndarray
    torque: np.ndarray
    disturbance: np.ndarray
    saturated: np.ndarray
    controller: str
    epsilon: float
    duration: float
    sample_period: float | None = None
    seed: int = 0
    scenario: str = ""
    plant: str = ""
    disturbance_bound: float = 0.0
    torque_limit: tuple[float, ...] | None = None
    diagnostics: Mapping[str, np.ndarray] = field(default_factory=dict)
    step_time_median: float = math.nan
    wall_time: float = math.nan
    info: dict[str, Any] = field(default_factory=dict)

    # ------------------------------------------------------------------ derived series
    @property
    def dof(self) -> int:
        return self.q.shape[1]

    @property
    def error(self) -> np.ndarray:
        """Tracking error ``e = q_d - q`` [rad], ``(K, n)``."""
        return self.q_desired - self.q

    @property
    def error_norm(self) -> np.ndarray:
        """``||e||`` [rad], ``(K,)``."""
        return np.linalg.norm(self.error, axis=1)

    @property
    def saturated_samples(self) -> int:
        """Number of samples at which the torque limit clipped the command."""
        return int(np.count_nonzero(self.saturated))

    @cached_property
    def metrics(self) -> dict[str, Any]:
        """The run's metrics, keys :data:`urpc.sim.metrics.METRIC_NAMES` and the final value of
        each diagnostic series (see :mod:`urpc.sim.metrics`)."""
        return series_metrics(
            self.t,
            self.error_norm,
            self.torque,
            self.epsilon,
            diagnostics=self.diagnostics,
            step_time_median=self.step_time_median,
            wall_time=self.wall_time,
        )

    def labelled(self, *, scenario: str | None = None, plant: str | None = None):
        """This result with the report's labels: the ``scenario`` name and the ``plant``
        description (``None`` keeps the present one); the series are shared, not copied.

        Raises:
            InputError: a label that is not a string (the field named).
        """
        labels = {"scenario": scenario, "plant": plant}
        for name, value in labels.items():
            if value is not None and not isinstance(value, str):
                raise InputError(
                    f"{value!r} is a {type(value).__name__}; a label is a string", field=name
                )
        return replace(self, **{k: v for k, v in labels.items() if v is not None})

    def summary(self) -> dict[str, Any]:
        """The metrics plus ``epsilon`` and ``controller`` (the content of ``summary.json``)."""
        return {**self.metrics, "epsilon": float(self.epsilon), "controller": self.controller}

    def __repr__(self) -> str:
        timing = "continuous" if self.sample_period is None else f"T={self.sample_period:g} s"
        return (
            f"SimulationResult({self.controller!r}, scenario={self.scenario!r}, {timing}, "
            f"duration={self.duration:g} s, samples={len(self.t)}, met={self.metrics['met']})"
        )

    # ------------------------------------------------------------------ files
    def save(self, directory: str | Path, *, csv: bool = True) -> Path:
        """Write ``result.npz`` (every series and the metadata), ``result.csv`` (unless ``csv`` is
        false: a 10 kHz, 10 s run makes a ~7 MB table) and ``summary.json`` into ``directory``
        (created with its parents if missing), atomically (:func:`urpc.atomic.write_files`).

        Returns:
            The directory.
        """
        return write_files(directory, self.writers(csv=csv))

    def writers(self, *, csv: bool = True) -> dict[str, Callable[[Path], None]]:
        """File name -> function writing that file, for :meth:`save` and
        :func:`urpc.atomic.write_files`."""
        writers = {NPZ_NAME: self._write_npz, CSV_NAME: self._write_csv}
        if not csv:
            del writers[CSV_NAME]
        writers[SUMMARY_NAME] = self._write_summary
        return writers

    @classmethod
    def load(cls, directory: str | Path) -> SimulationResult:
        """Read a result written by :meth:`save` (from its ``result.npz``).

        Raises:
            InputError: the file is missing or is not a urpc result.
        """
        path = Path(directory) / NPZ_NAME
        if not path.is_file():
            raise InputError("no result.npz here; give a directory written by save()", path)
        try:
            with np.load(path, allow_pickle=False) as archive:
                series = {name: archive[name] for name in archive.files if name != "metadata"}
                metadata = json.loads(str(archive["metadata"]))
        except (KeyError, ValueError, OSError) as exc:
            raise InputError(f"not a urpc result file ({exc})", path) from None
        series["diagnostics"] = {
            name[len(_DIAGNOSTIC) :]: series.pop(name)
            for name in list(series)
            if name.startswith(_DIAGNOSTIC)
        }
        if metadata.get("torque_limit") is not None:
            metadata["torque_limit"] = tuple(metadata["torque_limit"])
        known = {f.name for f in fields(cls)}
        values = {k: v for k, v in {**series, **metadata}.items() if k in known}
        for name in ("step_time_median", "wall_time"):
            values[name] = math.nan if values.get(name) is None else values[name]
        return cls(**values)

    def _metadata(self) -> dict[str, Any]:
        return {
            "controller": self.controller,
            "epsilon": float(self.epsilon),
            "duration": float(self.duration),
            "sample_period": self.sample_period,
            "seed": int(self.seed),
            "scenario": self.scenario,
            "plant": self.plant,
            "disturbance_bound": float(self.disturbance_bound),
            "torque_limit": None if self.torque_limit is None else list(self.torque_limit),
            "step_time_median": finite_or_none(self.step_time_median),
            "wall_time": finite_or_none(self.wall_time),
            "info": self.info,
        }

    def _write_npz(self, path: Path) -> None:
        arrays = {name: np.asarray(getattr(self, name)) for name in _SERIES}
        for name, series in self.diagnostics.items():
            arrays[_DIAGNOSTIC + name] = np.asarray(series)
        arrays["error"] = self.error
        arrays["error_norm"] = self.error_norm
        arrays["metadata"] = np.array(json.dumps(self._metadata()))
        with path.open("wb") as stream:
            np.savez_compressed(stream, **arrays)

    def _write_csv(self, path: Path) -> None:
        n = self.dof
        joints = [str(i + 1) for i in range(n)]
        columns = ["t"]
        blocks = [self.t[:, None]]
        for prefix, data in (
            ("q", self.q),
            ("qd", self.qd),
            ("q_desired", self.q_desired),
            ("qd_desired", self.qd_desired),
            ("e", self.error),
        ):
            columns += [f"{prefix}_{j}" for j in joints]
            blocks.append(data)
        columns.append("e_norm")
        blocks.append(self.error_norm[:, None])
        for prefix, data in (("u", self.torque), ("d", self.disturbance)):
            columns += [f"{prefix}_{j}" for j in joints]
            blocks.append(data)
        for name, series in self.diagnostics.items():
            columns.append(name)
            blocks.append(np.asarray(series, dtype=float)[:, None])
        table = np.hstack(blocks)
        with path.open("w") as stream:
            np.savetxt(
                stream, table, fmt="%.12g", delimiter=",", header=",".join(columns), comments=""
            )

    def _write_summary(self, path: Path) -> None:
        with path.open("w") as stream:
            json.dump(self.summary(), stream, indent=2)
            stream.write("\n")

    # ------------------------------------------------------------------ figures
    def plot(self) -> dict[str, Any]:
        """Figures of this run: ``trajectory`` (desired and actual joint positions), ``error``
        (``||e||`` on a log scale with the epsilon line, and ``||e|| / epsilon``), ``torque``
        (commanded torques, one panel per joint) and ``gains`` (``phi`` and ``kappa`` over time),
        as :class:`matplotlib.figure.Figure` objects (headless; save them with ``savefig``)."""
        from .plotting import plot_error, plot_gains, plot_torque, plot_trajectory

        return {
            "trajectory": plot_trajectory(self),
            "error": plot_error(self),
            "torque": plot_torque(self),
            "gains": plot_gains(self),
        }

    # ------------------------------------------------------------------ replay
    def replay(self, path: str | Path, robot: Any = None, **options: Any) -> Path:
        """Write a 3D replay of this run: one self-contained HTML file (no network, no server)
        showing the arm moving with ``q``, the desired end-effector path, play, pause and a time
        slider (:mod:`urpc.sim.replay`, ``docs/replay.md``).

        Args:
            path: The file to write (an existing folder gets ``replay.html``).
            robot: The simulated :class:`~urpc.model.robot.Robot`; default: the robot recorded in
                ``info["robot"]`` by :func:`~urpc.sim.simulation.simulate`, loaded again from its
                URDF.
            options: :func:`urpc.sim.replay.replay_html`'s (``title``, ``fps``, ``max_frames``).

        Returns:
            The file written.

        Raises:
            InputError: no robot given or recorded, or its URDF is gone.
        """
        from .replay import ReplayPart, write_replay

        if robot is None:
            robot = self._recorded_robot()
        options.setdefault("title", self.scenario or robot.name)
        part = ReplayPart(robot, self.t, self.q, self.q_desired, label=self.controller)
        return write_replay(path, part, **options)

    def _recorded_robot(self) -> Any:
        from ..model.robot import load_robot

        recorded = self.info.get("robot")
        if not isinstance(recorded, dict) or not recorded.get("urdf"):
            raise InputError(
                "this result does not record its robot; give it: result.replay(path, robot)",
                field="robot",
            )
        if not Path(recorded["urdf"]).is_file():
            raise InputError(
                "the robot's URDF recorded in this result no longer exists; give the robot: "
                "result.replay(path, robot)",
                source=recorded["urdf"],
            )
        return load_robot(recorded["urdf"], recorded.get("locked_joints") or {})
