"""Results: summary, files (round trip, atomic writes) and figures."""

from __future__ import annotations

import csv
import dataclasses
import json
import math

import numpy as np
import pytest
from matplotlib.figure import Figure

import urpc
from urpc.control.base import Reference
from urpc.control.synthesis import synthesize
from urpc.errors import InputError
from urpc.sim import plotting
from urpc.sim.metrics import METRIC_NAMES
from urpc.sim.results import SimulationResult
from urpc.sim.simulation import CONTINUOUS_METHOD, simulate


class PaperTrajectory:
    amplitude = np.array([np.pi / 4, -np.pi / 8])

    def reference(self, t: float) -> Reference:
        a, b = 0.5 * np.pi * t, np.pi * t
        s = math.sin(a) * math.sin(b)
        sd = 0.5 * np.pi * math.cos(a) * math.sin(b) + np.pi * math.sin(a) * math.cos(b)
        sdd = -1.25 * np.pi**2 * s + np.pi**2 * math.cos(a) * math.cos(b)
        return Reference(self.amplitude * s, self.amplitude * sd, self.amplitude * sdd)


@pytest.fixture(scope="module")
def result(rr, rr_box, rr_true_point):
    plant = rr_box.plant(rr, rr_true_point)
    controller = synthesize(rr, rr_box, 1e-2, sample_period=1e-3, sampled_law="paper")
    return simulate(
        plant,
        controller,
        PaperTrajectory(),
        duration=0.5,
        q0=[0.02, -0.02],
        qd0=[0, 0],
        disturbance_bound=10.0,
        seed=3,
        torque_limit=400,
    ).labelled(scenario="scenario 3")


SUMMARY_KEYS = {*METRIC_NAMES, "phi", "kappa", "epsilon", "controller"}


def test_summary_is_the_metrics_plus_epsilon_and_controller(result):
    summary = result.summary()
    assert set(summary) == SUMMARY_KEYS
    assert summary["controller"] == "interval" and summary["epsilon"] == 1e-2
    assert {k: summary[k] for k in (*METRIC_NAMES, "phi", "kappa")} == result.metrics
    assert summary["phi"] == result.diagnostics["phi"][-1]  # a diagnostic's final value
    np.testing.assert_allclose(result.error, result.q_desired - result.q)
    np.testing.assert_allclose(result.error_norm, np.linalg.norm(result.error, axis=1))


def test_save_writes_the_three_files_and_loads_back(result, tmp_path):
    directory = result.save(tmp_path / "runs" / "s3")
    assert sorted(p.name for p in directory.iterdir()) == [
        "result.csv",
        "result.npz",
        "summary.json",
    ]
    summary = json.loads((directory / "summary.json").read_text())
    assert set(summary) == SUMMARY_KEYS
    assert summary == json.loads(json.dumps(result.summary()))

    with (directory / "result.csv").open() as stream:
        rows = list(csv.reader(stream))
    header, body = rows[0], np.array(rows[1:], dtype=float)
    assert header == [
        "t",
        "q_1",
        "q_2",
        "qd_1",
        "qd_2",
        "q_desired_1",
        "q_desired_2",
        "qd_desired_1",
        "qd_desired_2",
        "e_1",
        "e_2",
        "e_norm",
        "u_1",
        "u_2",
        "d_1",
        "d_2",
        "phi",
        "kappa",
    ]
    assert body.shape == (len(result.t), len(header))
    np.testing.assert_allclose(body[:, header.index("e_norm")], result.error_norm, rtol=1e-11)
    np.testing.assert_allclose(body[:, header.index("u_2")], result.torque[:, 1], rtol=1e-11)
    np.testing.assert_allclose(body[:, header.index("phi")], result.diagnostics["phi"], rtol=1e-11)

    loaded = SimulationResult.load(directory)
    for item in dataclasses.fields(SimulationResult):
        original, copy = getattr(result, item.name), getattr(loaded, item.name)
        if isinstance(original, np.ndarray):
            np.testing.assert_array_equal(copy, original)
        elif item.name == "diagnostics":
            assert list(copy) == list(original) == ["phi", "kappa"]
            for name, series in original.items():
                np.testing.assert_array_equal(copy[name], series)
        else:
            assert copy == original, item.name
    assert loaded.metrics == result.metrics


def test_continuous_metadata_round_trips(rr, rr_box, tmp_path):
    run = simulate(
        rr_box.plant(rr),
        synthesize(rr, rr_box, 1e-2),
        PaperTrajectory(),
        duration=0.05,
        q0=[0, 0],
        qd0=[0, 0],
    )
    loaded = SimulationResult.load(run.save(tmp_path / "continuous"))
    assert loaded.sample_period is None and loaded.torque_limit is None
    assert loaded.info == run.info and loaded.info["integrator"] == CONTINUOUS_METHOD


def test_saving_again_replaces_the_files_and_keeps_others(result, tmp_path):
    directory = result.save(tmp_path / "run")
    (directory / "notes.txt").write_text("mine")
    (directory / "summary.json").write_text("stale")
    result.save(directory)
    assert json.loads((directory / "summary.json").read_text()) == json.loads(
        json.dumps(result.summary())
    )
    assert (directory / "notes.txt").read_text() == "mine"
    assert sorted(p.name for p in directory.iterdir()) == [
        "notes.txt",
        "result.csv",
        "result.npz",
        "summary.json",
    ]


def test_a_failing_write_leaves_nothing_behind(result, tmp_path, monkeypatch):
    def broken(self, path):
        path.write_text("half a file")
        raise OSError("disk full")

    monkeypatch.setattr(SimulationResult, "_write_csv", broken)
    with pytest.raises(OSError, match="disk full"):
        result.save(tmp_path / "new")
    assert list(tmp_path.iterdir()) == []  # neither the directory nor a staging copy

    existing = tmp_path / "existing"
    existing.mkdir()
    (existing / "summary.json").write_text("previous")
    with pytest.raises(OSError, match="disk full"):
        result.save(existing)
    assert [p.name for p in existing.iterdir()] == ["summary.json"]
    assert (existing / "summary.json").read_text() == "previous"


def test_load_rejects_a_directory_without_a_result(tmp_path):
    with pytest.raises(InputError, match="result.npz"):
        SimulationResult.load(tmp_path)


def test_plot_returns_labelled_headless_figures(result, tmp_path):
    # The titles are figure titles (suptitle, two lines, so that none is cut); the error figure
    # has a second panel (||e|| / epsilon), the torque figure one panel per joint, and the gains
    # figure is new (the expectations changed with these figures).
    figures = result.plot()
    assert set(figures) == {"trajectory", "error", "torque", "gains"}
    for name, figure in figures.items():
        assert isinstance(figure, Figure)
        axes = figure.axes[-1]
        assert "[s]" in axes.get_xlabel()
        title = figure.get_suptitle() or figure.axes[0].get_title()
        assert "interval" in title and "scenario 3" in title
        figure.savefig(tmp_path / f"{name}.png")
        assert (tmp_path / f"{name}.png").stat().st_size > 1000
    assert figures["trajectory"].axes[0].get_legend() is not None
    error_axes = figures["error"].axes[0]
    assert error_axes.get_legend() is not None
    assert error_axes.get_yscale() == "log" and "[rad]" in error_axes.get_ylabel()
    assert any(
        np.allclose(line.get_ydata(), 1e-2) for line in error_axes.get_lines()
    )  # the epsilon line
    assert [a.get_ylabel() for a in figures["torque"].axes] == ["$u_{1}$ [N m]", "$u_{2}$ [N m]"]
    assert [a.get_ylabel() for a in figures["gains"].axes] == [
        "$\\phi$ [N m s/rad]",
        "$\\kappa$ [s/rad]",
    ]
    assert "[rad]" in figures["trajectory"].axes[0].get_ylabel()


def test_a_pushed_disturbance_is_named_in_the_titles(rr, rr_box):
    """A run under a disturbance other than the default ball says which in every title (a
    figure of a worst-case push must not read like a random one); the ball adds nothing."""
    from urpc.sim.plotting import describe

    controller = urpc.synthesize(rr, rr_box, 1e-2, sample_period=1e-3)
    runs = {
        model: urpc.simulate(
            rr, controller, urpc.PaperTrajectory(), duration=0.05, disturbance_bound=1.0,
            disturbance=model,
        )
        for model in ("ball", "worst", "lightest")
    }  # fmt: skip
    assert describe(runs["ball"]).endswith("||d|| <= 1 N m")
    assert describe(runs["worst"]).endswith("||d|| <= 1 N m (at the bound, against r)")
    for name, figure in runs["lightest"].plot().items():
        title = figure.get_suptitle() or figure.axes[0].get_title()
        assert "along the lightest mode" in title, name
    assert runs["lightest"].info["joint_kinds"] == list(rr.joint_kinds)


def test_compare_overlays_runs(result, tmp_path):
    other = dataclasses.replace(result, controller="r-alpha", torque=result.torque * 1.1)
    figure = plotting.compare([result, other])
    assert len(figure.axes) == 1 + result.dof
    labels = [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
    assert "interval" in labels and "r-alpha" in labels
    assert figure.axes[0].get_yscale() == "log"
    assert all("[N m]" in axes.get_ylabel() for axes in figure.axes[1:])
    overview = plotting.plot_overview(result)
    assert len(overview.axes) == 2
    reference = plotting.plot_reference(PaperTrajectory(), 4.0)
    lines = reference.axes[0].get_lines()
    assert len(lines) == 2 and lines[0].get_ydata().max() == pytest.approx(0.6046, abs=1e-3)
    assert "[rad]" in reference.axes[0].get_ylabel()
    figure.savefig(tmp_path / "compare.png")
    with pytest.raises(ValueError):
        plotting.compare([])
