"""Scenario settings: everything one simulation run needs, read from one YAML file.

The settings are one frozen, validated model, :class:`Scenario` (declared with the file format in
:mod:`urpc.formats.scenario`, documented in ``docs/scenarios.md``); the paper's six runs are
shipped in ``robots/rr_planar/scenarios/``. Loading (:func:`load_scenario`) only validates;
:mod:`urpc.studies.scenario.setup` turns the settings into objects and
:mod:`urpc.studies.scenario.run` synthesizes and simulates. Relative paths in a file are resolved
against the file's folder.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ... import names
from ...errors import InputError, did_you_mean
from ...formats.base import read_yaml, validate
from ...formats.scenario import Scenario
from ...model.catalog import builtin_root

#: Controllers a scenario can run.
CONTROLLERS: tuple[str, ...] = names.CONTROLLERS
#: Top-level keys of a scenario file.
SCENARIO_KEYS: tuple[str, ...] = tuple(Scenario.model_fields)
#: Plant backends a scenario can simulate with (``urpc.sim.plants.PLANTS``).
PLANT_BACKENDS = names.PLANT_BACKENDS


def shipped_scenarios() -> dict[str, Path]:
    """Scenarios shipped with the built-in robot data (``robots/<robot>/scenarios/*.yaml``), by
    name ``<robot>/<file stem>`` (``rr_planar/s1_ic1``). They ship inside the package, so they are
    found after a plain ``pip install`` too."""
    root = builtin_root()
    return {
        f"{path.parent.parent.name}/{path.stem}": path
        for path in sorted(root.glob("*/scenarios/*.yaml"))
    }


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file (a path, or a shipped name such as ``rr_planar/s2_ic1``).

    Raises:
        InputError: naming the file and the field: a missing file, bad YAML, an unknown key (with
            the closest valid one), a wrong type, a non-positive ``epsilon``, ``duration`` or
            ``sample_period``, an unknown controller or trajectory kind.
    """
    path = Path(path)
    if not path.is_file():
        shipped = shipped_scenarios()
        name = path.as_posix().removesuffix(".yaml")
        if name not in shipped:
            raise InputError(
                "no such scenario file or shipped scenario; " + did_you_mean(name, shipped),
                source=path,
            )
        path = shipped[name]
    document = read_yaml(path)
    return parse_scenario(document, source=path)


def parse_scenario(document: Any, source: str | Path | None = None) -> Scenario:
    """Validate a scenario document (parsed YAML); relative paths are resolved against the
    folder of ``source`` (the current directory without one)."""
    base = Path(source).resolve().parent if source is not None else Path.cwd()
    return validate(Scenario, document, source, context={"base": base, "source": source})
