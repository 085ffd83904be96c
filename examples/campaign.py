"""A verification campaign: many runs of one scenario with true parameters drawn over the box,
on a Dask cluster when ``dask.distributed`` is installed (``pip install 'urpc[dask]'``), else on a
local process pool (or when ``URPC_EXAMPLE_DASK=0``: the test suite runs it so, since starting a
cluster takes longer than the runs). Point ``scheduler`` at your own cluster
(``tcp://host:8786``) to scale out.

    python examples/campaign.py
"""

from __future__ import annotations

import logging
import os

from _settings import duration, runs

from urpc.studies.campaign import run_campaign
from urpc.studies.scenario import load_scenario


def main() -> None:
    scenario = load_scenario("rr_planar/s3_ic1").with_overrides(
        duration=duration(5.0),
        controller_options={"interval": {"sampled_law": "implicit"}},  # the certified law
    )
    cluster = None
    if os.environ.get("URPC_EXAMPLE_DASK", "1") != "0":
        try:
            from dask.distributed import LocalCluster
        except ImportError:
            print("dask.distributed is not installed: a local process pool")
        else:
            cluster = LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, silence_logs=logging.ERROR
            )
    try:
        scheduler = None if cluster is None else cluster.scheduler_address
        result = run_campaign(scenario, runs(20), scheduler=scheduler, seed=0)
    finally:
        if cluster is not None:
            cluster.close()
    rows = result.rows()
    worst = max(row["final_error"] for row in rows)
    print(f"{result.runs} runs on {scheduler or 'a local pool'}: {result.met_fraction:.0%} met")
    print(f"worst final error {worst:.3g} rad (epsilon {scenario.epsilon:g} rad)")


if __name__ == "__main__":  # worker processes import this file: run only once
    main()
