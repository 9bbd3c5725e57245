"""pdamp — particle damper simulation and design, from Python.

The same library as the ``pdamp`` command line (not a wrapper around the binary), every level
of the toolchain: single impacts and restitution curves (:func:`impact`, :func:`cor`, D Part I),
a damper under harmonic excitation (:func:`damper_point`, :func:`fields`, D Part II), the damper
in a structure (:func:`couple`, :func:`structure_modes`, D Part III), powder-filled cavities
(:func:`powder_run`, P), and a DEM :class:`World` stepped from Python with zero-copy numpy
views of the particles and bodies driven from outside. Scenarios are read from TOML files or
built from dicts and validated with the command line's messages (:class:`ScenarioError` names
the key and its line). Simulations run with the GIL released; Ctrl-C (a notebook's stop
button) stops them cleanly with ``KeyboardInterrupt``; ``progress=`` takes a callback
``f(phase, fraction)`` or ``True`` for a tqdm bar (shown by default in notebooks when tqdm is
installed). Units are SI, and every key and column name carries its unit (``frequency_hz``,
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
import sys as _sys
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Union

from . import _pdamp
from ._pdamp import Scenario, ScenarioError, World, __version__

__all__ = [
    "Scenario",
    "ScenarioError",
    "World",
    "RunResult",
    "__version__",
    "load",
    "run",
    "damper_point",
    "fields",
    "couple",
    "structure_modes",
    "powder_run",
    "cor",
    "impact",
    "horizontal_formulas",
]

PathLike = Union[str, "_os.PathLike[str]"]

_AMPLITUDE_KEYS = ("amplitude_m", "acceleration_m_s2", "intensity")

Progress = Union[None, bool, Callable[[str, float], Any]]


def _in_notebook() -> bool:
    shell = _sys.modules.get("IPython")
    try:
        return shell is not None and type(shell.get_ipython()).__name__ == "ZMQInteractiveShell"
    except Exception:
        return False


class _Bar:
    """A tqdm bar (``tqdm.auto``: a widget in notebooks) fed by the library's progress."""

    def __init__(self, tqdm):
        self._bar = tqdm(total=100, unit="%", bar_format="{desc} {percentage:3.0f}%|{bar}| {elapsed}<{remaining}")
        self._phase = None

    def __call__(self, phase: str, fraction: float) -> None:
        if phase != self._phase:
            self._phase = phase
            self._bar.set_description(phase)
        n = round(100.0 * min(max(fraction, 0.0), 1.0), 1)
        self._bar.update(n - self._bar.n)

    def close(self) -> None:
        self._bar.close()


class _Progress:
    """``progress=``: a callable gets ``(phase, fraction)``; ``True`` (or ``None`` in a
    notebook with tqdm installed) shows a tqdm bar; ``False`` (or ``None`` elsewhere) nothing."""

    def __init__(self, progress: Progress):
        self.callback = None
        self._bar = None
        if callable(progress):
            self.callback = progress
        elif progress or (progress is None and _in_notebook()):
            try:
                from tqdm.auto import tqdm
            except ImportError:
                if progress:
                    self.callback = lambda phase, f: print(f"\r{phase} {100 * f:5.1f} %", end="", file=_sys.stderr)
            else:
                self._bar = self.callback = _Bar(tqdm)

    def __enter__(self):
        return self.callback

    def __exit__(self, *exc):
        if self._bar is not None:
            self._bar.close()
        return False


class RunResult:
    """The outcome of a run that writes a folder (:func:`couple`, :func:`powder_run`,
    :func:`structure_modes`): ``summary`` (the printed JSON as a dict), ``out`` (the folder) and
    its tables as pandas DataFrames (``decay``, ``damping``, ``frf``, ``response``, ``energy``,
    ``modes``, ``tip``, ``envelope``, …: ``result.table("decay")`` or ``result.decay``; ``None``
    where the run did not write it). Without pandas a table is a dict of numpy arrays."""

    def __init__(self, summary: Dict[str, Any], out: PathLike):
        self.summary = summary
        self.out = Path(out)

    @property
    def tables(self) -> List[str]:
        """Names of the CSV tables in ``out``."""
        return sorted(p.stem for p in self.out.glob("*.csv"))

    def table(self, name: str):
        """The table ``out/NAME.csv`` (``None`` when absent)."""
        path = self.out / f"{name}.csv"
        if not path.exists():
            return None
        try:
            import pandas as pd
        except ImportError:
            import numpy as np

            a = np.genfromtxt(path, delimiter=",", names=True)
            return {k: a[k] for k in a.dtype.names}
        return pd.read_csv(path)

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        if (self.out / f"{name}.csv").exists():
            return self.table(name)
        if name in ("decay", "damping", "frf", "response", "energy", "modes", "tip", "envelope"):
            return None
        raise AttributeError(name)

    def __getitem__(self, key: str) -> Any:
        return self.summary[key]

    def __repr__(self) -> str:
        return f"pdamp.RunResult(out={str(self.out)!r}, tables={self.tables})"


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


def run(
    scenario: Scenario,
    out: PathLike,
    *,
    threads: Optional[int] = None,
    progress: Progress = None,
) -> RunResult:
    """A scenario run to files, as ``pdamp run SCENARIO.toml --out OUT``: settling, the main
    run, ``energy.csv`` (the ledger over time), VTK snapshots and ``summary.json``. Returns a
    :class:`RunResult` (``summary``; table ``energy``). A damper scenario runs its excitation
    point (see :func:`damper_point`). For a loop of your own use :class:`World`."""
    with _Progress(progress) as cb:
        text = _pdamp.run(scenario, _os.fspath(out), threads, cb)
    return RunResult(_json.loads(text), out)


def damper_point(
    scenario: Scenario,
    out: PathLike,
    *,
    frequency_hz: Optional[float] = None,
    amplitude_m: Optional[float] = None,
    acceleration_m_s2: Optional[float] = None,
    intensity: Optional[float] = None,
    threads: Optional[int] = None,
    progress: Progress = None,
) -> Dict[str, Any]:
    """One excitation point of a damper scenario, as ``pdamp run DAMPER.toml --out OUT``.

    Prepares the bed, excites the container harmonically at ``frequency_hz`` (Hz) with one of
    ``amplitude_m`` (m), ``acceleration_m_s2`` (m/s²) or ``intensity`` (Γ = A/g; default: the
    scenario's ``[damper]`` point), evaluates the complex power method and writes every output
    of the command line into ``out``. Returns ``summary.json`` as a dict
    (``effective_loss_factor``, ``effective_mass_ratio``, ``dissipated_energy_per_cycle_j``, the
    bed statistics, …). ``threads``: worker threads (default: all cores; results do not depend
    on it). ``progress``: a callback ``f(phase, fraction)`` or ``True`` for a tqdm bar. The
    GIL is released while it runs.
    """
    sc = _with_excitation(scenario, frequency_hz, amplitude_m, acceleration_m_s2, intensity)
    with _Progress(progress) as cb:
        return _json.loads(_pdamp.run(sc, _os.fspath(out), threads, cb))


def fields(
    scenario: Scenario,
    out: PathLike,
    *,
    threads: Optional[int] = None,
    as_frame: bool = True,
    progress: Progress = None,
):
    """The effective field over the scenario's ``[fields]`` grid, as ``pdamp fields``.

    Writes ``fields.csv``, the maps and the resumable store (``out/points``) into ``out`` and
    returns the columns of ``fields.csv`` (``frequency_hz``, ``amplitude_m``,
    ``effective_loss_factor``, ``effective_mass_ratio``, …) as a pandas DataFrame, or as a dict
    of numpy arrays with ``as_frame=False`` or without pandas. Finished points in ``out`` are
    reused (the command line's store).
    """
    with _Progress(progress) as cb:
        cols = _pdamp.fields(scenario, _os.fspath(out), threads, cb)
    return _frame(cols, as_frame)


def _frame(cols, as_frame: bool):
    if not as_frame:
        return cols
    try:
        import pandas as pd
    except ImportError:
        return cols
    return pd.DataFrame(cols)


def couple(
    path: PathLike,
    out: PathLike,
    *,
    threads: Optional[int] = None,
    resume: bool = False,
    checkpoint_interval_s: float = 0.0,
    progress: Progress = None,
) -> RunResult:
    """A particle damper in a structure, as ``pdamp couple SCENARIO.toml --out OUT``.

    The scenario file couples a structure (beam, Matrix Market or Gmsh model, modally reduced)
    to full DEM, effective fields or formulas; free decay, sweeps or steady-state FRFs. Every
    output of the command line goes to ``out``; returns a :class:`RunResult` with the summary
    (``damping_ratio`` per mode, …) and the tables ``decay``, ``damping``, ``frf``,
    ``response``. ``resume`` continues from the checkpoint in ``out``.
    """
    with _Progress(progress) as cb:
        text = _pdamp.couple(_os.fspath(path), _os.fspath(out), threads, resume, checkpoint_interval_s, cb)
    return RunResult(_json.loads(text), out)


def structure_modes(path: PathLike, out: PathLike) -> RunResult:
    """Natural frequencies (Hz) and modes of a structure file, as ``pdamp structure modes``;
    the table ``modes`` (``modes.csv``) and the summary."""
    return RunResult(_json.loads(_pdamp.structure_modes(_os.fspath(path), _os.fspath(out))), out)


def powder_run(
    path: PathLike,
    out: PathLike,
    *,
    packings: int = 1,
    threads: Optional[int] = None,
    resume: bool = False,
    checkpoint_interval_s: float = 0.0,
    progress: Progress = None,
) -> RunResult:
    """A powder-filled cavity, two-way coupled DEM–FEM (P), as ``pdamp powder run``.

    Prepares the powder bed, excites the structure and evaluates the free decay (ζ1, ζ2, ζ̄5 of
    P Table 1). ``packings`` K > 1 runs an ensemble of K random packings (``ensemble.json``:
    mean, standard deviation and 95 % confidence interval). Returns a :class:`RunResult` (tables
    ``tip``, ``envelope``, ``energy``; ``table`` of an ensemble).
    """
    with _Progress(progress) as cb:
        text = _pdamp.powder_run(
            _os.fspath(path), _os.fspath(out), packings, threads, resume, checkpoint_interval_s, cb
        )
    return RunResult(_json.loads(text), out)


def cor(
    sphere: str,
    wall: str,
    sphere_radius_m: float,
    velocities_m_s: Sequence[float],
    *,
    model: str = "fe",
    mesh: str = "medium",
    repeat: int = 1,
    thornton_pressure_factor: float = 1.6,
    materials: Optional[PathLike] = None,
    threads: Optional[int] = None,
    as_frame: bool = True,
    progress: Progress = None,
):
    """The coefficient of restitution ε(v) of a sphere hitting a wall (or ``wall="sphere"``: an
    identical sphere) from an impact model (``fe``, ``hertz``, ``thornton``, ``viscoelastic``;
    D Chap. 4), as ``pdamp cor``. Materials: ``s235``, ``al6060``, ``saa9579`` or names from a
    ``materials`` TOML file. Returns the columns ``velocity_m_s``, ``impact``, ``restitution``,
    ``contact_time_s``, ``max_force_n`` (a DataFrame). Bad inputs raise ``ValueError`` naming the
    argument."""
    with _Progress(progress) as cb:
        cols = _pdamp.cor(
            sphere,
            wall,
            float(sphere_radius_m),
            [float(v) for v in velocities_m_s],
            model,
            mesh,
            int(repeat),
            float(thornton_pressure_factor),
            None if materials is None else _os.fspath(materials),
            threads,
            cb,
        )
    return _frame(cols, as_frame)


def impact(
    *,
    radius_m: float,
    youngs_modulus_pa: float,
    poisson_ratio: float,
    density_kg_m3: float,
    velocity_m_s: float,
    partner: str = "wall",
    law: str = "hertz",
    restitution: float = 1.0,
    stiffness_n_m: Optional[float] = None,
) -> Dict[str, float]:
    """One head-on impact of a sphere on a rigid wall (``partner="sphere"``: an identical
    sphere) with a DEM contact law (``hertz``, ``gonthier``, ``lankarani-nikravesh``,
    ``linear``, ``hertz-mindlin``), as ``pdamp impact``: the measured ``restitution``,
    ``contact_time_s``, ``max_force_n``, ``max_overlap_m`` and Hertz theory's values (D Eq.
    4.8, 2.80). Bad inputs raise ``ValueError`` naming the argument."""
    return _json.loads(
        _pdamp.impact(
            float(radius_m),
            float(youngs_modulus_pa),
            float(poisson_ratio),
            float(density_kg_m3),
            float(velocity_m_s),
            partner,
            law,
            float(restitution),
            None if stiffness_n_m is None else float(stiffness_n_m),
        )
    )


def horizontal_formulas(
    amplitudes_m: Sequence[float],
    *,
    frequency_hz: float,
    rolling_clearance_m: float,
    bouncing_clearance_m: float,
    bouncing_mass_ratio: float = 1.0,
    as_frame: bool = True,
):
    """The analytical motion-mode model of a horizontally excited damper (D Eq. 6.12):
    effective loss factor η̄ and mass ratio m̄_bed/m_bed over the amplitudes (m) at
    ``frequency_hz`` — rolling (scattered ``X/h_rol``, collect-and-collide D Eq. 5.10, maximum
    20/(7π) ≈ 0.91 at ``X_opt = 0.4 h_rol``) below A = g, bouncing (scattered ``2X/h_bou``,
    collect-and-collide D Eq. 6.8, maximum 4/π ≈ 1.27 at ``X_opt = h_bou/π``) above. Clearances
    in m (D Eq. 5.1, 6.1; D Tab. 6.2). Returns the columns ``amplitude_m``,
    ``effective_loss_factor``, ``effective_mass_ratio``."""
    cols = _pdamp.horizontal_formulas(
        [float(x) for x in amplitudes_m],
        float(frequency_hz),
        float(rolling_clearance_m),
        float(bouncing_clearance_m),
        float(bouncing_mass_ratio),
    )
    return _frame(cols, as_frame)
