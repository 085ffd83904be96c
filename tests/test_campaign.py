"""Campaigns: the draws (vertices, consistency, seeds), local and Dask execution, outputs, CLI."""

from __future__ import annotations

import csv
import dataclasses
import json

import numpy as np
import pytest

from urpc.__main__ import main
from urpc.errors import InputError
from urpc.model.uncertainty import LinkBox, ParameterBox
from urpc.studies.campaign import (
    HISTOGRAM_NAME,
    RUNS_NAME,
    SUMMARY_NAME,
    RunSpec,
    RunTask,
    draw_runs,
    physically_consistent,
    run_campaign,
    run_one,
)
from urpc.studies.scenario import build, load_scenario, run_scenario

SUMMARY_KEYS = {
    "runs", "met_fraction", "worst_final_error_over_epsilon", "worst_entry_time",
    "torque_peak_max", "scenario", "seed", "rejected_draws", "wall_time", "runs_per_minute",
}  # fmt: skip


@pytest.fixture(scope="module")
def short():
    """The paper's scenario 3 (the Table I box, 1 kHz, ||d|| <= 10 N m), 0.2 s long."""
    return load_scenario("rr_planar/s3_ic1").with_overrides(duration=0.2)


@pytest.fixture(scope="module")
def setup(short):
    return build(short)


@pytest.fixture(scope="module")
def reference(short):
    """9 runs (the 8 vertices and one uniform draw) in this process."""
    return run_campaign(short, 9, workers=1, seed=5)


def _deterministic(result):
    return result.rows()  # rows carry no wall times


# ----------------------------------------------------------------------------- draws
def test_draws_cover_every_vertex_then_uniform_points_inside_the_box(setup):
    specs, stats = draw_runs(setup, 12, seed=1)
    box, epsilon = setup.box, setup.scenario.epsilon
    assert box.n_uncertain == 3 and stats["vertex_total"] == 8 and stats["vertices"] == 8
    assert [s.kind for s in specs] == ["vertex"] * 8 + ["uniform"] * 4
    assert {s.vertex for s in specs[:8]} == set(range(8))
    link = box.link_box("link2")
    for spec in specs:
        values = np.array(spec.point["link2"])
        assert np.all(values >= link.lower) and np.all(values <= link.upper)
        assert physically_consistent(box, spec.point)
        assert np.all(np.abs(np.array(spec.q0) - setup.q0) <= 2 * epsilon)
        assert spec.qd0 == tuple(setup.qd0)
    for spec in specs[:8]:
        assert np.array_equal(spec.point["link2"], box.vertex(spec.vertex).links["link2"])
    # The paper's true plant (m2 = 10, lc2 = 0.525, I2 = 20/12) is vertex 7.
    assert np.array(specs[7].point["link2"])[[0, 1, 6]] == pytest.approx((10, 0.525, 20 / 12))
    assert len({s.seed for s in specs}) == 12


def test_draws_depend_only_on_seed_and_run_index(setup):
    few, _ = draw_runs(setup, 9, seed=4)
    many, _ = draw_runs(setup, 20, seed=4)
    other, _ = draw_runs(setup, 9, seed=5)
    assert few == many[:9]
    assert all(a.seed != b.seed and a.q0 != b.q0 for a, b in zip(few, other, strict=True))


def test_fewer_runs_than_vertices_take_half_random_distinct_vertices(setup):
    specs, stats = draw_runs(setup, 6, seed=0)
    vertices = [s.vertex for s in specs if s.kind == "vertex"]
    assert stats["vertices"] == 3 and len(set(vertices)) == 3
    assert [s.kind for s in specs] == ["vertex"] * 3 + ["uniform"] * 3


def test_physical_consistency_is_the_pseudo_inertia_test(setup):
    box = setup.box
    nominal = box.link_box("link2").nominal.copy()  # m, c, ixx, ixy, iyy, ixz, iyz, izz
    assert physically_consistent(box, {"link2": nominal})
    triangle = nominal.copy()
    triangle[6] = 4.0  # iyy > ixx + izz = 40/12
    assert not physically_consistent(box, {"link2": triangle})
    negative = nominal.copy()
    negative[0] = -1.0
    assert not physically_consistent(box, {"link2": negative})
    massless = nominal.copy()
    massless[0] = 0.0  # no mass but rotational inertia: no rigid body has that
    assert not physically_consistent(box, {"link2": massless})
    assert physically_consistent(box, {"link2": np.zeros(10)})


def test_inconsistent_draws_and_vertices_are_rejected_and_counted(setup):
    link = setup.box.link_box("link2")
    lower, upper = link.lower.copy(), link.upper.copy()
    upper[6] = 5.0  # iyy up to 5 > ixx + izz: the upper iyy vertices are not rigid bodies
    wide = ParameterBox((LinkBox("link2", "physical", link.nominal, lower, upper),))
    specs, stats = draw_runs(dataclasses.replace(setup, box=wide), 16, seed=2)
    assert stats["rejected_vertices"] == 4 and stats["vertices"] == 4
    assert stats["rejected_draws"] > 0
    assert all(physically_consistent(wide, s.point) for s in specs)
    assert sum(s.kind == "uniform" for s in specs) == 12


def test_bad_counts_raise_input_errors(setup, short):
    with pytest.raises(InputError, match="runs"):
        draw_runs(setup, 0)
    with pytest.raises(InputError, match="seed"):
        draw_runs(setup, 3, seed=-1)
    with pytest.raises(InputError, match="ic_spread"):
        draw_runs(setup, 3, ic_spread=float("nan"))
    with pytest.raises(InputError, match="workers"):
        run_campaign(short, 3, workers=0)


# ----------------------------------------------------------------------------- execution
def test_reference_campaign_summary(reference, short):
    summary = reference.summary()
    assert SUMMARY_KEYS <= set(summary)
    assert summary["runs"] == 9 and summary["vertex_runs"] == 8
    assert summary["seed"] == 5 and summary["scenario"] == "s3_ic1"
    assert 0 <= summary["met_fraction"] <= 1
    assert [o.spec.index for o in reference.outcomes] == list(range(9))
    rows = reference.rows()
    ok = [r for r in rows if r["status"] == "ok"]
    assert ok and all(r["final_error_over_epsilon"] == r["final_error"] / 0.01 for r in ok)
    assert summary["torque_peak_max"] == max(r["torque_peak"] for r in ok)


def test_dask_cluster_on_loopback_gives_the_local_results(short, reference):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=False,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        result = run_campaign(short, 9, scheduler=cluster.scheduler_address, seed=5)
    assert result.scheduler == cluster.scheduler_address and result.workers is None
    assert _deterministic(result) == _deterministic(reference)


def test_unreachable_scheduler_is_an_input_error(short):
    pytest.importorskip("distributed")
    with pytest.raises(InputError, match="scheduler address"):
        run_campaign(short, 2, scheduler="nohost")
    with pytest.raises(InputError, match="cannot reach"):
        run_campaign(short, 2, scheduler="tcp://127.0.0.1:9", connect_timeout=0.5)


def test_diverging_runs_are_recorded_not_raised(short):
    calls = []
    wild = short.with_overrides(controller_options={"interval": {"phi_P": 1e5}})
    result = run_campaign(wild, 2, workers=1, progress=lambda done, total: calls.append(done))
    assert calls == [1, 2]
    assert all(o.status == "diverged" and not o.met for o in result.outcomes)
    assert "diverged at t =" in result.outcomes[0].message
    summary = result.summary()
    assert summary["diverged"] == 2 and summary["met_fraction"] == 0
    assert summary["worst_final_error_over_epsilon"] is None


def test_a_run_with_the_scenarios_own_draws_reproduces_run_scenario(short):
    setup = build(short)
    spec = RunSpec(
        index=0,
        kind="uniform",
        vertex=None,
        seed=short.seed,
        point={name: tuple(values) for name, values in setup.true_point.links.items()},
        q0=tuple(setup.q0),
        qd0=tuple(setup.qd0),
    )
    outcome = run_one(RunTask(json.dumps(short.to_dict(), sort_keys=True), str(short.source), spec))
    expected = run_scenario(short).metrics
    assert outcome.status == "ok" and outcome.cpu_time > 0
    for name in ("met", "entry_time", "final_error", "torque_peak", "torque_variation", "phi"):
        assert outcome.metrics[name] == expected[name], name


# ----------------------------------------------------------------------------- outputs
def test_save_writes_csv_summary_and_histogram(reference, tmp_path):
    out = reference.save(tmp_path / "deep" / "campaign")
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [RUNS_NAME, SUMMARY_NAME, HISTOGRAM_NAME]
    )
    with (out / RUNS_NAME).open(newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 9 and {"run", "kind", "seed", "link2.mass", "link2.iyy"} <= set(rows[0])
    assert {"met", "entry_time", "final_error_over_epsilon", "torque_peak"} <= set(rows[0])
    assert rows[0]["kind"] == "vertex" and float(rows[0]["link2.mass"]) == 5.0
    for row, expected in zip(rows, reference.rows(), strict=True):
        assert int(row["seed"]) == expected["seed"] and row["status"] == expected["status"]
        if expected["final_error"] is not None:  # the text reads back to the same double
            assert float(row["final_error"]) == expected["final_error"]
    summary = json.loads((out / SUMMARY_NAME).read_text())
    assert summary["runs"] == 9 and summary == json.loads(json.dumps(reference.summary()))
    assert (out / HISTOGRAM_NAME).read_bytes()[:4] == b"\x89PNG"
    assert (out / HISTOGRAM_NAME).stat().st_size < 200_000
    reference.save(out)  # an existing folder receives fresh files
    assert not [p for p in tmp_path.rglob(".*.tmp")]


def test_save_into_an_unwritable_place_leaves_nothing(reference, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(InputError, match="not a writable folder"):
        reference.save(blocker / "out")
    with pytest.raises(InputError, match="not a folder"):
        reference.save(blocker)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


# ----------------------------------------------------------------------------- CLI
def test_cli_campaign_json(capsys, tmp_path):
    out = tmp_path / "c"
    code = main(
        ["campaign", "rr_planar/s3_ic1", "--runs", "3", "--duration", "0.1", "--workers", "1",
         "--seed", "2", "--out", str(out), "--json", "--no-progress"]
    )  # fmt: skip
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    # The shipped s3 runs the paper's law: one line says it is not certified, nothing else.
    assert code == 0 and captured.err.startswith("warning: NOT certified (paper law")
    assert len(captured.err.splitlines()) == 1
    assert summary["certified"] is False and summary["certificate"]["law"] == "paper"
    assert SUMMARY_KEYS <= set(summary) and summary["out"] == str(out)
    assert summary["runs"] == 3 and summary["duration"] == 0.1 and summary["vertex_runs"] == 1
    assert (out / RUNS_NAME).is_file()
    assert summary["controller_options"]["sampled_law"] == "paper"
    code = main(["campaign", "rr_planar/s3_ic1", "--runs", "1", "--duration", "0.05",
                 "--workers", "1", "--out", str(out), "--no-progress",
                 "--sampled-law", "implicit"])  # fmt: skip
    captured = capsys.readouterr()
    assert code == 0 and "met epsilon" in captured.out and "runs/min" in captured.out
    summary = json.loads((out / SUMMARY_NAME).read_text())
    assert summary["runs"] == 1 and summary["controller_options"]["sampled_law"] == "implicit"
    assert summary["certificate"]["law"] == "implicit"


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--runs", "0"], "--runs"),
        (["--runs", "x"], "--runs"),
        (["--runs", "2", "--seed", "-1"], "--seed"),
        (["--runs", "2", "--workers", "0"], "--workers"),
        (["--runs", "2", "--workers", "2", "--scheduler", "tcp://127.0.0.1:9"], "not allowed"),
        (["--runs", "2", "--scheduler", "nohost"], "scheduler"),
        (["--runs", "2", "--ic-spread", "-1"], "--ic-spread"),
        (["--runs", "2", "--duration", "-1"], "duration"),
        (["--runs", "2", "--plant", "bullet"], "--plant"),
        (["--runs", "2", "--sampled-law", "yes"], "--sampled-law"),
        ([], "--runs"),
    ],
)
def test_cli_bad_input_exits_2_with_one_line(capsys, tmp_path, argv, message):
    out = tmp_path / "out"
    code = main(["campaign", "rr_planar/s3_ic1", "--out", str(out), "--no-progress", *argv])
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error:"), captured.err
    assert message in lines[0] and captured.out == ""
    assert not out.exists()


def test_cli_bad_scenario_and_output(capsys, tmp_path):
    code = main(["campaign", "rr_planar/s9", "--runs", "2"])
    err = capsys.readouterr().err
    assert code == 2 and "rr_planar/s3_ic1" in err and len(err.strip().splitlines()) == 1
    blocker = tmp_path / "file"
    blocker.write_text("")
    code = main(["campaign", "rr_planar/s3_ic1", "--runs", "2", "--out", str(blocker / "x")])
    err = capsys.readouterr().err
    assert code == 2 and "not a writable folder" in err and len(err.strip().splitlines()) == 1
