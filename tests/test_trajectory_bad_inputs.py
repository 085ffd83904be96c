"""Bad trajectory files and waypoints: one InputError naming the file, the field (and the line or
sample) and the valid choices, never a traceback or a silently wrong trajectory."""

import subprocess
import sys

import numpy as np
import pytest
import yaml

import urpc
from urpc.studies.scenario import build, load_scenario
from urpc.trajectory_sources import check_limits

ROBOTS = urpc.load_robot("rr_planar").urdf_path.parent
BASE = {
    "robot": "rr_planar",
    "uncertainty": str(ROBOTS / "uncertainty.yaml"),
    "true_parameters": str(ROBOTS / "true_parameters.yaml"),
    "duration": 1.0,
}


def rest_samples(n=201, duration=2.0, start=0.0):
    t = np.linspace(0, duration, n)
    s = (1 - np.cos(np.pi * t / duration)) / 2
    return t + start, np.stack([0.5 * s, -0.3 * s], 1)


def write_csv(path, header, t, q):
    lines = [header] + [",".join(f"{v:.17g}" for v in row) for row in np.column_stack([t, q])]
    path.write_text("\n".join(lines) + "\n")
    return path


def load_refused(*args) -> str:
    """The message of the InputError that ``urpc.load_samples(*args)`` raises."""
    with pytest.raises(urpc.InputError) as info:
        urpc.load_samples(*args)
    return str(info.value)


def scenario(tmp_path, trajectory):
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump({**BASE, "trajectory": trajectory}))
    return path


def refused(tmp_path, trajectory) -> str:
    path = scenario(tmp_path, trajectory)
    with pytest.raises(urpc.InputError) as info:
        build(load_scenario(path))
    return str(info.value)


# ---------------------------------------------------------------- 1. damaged NPZ files
def test_truncated_npz_is_not_a_zip_archive(tmp_path):
    t, q = rest_samples()
    good = tmp_path / "good.npz"
    np.savez(good, t=t, q=q)
    bad = tmp_path / "bad.npz"
    bad.write_bytes(good.read_bytes()[:100])
    with pytest.raises(urpc.InputError, match=r"bad\.npz: not a readable NPZ file \(not a zip"):
        urpc.load_samples(bad, 2)


def test_text_saved_as_npz_is_not_a_zip_archive(tmp_path):
    path = tmp_path / "text.npz"
    path.write_text("t,q1,q2\n0,0,0\n1,1,1\n")
    message = load_refused(path, 2)
    assert "text.npz" in message and "not a zip archive" in message
    assert "pickled" not in message


@pytest.mark.parametrize(
    ("key", "value", "shape"),
    [
        ("q", lambda q: q[:, :, None], "(201, 2, 1)"),
        ("q", lambda q: np.array(1.0), "()"),
        ("qd", lambda q: np.zeros((5, 2)), "(5, 2)"),
        ("q", lambda q: q[:, :1].reshape(-1), "(201,)"),
    ],
)
def test_npz_array_of_the_wrong_shape_names_the_key_and_both_shapes(tmp_path, key, value, shape):
    t, q = rest_samples()
    arrays = {"t": t, "q": q}
    arrays[key] = value(q)
    path = tmp_path / "shape.npz"
    np.savez(path, **arrays)
    message = load_refused(path, 2)
    assert "shape.npz" in message and f"field '{key}'" in message
    assert f"has shape {shape}" in message and "(samples x joints) = (201, 2)" in message


def test_npz_of_strings_names_the_key(tmp_path):
    t, q = rest_samples()
    path = tmp_path / "strings.npz"
    np.savez(path, t=t, q=q.astype(str))
    with pytest.raises(urpc.InputError, match=r"strings\.npz: field 'q': .*expected numbers"):
        urpc.load_samples(path, 2)


def test_damaged_npz_through_the_cli_prints_one_error_line(tmp_path):
    (tmp_path / "bad.npz").write_bytes(b"PK\x03\x04 truncated")
    path = scenario(tmp_path, {"kind": "file", "path": "bad.npz"})
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "urpc",
            "simulate",
            str(path),
            "--no-certify",
            "--out",
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 2, run.stderr
    errors = [line for line in run.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "not a zip archive" in errors[0], run.stderr
    assert "Traceback" not in run.stderr + run.stdout


# ---------------------------------------------------------------- 2. encodings
def test_csv_that_is_not_utf8_is_refused(tmp_path):
    path = tmp_path / "utf16.csv"
    path.write_bytes("t,q1,q2\n0,0,0\n1,0,0\n".encode("utf-16"))
    with pytest.raises(urpc.InputError, match=r"utf16\.csv: cannot read the file as UTF-8 text"):
        urpc.load_samples(path, 2)


def test_csv_with_a_utf8_bom_is_read(tmp_path):
    t, q = rest_samples()
    plain = write_csv(tmp_path / "plain.csv", "t,q1,q2", t, q)
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes())
    assert np.array_equal(urpc.load_samples(bom, 2).q, urpc.load_samples(plain, 2).q)


# ---------------------------------------------------------------- 3. per-joint limits
@pytest.mark.parametrize("kind", ["file", "waypoints"])
def test_acceleration_limit_of_the_wrong_length(tmp_path, kind):
    t, q = rest_samples()
    write_csv(tmp_path / "plan.csv", "t,q1,q2", t, q)
    trajectory = (
        {"kind": "file", "path": "plan.csv"}
        if kind == "file"
        else {"kind": "waypoints", "points": [[0, 0], [0.2, -0.1]]}
    )
    message = refused(tmp_path, {**trajectory, "acceleration_limit": [10, 10, 10]})
    assert "scenario.yaml: field 'trajectory.acceleration_limit': 3 values" in message
    assert "the robot has 2 joints" in message


@pytest.mark.parametrize("kind", ["file", "waypoints"])
@pytest.mark.parametrize("limit", [0, -5, [10, 0]])
def test_acceleration_limit_not_positive_blames_the_scenario(tmp_path, kind, limit):
    t, q = rest_samples()
    write_csv(tmp_path / "plan.csv", "t,q1,q2", t, q)
    trajectory = (
        {"kind": "file", "path": "plan.csv"}
        if kind == "file"
        else {"kind": "waypoints", "points": [[0, 0], [0.2, -0.1]]}
    )
    message = refused(tmp_path, {**trajectory, "acceleration_limit": limit})
    assert "scenario.yaml: field 'trajectory.acceleration_limit': must be > 0" in message
    assert "plan.csv" not in message and "trajectory.points" not in message


def test_check_limits_refuses_a_limit_list_of_the_wrong_length():
    trajectory = urpc.from_samples(*rest_samples())
    with pytest.raises(urpc.InputError, match="field 'acceleration_limit': 3 values"):
        check_limits(trajectory, urpc.load_robot("rr_planar"), acceleration_limit=[1, 2, 3])


# ---------------------------------------------------------------- 4. uneven waypoints
def test_waypoints_of_uneven_length_name_the_point(tmp_path):
    message = refused(tmp_path, {"kind": "waypoints", "points": [[0, 0], [0.5]]})
    assert "field 'trajectory.points[1]': 1 value; the robot has 2 joints" in message


def test_waypoint_times_one_per_point(tmp_path):
    message = refused(
        tmp_path, {"kind": "waypoints", "points": [[0, 0], [0.1, 0]], "times": [0, 1, 2]}
    )
    assert "field 'trajectory.times': 3 times for 2 points" in message


# ---------------------------------------------------------------- 5. header names
@pytest.mark.parametrize("header", ["t,q2,q1", "t,joint2,joint1", "t,q_2,q_1", "time,joint2,q1"])
def test_csv_columns_are_taken_by_name(tmp_path, header):
    t, q = rest_samples()
    reference = urpc.load_samples(write_csv(tmp_path / "a.csv", "t,q1,q2", t, q), 2)
    swapped = write_csv(tmp_path / "b.csv", header, t, q[:, ::-1])
    robot = urpc.load_robot("rr_planar")
    loaded = urpc.load_samples(swapped, 2, robot.joint_names)
    assert np.array_equal(loaded.q, reference.q)


def test_csv_derivative_columns_are_taken_by_name(tmp_path):
    t = np.linspace(0, 1, 11)
    q, qd = np.stack([np.sin(t), 2 * t], 1), np.stack([np.cos(t), 2 + 0 * t], 1)
    table = np.column_stack([t, qd[:, 1], q[:, 1], q[:, 0], qd[:, 0]])
    path = tmp_path / "d.csv"
    np.savetxt(path, table, delimiter=",", header="t,qd2,q2,q1,qd1", comments="")
    loaded = urpc.load_samples(path, 2)
    assert np.allclose(loaded.q, q) and np.allclose(loaded.evaluate(t)[1], qd, atol=1e-12)


@pytest.mark.parametrize(
    ("header", "expected"),
    [
        ("t,q1,q3", "unknown column 'q3' (column 3); valid: t, q1, q2, joint1, joint2, qd1"),
        ("t,q1,q1", "column 'q1' (column 3) repeats joint 1, already given by 'q1' (column 2)"),
        ("t,joint1,q1", "column 'q1' (column 3) repeats joint 1, already given by 'joint1'"),
        ("t,q1,speed", "unknown column 'speed'"),
        ("t,q1,q2,qd1", "1 qd columns for 2 joints: missing qd2"),
    ],
)
def test_csv_unknown_or_repeated_names_are_refused(tmp_path, header, expected):
    path = tmp_path / "names.csv"
    columns = header.count(",") + 1
    path.write_text(header + "\n" + "\n".join(",".join([str(k)] * columns) for k in range(3)))
    robot = urpc.load_robot("rr_planar")
    message = load_refused(path, 2, robot.joint_names)
    assert "names.csv" in message and expected in message


def test_csv_currently_valid_layouts_still_load(tmp_path):
    t, q = rest_samples()
    reference = urpc.load_samples(write_csv(tmp_path / "a.csv", "t,q1,q2", t, q), 2).q
    for header in ("t,q0,q1", "time,q_1,q_2", "t, q1, q2", "t,q 1,q 2"):
        path = write_csv(tmp_path / "b.csv", header, t, q)
        assert np.array_equal(urpc.load_samples(path, 2).q, reference), header
    path = tmp_path / "c.csv"
    np.savetxt(path, np.column_stack([t, q]), delimiter=",")
    assert np.array_equal(urpc.load_samples(path, 2).q, reference)
    assert np.array_equal(urpc.load_samples(path).q, reference)


# ---------------------------------------------------------------- 6. ragged rows
@pytest.mark.parametrize(("row", "count"), [("1,0.1,0.2,9", 4), ("1,0.1", 2)])
def test_csv_rows_with_too_many_or_too_few_values_name_the_line(tmp_path, row, count):
    path = tmp_path / "ragged.csv"
    path.write_text(f"t,q1,q2\n0,0,0\n# a comment\n{row}\n2,0,0\n")
    message = load_refused(path, 2)
    assert f"ragged.csv: line 4 has {count} values; the header has 3 columns" in message


def test_csv_value_not_a_number_names_the_line_and_column(tmp_path):
    path = tmp_path / "text.csv"
    path.write_text("t,q1,q2\n0,0,0\n1,abc,0\n")
    with pytest.raises(urpc.InputError, match=r"line 3, column 'q1': 'abc' is not a number"):
        urpc.load_samples(path, 2)


# ---------------------------------------------------------------- 7. times start at 0
def test_csv_samples_that_do_not_start_at_zero(tmp_path):
    t, q = rest_samples(start=-5.0)
    write_csv(tmp_path / "late.csv", "t,q1,q2", t, q)
    message = refused(tmp_path, {"kind": "file", "path": "late.csv"})
    assert "late.csv: field 't': the samples start at t = -5 s; a trajectory starts at t = 0" in (
        message
    )


@pytest.mark.parametrize(("times", "start"), [([5, 6], "5"), ([-1, 1], "-1")])
def test_waypoint_times_that_do_not_start_at_zero(tmp_path, times, start):
    message = refused(
        tmp_path, {"kind": "waypoints", "points": [[0, 0], [0.1, -0.1]], "times": times}
    )
    assert (
        f"field 'trajectory.times': the waypoints start at t = {start} s; a trajectory starts at "
        "t = 0" in message
    )


# ---------------------------------------------------------------- 8. limits between grid points
def test_short_waypoint_segment_cannot_hide_its_speed(tmp_path):
    message = refused(
        tmp_path, {"kind": "waypoints", "points": [[0, 0], [0.5, -0.3]], "times": [0, 0.001]}
    )
    assert "field 'trajectory': the velocity of joint joint1 is 937.5 at t = 0.0005 s" in message


def test_short_file_segment_cannot_hide_its_speed(tmp_path):
    # a quick step between two samples 0.4 ms apart, both off the 1 ms grid
    t = np.array([0.0, 0.2, 0.4, 0.6, 0.8, 1.0003, 1.0007, 1.2, 1.4, 1.6, 1.8, 2.0])
    q = np.zeros((len(t), 2))
    q[6:, 0] = 0.3
    path = tmp_path / "step.npz"
    np.savez(path, t=t, q=q, qd=np.zeros_like(q))
    trajectory = urpc.load_samples(path, 2)
    peak = np.abs(trajectory.evaluate(np.linspace(1.0003, 1.0007, 2001))[1][:, 0]).max()
    assert peak > 20  # the rr_planar limit, hidden from a 1 ms grid
    coarse = np.arange(0, 2.0005, 1e-3)
    assert np.abs(trajectory.evaluate(coarse)[1][:, 0]).max() < 20
    with pytest.raises(urpc.InputError, match=r"the velocity of joint joint1 is 1\d\d\d"):
        check_limits(trajectory, urpc.load_robot("rr_planar"), source=path)


# ---------------------------------------------------------------- 9. time spans and steps
def test_a_huge_time_span_is_checked_piece_by_piece(tmp_path):
    # a 1 ms grid over 1e9 s would be 1e12 points (7 TiB); the pieces are a handful
    write_csv(tmp_path / "slow.csv", "t,q1,q2", [0.0, 1e9], [[0.0, 0.0], [0.1, 0.0]])
    assert build(load_scenario(scenario(tmp_path, {"kind": "file", "path": "slow.csv"})))
    waypoints = {"kind": "waypoints", "points": [[0, 0], [0.1, 0]], "times": [0, 1e9]}
    assert build(load_scenario(scenario(tmp_path, waypoints)))


def test_a_quick_step_late_in_a_long_span_is_still_found(tmp_path):
    t = np.array([0.0, 1e6, 1e6 + 0.02, 2e6])
    q = np.array([[0.0, 0.0], [0.0, 0.0], [0.5, 0.0], [0.5, 0.0]])
    np.savez(tmp_path / "late.npz", t=t, q=q, qd=np.zeros_like(q))
    message = refused(tmp_path, {"kind": "file", "path": "late.npz"})
    assert "late.npz: field 'trajectory': the velocity of joint joint1 is 46.875" in message


def test_a_span_that_overflows_the_spline_is_refused(tmp_path):
    write_csv(tmp_path / "max.csv", "t,q1,q2", [0.0, 1e308], [[0.0, 0.0], [0.1, 0.0]])
    message = refused(tmp_path, {"kind": "file", "path": "max.csv"})
    assert "max.csv: field 't': the position of the spline through the samples is not finite" in (
        message
    )
    assert "span t = 0 to 1e+308 s" in message and "give times in seconds" in message


def test_time_steps_too_small_to_differentiate_are_refused(tmp_path):
    write_csv(tmp_path / "tiny.csv", "t,q1,q2", [0.0, 1e-300], [[0.0, 0.0], [0.1, 0.0]])
    message = refused(tmp_path, {"kind": "file", "path": "tiny.csv"})
    assert "tiny.csv: field 't': sample 1, line 3 (t = 1e-300 s) comes 1e-300 s after" in message
    assert "the smallest step accepted is 1e-09 s" in message
    message = refused(
        tmp_path, {"kind": "waypoints", "points": [[0, 0], [0.1, 0]], "times": [0, 1e-320]}
    )
    assert "field 'trajectory.times': point 1" in message
    assert "the smallest step accepted is 1e-09 s" in message
    # relative to the largest time: 1e9 s and 1e9 s + 0.5 s are one step of 0.5 s < 1 s
    with pytest.raises(urpc.InputError, match=r"smallest step accepted is 1 s \(1e-09 times"):
        urpc.from_samples([0.0, 1e9, 1e9 + 0.5], [[0.0], [0.0], [0.0]])


@pytest.mark.parametrize(
    ("t", "q", "field", "expected"),
    [
        ([0, 1e-300], [[0, 0], [1, 1]], "t", "comes 1e-300 s after the one before"),
        ([0, 1e308], [[0, 0], [1, 1]], "t", "spline through the samples is not finite"),
        (np.linspace(0, 1e308, 6), np.zeros((6, 2)), "t", "no spline fits the samples"),
        (np.linspace(0, 1, 11), np.full((11, 2), 1e308), "q", "positions |q| up to 1e+308 rad"),
    ],
)
def test_samples_whose_spline_is_not_finite_are_refused(t, q, field, expected):
    with pytest.raises(urpc.InputError) as info:
        urpc.from_samples(t, q).reference(0.5)
    assert info.value.field == field and expected in str(info.value)


def test_waypoints_whose_segment_overflows_are_refused():
    with pytest.raises(urpc.InputError, match="segment from point 0 to 1 .* overflows double"):
        urpc.WaypointTrajectory([[-1e308, 0], [1e308, 1]], [0, 1])
    with pytest.raises(urpc.InputError, match="the acceleration of the segment from point 0"):
        urpc.WaypointTrajectory([[0, 0], [1e300, 1]], [0, 1e-5])


def test_the_limits_grid_of_an_unknown_kind_is_bounded():
    with pytest.raises(urpc.InputError) as info:
        check_limits(urpc.PaperTrajectory(), urpc.load_robot("rr_planar"), times=[0, 1e9])
    message = str(info.value)
    assert "field 't'" in message and "the longest span accepted is 1000 s" in message


# ---------------------------------------------------------------- 10. CSV lines
@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (
            "t,q1,q2\n0,0,0\n# planner segment 2\n\n0.1,0,0\n0.2,nan,0\n0.3,0,0\n",
            "field 'q': sample 2, line 6 (t = 0.2 s) is not finite",
        ),
        (
            "t,q1,q2\n0,0,0\n# comment\n# comment\n0.2,0,0\n0.1,0,0\n",
            "sample 2, line 6 (t = 0.1 s) does not come after t = 0.2 s",
        ),
        ("\n# no header\n0,0,0\n\n1,nan,0\n", "sample 1, line 5 (t = 1 s) is not finite"),
    ],
)
def test_csv_errors_name_the_real_line_past_comments_and_blank_lines(tmp_path, text, expected):
    path = tmp_path / "skips.csv"
    path.write_text(text)
    message = load_refused(path, 2)
    assert "skips.csv" in message and expected in message


def test_npz_samples_name_no_line(tmp_path):
    np.savez(tmp_path / "order.npz", t=[0.0, 0.2, 0.1], q=np.zeros((3, 2)))
    with pytest.raises(urpc.InputError) as info:
        urpc.load_samples(tmp_path / "order.npz", 2)
    assert "sample 2 (t = 0.1 s) does not come after" in str(info.value)
    assert "line" not in info.value.detail


# ---------------------------------------------------------------- 11. NPZ members
def npz_of_members(path, **members):
    import zipfile

    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(f"{name}.npy", data)
    return path


def npy_header(shape, descr="<f8") -> bytes:
    import io

    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buffer, {"descr": descr, "fortran_order": False, "shape": shape}
    )
    return buffer.getvalue()


def test_npz_member_that_is_not_npy_data_names_the_array(tmp_path):
    path = npz_of_members(tmp_path / "plan.npz", t="garbage", q="garbage")
    message = load_refused(path, 2)
    assert "plan.npz: field 't': array 't' (member t.npy) is not a numpy array" in message
    assert "numpy.savez" in message


def test_npz_header_declaring_too_many_samples_is_refused_before_reading(tmp_path):
    header = npy_header((10**11,))
    path = npz_of_members(tmp_path / "bomb.npz", t=header + bytes(64), q=header + bytes(64))
    message = load_refused(path, 2)
    assert "bomb.npz: field 't'" in message and "declares shape (100000000000,)" in message
    assert "at most 10000000 samples" in message


def test_a_csv_larger_than_its_cap_is_refused_before_reading(tmp_path):
    """A sparse file one byte over the cap (nothing written, so nothing to read) is refused by its
    size, pointing at NPZ."""
    from urpc.trajectory_files import MAX_CSV_BYTES

    path = tmp_path / "huge.csv"
    with path.open("wb") as stream:
        stream.truncate(MAX_CSV_BYTES + 1)
    message = load_refused(path, 2)
    assert "huge.csv" in message and "268 MB of CSV are read" in message and ".npz" in message


def test_npz_header_declaring_more_than_the_file_holds_is_damaged(tmp_path):
    t, q = rest_samples()
    path = npz_of_members(
        tmp_path / "short.npz",
        t=npy_header((201,)) + t.tobytes(),
        q=npy_header((201, 2)) + bytes(8),
    )
    message = load_refused(path, 2)
    assert "short.npz: field 'q'" in message and "(3216 bytes), but holds 8 bytes" in message


def test_npz_compressed_and_fortran_ordered_arrays_still_load(tmp_path):
    t, q = rest_samples()
    np.savez_compressed(tmp_path / "c.npz", t=t, q=np.asfortranarray(q), extra=np.array(["x"]))
    assert np.array_equal(urpc.load_samples(tmp_path / "c.npz", 2).q, q)


# ---------------------------------------------------------------- 12. Python API arguments
def test_load_samples_arguments_of_the_wrong_type(tmp_path):
    t, q = rest_samples()
    path = write_csv(tmp_path / "plan.csv", "t,q1,q2", t, q)
    with pytest.raises(urpc.InputError, match="field 'path': expected a file path .* NoneType"):
        urpc.load_samples(None)
    with pytest.raises(urpc.InputError, match="field 'joint_names': 5 is not a list of joint"):
        urpc.load_samples(path, 2, 5)
    with pytest.raises(urpc.InputError, match="field 'dof': 2.0 must be an integer >= 1"):
        urpc.load_samples(path, 2.0)
    assert np.array_equal(urpc.load_samples(path, 2, None).q, urpc.load_samples(path, 2).q)


def test_headerless_csv_with_zero_joints_is_refused(tmp_path):
    path = tmp_path / "plain.csv"
    path.write_text("0,0,0\n1,0,0\n")
    with pytest.raises(urpc.InputError, match="field 'dof': 0 must be an integer >= 1"):
        urpc.load_samples(path, 0)


@pytest.mark.parametrize("t", ["a", float("nan"), None])
@pytest.mark.parametrize(
    "trajectory",
    [
        urpc.from_samples([0, 1], [[0, 0], [1, 1]]),
        urpc.WaypointTrajectory([[0, 0], [1, 1]], [0, 1]),
        urpc.StreamedReference([0, 0]),
        urpc.PaperTrajectory(),
        urpc.SinusoidTrajectory((0, 0), (0.1, 0.2), 0.5),
    ],
    ids=["samples", "waypoints", "streamed", "paper", "sinusoid"],
)
def test_a_reference_at_a_time_that_is_not_a_number(t, trajectory):
    with pytest.raises(urpc.InputError, match=r"field 't': the time .* is not a number \[s\]"):
        trajectory.reference(t)


def test_waypoints_of_zero_joints_are_refused():
    with pytest.raises(urpc.InputError, match=r"field 'points': points has shape \(2, 0\)"):
        urpc.WaypointTrajectory(np.zeros((2, 0)))


@pytest.mark.parametrize(
    ("q_start", "trajectory", "duration", "expected"),
    [
        ([0, 0, 0], urpc.PaperTrajectory(), 1.0, "field 'q_start': [0, 0, 0] has shape (3,)"),
        ([0, 0], "paper", 1.0, "field 'trajectory': expected a urpc.Trajectory, got str"),
        ([0, 0], urpc.PaperTrajectory(), 0.0, "field 'duration': 0.0 is out of range"),
        ([0, 0], urpc.PaperTrajectory(), 1e-300, "field 'duration': the approach from q_start"),
    ],
)
def test_approach_arguments_are_checked(q_start, trajectory, duration, expected):
    from urpc.trajectory_sources import Approach

    with pytest.raises(urpc.InputError) as info:
        Approach(q_start, trajectory, duration)
    assert expected in str(info.value)


def test_a_streamed_target_whose_move_overflows_is_refused_and_not_taken():
    streamed = urpc.StreamedReference([0, 0], velocity_limit=1, acceleration_limit=1)
    with pytest.raises(urpc.InputError, match="field 'target': the move to .* give a nearer"):
        streamed.set_target([1e308, 0], 0.0)
    assert np.array_equal(streamed.reference(0.5).q, [0, 0]) and streamed.updates == 0
    with pytest.raises(urpc.InputError, match="field 'duration': the move to .* over 1e-300 s"):
        streamed.set_target([1, 0], 0.0, 1e-300)
    assert np.all(np.isfinite(streamed.reference(1e-301).qdd))


# ---------------------------------------------------------------- 13. what a message asks for
def test_a_unit_in_the_time_header_is_told_what_to_write(tmp_path):
    path = tmp_path / "units.csv"
    path.write_text("t [s],q1,q2\n0,0,0\n0.1,0,0\n")
    message = load_refused(path, 2)
    assert "units.csv: field 't': the first column is 't [s]'; expected 't' or 'time'" in message
    assert "with no unit in the name" in message


@pytest.mark.parametrize(
    ("text", "name"), [("t;q1;q2\n0;0;0\n0.1;0;0\n", "semicolons"), ("0;0,1;0\n", "semicolons")]
)
def test_a_semicolon_csv_is_told_to_use_commas(tmp_path, text, name):
    path = tmp_path / "semi.csv"
    path.write_text(text)
    message = load_refused(path, 2)
    assert f"semi.csv: line 1 separates its values with {name}" in message
    assert "comma-separated" in message


def test_a_tab_separated_csv_is_told_to_use_commas(tmp_path):
    path = tmp_path / "tabs.csv"
    path.write_text("t\tq1\tq2\n0\t0\t0\n0.1\t0\t0\n")
    with pytest.raises(urpc.InputError, match="line 1 separates its values with tabs"):
        urpc.load_samples(path, 2)


@pytest.mark.parametrize("cell", ["1_0", "١", "0x10"])
def test_csv_values_python_alone_would_read_are_refused(tmp_path, cell):
    path = tmp_path / "odd.csv"
    path.write_text(f"t,q1,q2\n0,0,0\n1,{cell},0\n", encoding="utf-8")
    message = load_refused(path, 2)
    assert f"odd.csv: line 3, column 'q1': '{cell}' is not a number" in message


def test_a_device_is_not_a_regular_file(tmp_path):
    message = refused(tmp_path, {"kind": "file", "path": "/dev/zero"})
    assert "field 'trajectory.path': trajectory file '/dev/zero' is not a regular file" in message
    assert "does not exist" not in message
    with pytest.raises(urpc.InputError, match="/dev/zero: trajectory file is not a regular file"):
        urpc.load_samples("/dev/zero", 2)


@pytest.mark.parametrize("q", [[[0, 0], [1, 1j]], np.zeros((2, 2), complex)])
def test_complex_samples_are_refused_not_cut_to_their_real_part(q):
    with pytest.raises(urpc.InputError, match="field 'q': q holds complex numbers"):
        urpc.from_samples([0, 1], q)
