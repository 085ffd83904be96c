"""The table of docs/sampled-data.md: the certificate of every shipped scenario and demo assembly
at its own period, at 1 kHz and at 10 kHz (implicit law), next to the campaigns that test it.

    python scripts/sampled_data_table.py [--campaigns DIR]

``--campaigns DIR`` reads ``DIR/<robot>_<scenario>/summary.json`` written by
``urpc campaign <scenario> --runs 200 --sampled-law implicit --out DIR/<robot>_<scenario>``.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from urpc.control.certificate import certify
from urpc.studies.certification import certify_setup
from urpc.studies.demo.settings import DEFAULT_CONFIGURATIONS, DISTURBANCE_BOUND, DURATION
from urpc.studies.demo.synthesis import synthesize_configuration
from urpc.studies.scenario import build, build_controller, load_scenario, shipped_scenarios
from urpc.trajectories import generic_trajectory

IMPLICIT = {"interval": {"sampled_law": "implicit"}}


def _cells(certificate) -> list[str]:
    floor = certificate.epsilon_floor
    return [
        "yes" if certificate.certified else "no",
        f"{floor:.3g}" if math.isfinite(floor) else "none",
        f"{certificate.max_sample_period * 1e3:.3g}",
    ]


def _campaign(directory: Path | None, name: str, period: float | None, own: float | None) -> str:
    if directory is None or period != own:
        return ""
    path = directory / name.replace("/", "_") / "summary.json"
    if not path.is_file():
        return ""
    summary = json.loads(path.read_text())
    worst = summary["worst_final_error_over_epsilon"] * summary["epsilon"]
    return f"{summary['met']}/{summary['runs']}, worst {worst:.3g}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--campaigns", type=Path, help="folder of campaign outputs")
    args = parser.parse_args()
    print(
        "| scenario | epsilon [rad] | period [ms] | certified | epsilon_floor [rad] "
        "| max_sample_period [ms] | 200-run campaign: met, worst final error [rad] |"
    )
    print("|---|---|---|---|---|---|---|")
    for name in sorted(shipped_scenarios()):
        scenario = load_scenario(name).with_overrides(controller_options=IMPLICIT)
        own = scenario.sample_period
        for period in dict.fromkeys([own, 1e-3, 1e-4]):
            setup = build(scenario.with_overrides(sample_period=period or "continuous"))
            certificate = certify_setup(setup, build_controller(setup, "interval"))
            shown = "continuous" if period is None else f"{period * 1e3:g}"
            row = [name, f"{scenario.epsilon:g}", shown, *_cells(certificate)]
            row.append(_campaign(args.campaigns, name, period, own))
            print("| " + " | ".join(row) + " |")
    for configuration in DEFAULT_CONFIGURATIONS:
        for period in (1e-3, 1e-4):
            arm = synthesize_configuration(configuration, repeats=1, sample_period=period)
            trajectory = generic_trajectory(arm.nominal)
            certificate = certify(
                arm.controller, trajectory, duration=DURATION, disturbance_bound=DISTURBANCE_BOUND
            )
            row = [f"demo {configuration}", f"{arm.controller.epsilon:g}", f"{period * 1e3:g}"]
            print("| " + " | ".join([*row, *_cells(certificate), ""]) + " |")


if __name__ == "__main__":
    main()
