"""The machine a benchmark ran on, for its report."""

from __future__ import annotations

import os
import platform
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import pinocchio as pin


def machine_info() -> dict[str, object]:
    """CPU count, processor, load average, Python, numpy and Pinocchio versions, date (UTC)."""
    processor = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                processor = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        available = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        available = os.cpu_count()
    try:
        load = [round(x, 2) for x in os.getloadavg()]
    except OSError:
        load = None
    return {
        "cpu_count": os.cpu_count(),
        "cpus_available": available,
        "processor": processor,
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "pinocchio": pin.__version__,
        "load_average": load,
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
    }


def format_machine(machine: dict) -> str:
    """One line: processor, CPUs, load average, versions and date."""
    load = machine.get("load_average")
    end = machine.get("load_average_end")
    load_text = "n/a" if load is None else ", ".join(f"{x:g}" for x in load)
    if end is not None:
        load_text += " (start); " + ", ".join(f"{x:g}" for x in end) + " (end)"
    return (
        f"{machine['processor']}, {machine['cpus_available']} of {machine['cpu_count']} CPUs, "
        f"load average {load_text}; Python {machine['python']}, numpy {machine['numpy']}, "
        f"Pinocchio {machine['pinocchio']}; {machine['date']}"
    )
