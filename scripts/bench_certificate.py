"""The certificate's cost next to the control steps it certifies (issue 19's figures); the same
as ``urpc bench certificate``.

    python scripts/bench_certificate.py            # UR5, Panda, a 30-link chain
    python scripts/bench_certificate.py --quick    # UR5 and a 10-link chain only
    python scripts/bench_certificate.py --arms chain4,chain8,chain12   # the growth with n

See :mod:`urpc.studies.benchmark.certificate_cost` for what is measured.
"""

from __future__ import annotations

import argparse

from urpc.studies.benchmark.certificate_cost import (
    CERTIFICATE_ARMS,
    certificate_costs,
    format_certificate_costs,
)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="UR5 and a 10-link chain")
    parser.add_argument(
        "--arms", help="comma-separated arms instead (ur5, panda, chainN for an N-link chain)"
    )
    args = parser.parse_args(argv)
    arms = ["ur5", "chain10"] if args.quick else list(CERTIFICATE_ARMS)
    if args.arms:
        arms = [name.strip() for name in args.arms.split(",") if name.strip()]
    print(format_certificate_costs(certificate_costs(arms)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
