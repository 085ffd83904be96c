"""The certificate a run computes first, on the command line: ``urpc simulate``, ``urpc
campaign`` and ``urpc certify`` compute it once per configuration and read it from the cache
after that (counted by patching ``urpc.control.certificate.certify``), say which, show a status
line on a terminal, and ``--no-certify`` skips it with outputs that say "not computed", never a
verdict.

Every test has its own empty cache folder (the autouse fixture of conftest.py)."""

from __future__ import annotations

import io
import json
import sys

import pytest

from urpc.__main__ import main
from urpc.cli.campaign import resume_command
from urpc.control.certificate import Certificate

#: The RR arm at 1 kHz with the implicit law, 0.2 s: a certificate of about half a second.
SIMULATE = ["simulate", "rr_planar/s3_ic1", "--sampled-law", "implicit", "--duration", "0.2"]
CAMPAIGN = ["campaign", "rr_planar/s3_ic1", "--sampled-law", "implicit", "--duration", "0.2",
            "--runs", "1", "--workers", "1"]  # fmt: skip
CERTIFY = ["certify", "rr_planar/s3_ic1", "--sampled-law", "implicit", "--duration", "0.2"]
NOT_COMPUTED = "not computed (--no-certify)"


class _Terminal(io.StringIO):
    """A stderr that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _line(text: str, head: str) -> str:
    return next(line for line in text.splitlines() if line.startswith(head))


# ============================================================================ simulate
def test_a_second_simulate_reads_the_certificate_from_the_cache(capsys, counted):
    code, out, err = _run(capsys, *SIMULATE)
    assert code == 0, err
    first = _line(out, "certificate  ")
    assert first.startswith("certificate  computed in ") and ", cached (key " in first
    assert len(counted) == 1
    code, again, err = _run(capsys, *SIMULATE)
    assert code == 0, err
    assert len(counted) == 1  # not computed the second time
    key = first.split("(key ")[1][:12]
    assert _line(again, "certificate  ").startswith(f"certificate  cached (key {key};")
    assert _line(again, "guarantee    ") == _line(out, "guarantee    ")  # the same verdict
    assert all(line.startswith("warning: ") for line in err.splitlines())  # nothing else


def test_simulate_json_and_summary_are_the_same_from_the_cache(capsys, counted, tmp_path):
    code, out, err = _run(capsys, *SIMULATE, "--json")
    assert code == 0, err
    first = json.loads(out)  # one JSON object, no source line on stdout
    code, out, err = _run(capsys, *SIMULATE, "--out", tmp_path / "run")
    assert code == 0 and len(counted) == 1, err
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    for field in ("certified", "certificate", "not_certified"):
        assert summary[field] == first[field], field
    # Whatever the verdict, the JSON reads back as the same certificate (non-finite values too).
    assert Certificate.from_dict(first["certificate"]).to_dict() == first["certificate"]
    saved = json.loads((tmp_path / "run" / "certificate.json").read_text())
    assert saved["certificate"] == first["certificate"]


def test_no_cache_computes_again(capsys, counted):
    assert _run(capsys, *SIMULATE)[0] == 0
    code, out, _ = _run(capsys, *SIMULATE, "--no-cache")
    assert code == 0 and len(counted) == 2
    assert _line(out, "certificate  ").startswith("certificate  computed in ")
    assert _run(capsys, *SIMULATE)[0] == 0 and len(counted) == 2  # the fresh record is read


def test_no_certify_says_not_computed_in_the_text_and_in_summary_json(capsys, counted, tmp_path):
    code, out, err = _run(capsys, *SIMULATE, "--no-certify", "--out", tmp_path / "run")
    assert code == 0, err
    assert len(counted) == 0
    assert _line(out, "guarantee    ") == f"guarantee    {NOT_COMPUTED}"
    assert "certificate  " not in out and "certified" not in out.lower()
    assert err == ""  # no "NOT certified" warning: nothing was judged
    for name in ("summary.json", "certificate.json"):
        data = json.loads((tmp_path / "run" / name).read_text())
        assert data["certified"] is None and data["certificate"] is None, name
        assert data["not_certified"] == NOT_COMPUTED, name
    code, out, _ = _run(capsys, *SIMULATE, "--no-certify", "--json")
    summary = json.loads(out)
    assert summary["certified"] is None and summary["not_certified"] == NOT_COMPUTED


def test_a_terminal_shows_the_stages_then_one_line(capsys, counted, monkeypatch):
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    assert main(SIMULATE) == 0
    text = terminal.getvalue()
    assert "certifying: enclosing " in text and " cells (||e|| <= 0.01, ||r|| <= " in text
    assert "certifying: searching the largest sample period" in text
    assert "certificate: computed in " in text  # left on the terminal after the status line
    again = _Terminal()
    monkeypatch.setattr(sys, "stderr", again)
    assert main(SIMULATE) == 0 and len(counted) == 1
    assert "certificate: cached (key " in again.getvalue()
    assert "certifying" not in again.getvalue()
    quiet = _Terminal()
    monkeypatch.setattr(sys, "stderr", quiet)
    assert main([*SIMULATE, "--no-progress"]) == 0
    assert "certif" not in quiet.getvalue().replace("NOT certified", "")


def test_simulate_help_explains_the_flags(capsys):
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--no-certify skip the certificate" in text and "not computed (--no-certify)" in text
    assert "--no-cache compute the certificate again" in text and "URPC_CACHE_DIR" in text


# ============================================================================ campaign
def test_a_campaign_reuses_the_certificate_of_simulate(capsys, counted, tmp_path):
    assert _run(capsys, *SIMULATE)[0] == 0
    code, out, err = _run(capsys, *CAMPAIGN, "--out", tmp_path / "c")
    assert code == 0, err
    assert len(counted) == 1  # the same configuration: computed once for both
    assert _line(out, "  certificate").split()[1] == "cached"
    summary = json.loads((tmp_path / "c" / "summary.json").read_text())
    assert summary["certified"] in (True, False) and summary["certificate"]["law"] == "implicit"


def test_campaign_no_certify_says_not_computed(capsys, counted, tmp_path):
    code, out, err = _run(capsys, *CAMPAIGN, "--no-certify", "--out", tmp_path / "c")
    assert code == 0, err
    assert len(counted) == 0 and err == ""
    assert _line(out, "  guarantee").split(None, 1)[1] == NOT_COMPUTED
    summary = json.loads((tmp_path / "c" / "summary.json").read_text())
    assert summary["certified"] is None and summary["certificate"] is None
    assert summary["not_certified"] == NOT_COMPUTED


def test_the_resume_command_keeps_no_certify():
    from urpc.cli import build_parser

    args = build_parser().parse_args([*CAMPAIGN, "--no-certify", "--no-cache"])
    command = resume_command(args, "out")
    assert command.endswith("--no-certify --no-cache --resume")


# ============================================================================ certify
def test_certify_reads_the_cache_and_no_cache_computes_again(capsys, counted):
    code, out, _ = _run(capsys, *CERTIFY)
    assert code == 0 and out.splitlines()[-1].startswith("certificate: computed in ")
    code, again, _ = _run(capsys, *CERTIFY)
    assert code == 0 and len(counted) == 1
    assert again.splitlines()[-1].startswith("certificate: cached (key ")
    assert again.splitlines()[:-1] == out.splitlines()[:-1]  # the same report
    code, fresh, _ = _run(capsys, *CERTIFY, "--no-cache", "--json")
    assert code == 0 and len(counted) == 2
    data = json.loads(fresh)
    assert Certificate.from_dict(data).to_dict() == {
        k: v for k, v in data.items() if k != "scenario"
    }


def test_certify_cells_reach_the_certificate_and_its_cache_key(capsys, counted, monkeypatch):
    """``--cells N`` is the certificate's ``cells`` (checked on the call itself), a configuration
    of its own in the cache (computed again, not read back), and 0 is refused in one line."""
    from urpc.control import certificate as certificate_module

    asked = []
    real = certificate_module.certify

    def recording(*args, **kwargs):
        asked.append(kwargs.get("cells"))
        return real(*args, **kwargs)

    monkeypatch.setattr(certificate_module, "certify", recording)
    code, out, _ = _run(capsys, *CERTIFY, "--json")
    assert code == 0 and asked == [None]
    code, out, _ = _run(capsys, *CERTIFY, "--cells", 24, "--json")
    assert code == 0 and asked == [None, 24]
    assert json.loads(out)["figures"]["cells"] >= 24
    code, _, _ = _run(capsys, *CERTIFY, "--cells", 24)
    assert code == 0 and asked == [None, 24]  # read back from the cache
    code, out, err = _run(capsys, *CERTIFY, "--cells", 0)
    assert code == 2 and not out and err.count("\n") == 1 and "--cells" in err


def test_certify_require_efforts_adds_the_condition_and_is_a_configuration_of_its_own(
    capsys, counted
):
    """``--require-efforts`` puts the torque-within-efforts condition into the verdict (its
    value is the bound over the effort, the figures' ratio) and is cached apart from the
    default verdict, which has no such condition."""
    from urpc.control.certificate_report import EFFORT_CONDITION

    code, out, _ = _run(capsys, *CERTIFY, "--require-efforts", "--json")
    assert code == 0 and len(counted) == 1
    data = json.loads(out)
    (condition,) = [c for c in data["conditions"] if c["name"] == EFFORT_CONDITION]
    ratio = max(b / 1000.0 for b in data["figures"]["torque_bound"])  # the RR arm's efforts
    assert condition["value"] == pytest.approx(ratio)
    assert condition["holds"] == (ratio <= 1.0) and data["certified"] <= condition["holds"]
    code, out, _ = _run(capsys, *CERTIFY, "--json")
    assert code == 0 and len(counted) == 2  # not the cached strict verdict
    assert all(c["name"] != EFFORT_CONDITION for c in json.loads(out)["conditions"])


def test_an_unusable_cache_gives_one_warning_and_the_run_goes_on(
    capsys, counted, tmp_path, monkeypatch
):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("URPC_CACHE_DIR", str(blocker / "cache"))
    code, out, err = _run(capsys, *SIMULATE)
    assert code == 0, err
    cache_lines = [line for line in err.splitlines() if "certificate cache" in line]
    assert len(cache_lines) == 1 and cache_lines[0].startswith("warning: the certificate cache ")
    assert "URPC_CACHE_DIR" in cache_lines[0]
    line = _line(out, "certificate  ")
    assert line.startswith("certificate  computed in ") and "not cached: the cache cannot" in line
    assert len(counted) == 1


def test_off_a_terminal_a_large_arm_says_the_certificate_is_being_computed(capsys):
    """Minutes of silence read as a hang: a 10-joint arm or larger gets one line when the
    certificate starts (not when the cache answers) and its closing line; a small arm none."""
    import argparse

    from urpc.cli.common import LARGE_ARM_DOF, certificate_progress

    args = argparse.Namespace(no_progress=False)  # pytest's stderr is not a terminal
    assert certificate_progress(args, LARGE_ARM_DOF - 1) is False
    cached = certificate_progress(args, 15)
    cached("certificate: cached (key 0123456789ab)")
    assert capsys.readouterr().err == ""
    computed = certificate_progress(args, 15)
    computed("enclosing 160 cells (||e|| <= 0.01, ||r|| <= 0.45)")
    computed("searching the largest sample period")
    computed("certificate: computed in 259 s, cached (key 0123456789ab)")
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2
    assert lines[0].startswith("certificate: computing it for a 15-joint arm first")
    assert "--no-certify skips it" in lines[0]
    assert lines[1] == "certificate: computed in 259 s, cached (key 0123456789ab)"
