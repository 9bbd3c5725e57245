"""pdamp — particle damper simulation and design, from Python.

The same library as the ``pdamp`` command line (not a wrapper around the binary): scenarios
are read from TOML files or built from dicts and validated with the command line's messages
(:class:`ScenarioError` names the key and its line); a damper point and an effective field run
with the GIL released and return their results as a dict and as numpy arrays or a pandas
DataFrame. Units are SI, and every key and column name carries its unit (``frequency_hz``,
``amplitude_m``, ``dissipated_energy_per_cycle_j``).

>>> import pdamp
>>> sc = pdamp.load("examples/damper_cylinder_small.toml")
>>> point = pdamp.damper_point(sc, "out/point", frequency_hz=80.0, intensity=10.0)
>>> point["effective_loss_factor"]                                       # doctest: +SKIP
>>> df = pdamp.fields(sc, "out/fields")                                   # doctest: +SKIP
"""

from __future__ import annotations

import json as _json
import os as _os
from typing import Any, Dict, Optional, Union

from . import _pdamp
from ._pdamp import Scenario, ScenarioError, __version__

__all__ = ["Scenario", "ScenarioError", "__version__", "load", "damper_point", "fields"]

PathLike = Union[str, "_os.PathLike[str]"]

_AMPLITUDE_KEYS = ("amplitude_m", "acceleration_m_s2", "intensity")


def load(path: PathLike) -> Scenario:
    """Reads and validates a scenario file (relative paths in it resolve against its folder)."""
    return Scenario.load(_os.fspath(path))


def _with_excitation(scenario: Scenario, frequency_hz, amplitude_m, acceleration_m_s2, intensity):
    given = {k: v for k, v in zip(_AMPLITUDE_KEYS, (amplitude_m, acceleration_m_s2, intensity)) if v is not None}
    if frequency_hz is None and not given:
        return scenario
    if len(given) > 1:
        raise ScenarioError("give at most one of amplitude_m, acceleration_m_s2, intensity")
    d = scenario.to_dict()
    damper = d.get("damper")
    if damper is None:
        raise ScenarioError("the scenario has no [damper] section")
    if frequency_hz is not None:
        damper["frequency_hz"] = float(frequency_hz)
    if given:
        for k in _AMPLITUDE_KEYS:
            damper.pop(k, None)
        damper.update({k: float(v) for k, v in given.items()})
    return Scenario.from_dict(d, base_dir=scenario.base_dir)


def damper_point(
    scenario: Scenario,
    out: PathLike,
    *,
    frequency_hz: Optional[float] = None,
    amplitude_m: Optional[float] = None,
    acceleration_m_s2: Optional[float] = None,
    intensity: Optional[float] = None,
    threads: Optional[int] = None,
) -> Dict[str, Any]:
    """One excitation point of a damper scenario, as ``pdamp run DAMPER.toml --out OUT``.

    Prepares the bed, excites the container harmonically at ``frequency_hz`` (Hz) with one of
    ``amplitude_m`` (m), ``acceleration_m_s2`` (m/s²) or ``intensity`` (Γ = A/g; default: the
    scenario's ``[damper]`` point), evaluates the complex power method and writes every output
    of the command line into ``out``. Returns ``summary.json`` as a dict
    (``effective_loss_factor``, ``effective_mass_ratio``, ``dissipated_energy_per_cycle_j``, the
    bed statistics, …). ``threads``: worker threads (default: all cores; results do not depend
    on it). The GIL is released while it runs.
    """
    sc = _with_excitation(scenario, frequency_hz, amplitude_m, acceleration_m_s2, intensity)
    return _json.loads(_pdamp.damper_point(sc, _os.fspath(out), threads))


def fields(scenario: Scenario, out: PathLike, *, threads: Optional[int] = None, as_frame: bool = True):
    """The effective field over the scenario's ``[fields]`` grid, as ``pdamp fields``.

    Writes ``fields.csv``, the maps and the resumable store (``out/points``) into ``out`` and
    returns the columns of ``fields.csv`` (``frequency_hz``, ``amplitude_m``,
    ``effective_loss_factor``, ``effective_mass_ratio``, …) as a pandas DataFrame, or as a dict
    of numpy arrays with ``as_frame=False`` or without pandas. Finished points in ``out`` are
    reused (the command line's store).
    """
    cols = _pdamp.fields(scenario, _os.fspath(out), threads)
    if not as_frame:
        return cols
    try:
        import pandas as pd
    except ImportError:
        return cols
    return pd.DataFrame(cols)
