from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

Progress = Optional[Callable[[str, float], Any]]
Vec3 = Tuple[float, float, float]
Columns = Dict[str, npt.NDArray[np.float64]]

class ScenarioError(ValueError):
    """A scenario that cannot be read or is invalid; the message names the key (and its line)."""

class Scenario:
    """A validated scenario and the folder its relative paths resolve against."""

    @staticmethod
    def load(path: str) -> Scenario: ...
    @staticmethod
    def from_toml(text: str, base_dir: Optional[str] = None) -> Scenario: ...
    @staticmethod
    def from_dict(d: Dict[str, Any], base_dir: Optional[str] = None) -> Scenario: ...
    def to_toml(self) -> str: ...
    def to_dict(self) -> Dict[str, Any]: ...
    @property
    def title(self) -> str: ...
    @property
    def base_dir(self) -> str: ...

class World:
    """A DEM world of a plain scenario, built and settled as `pdamp run` does, stepped from Python.

    Particle state as read-only zero-copy numpy views (they follow the world as it is stepped);
    driven bodies moved with `drive_body`, their contact loads read with `body_load`.
    """

    def __init__(
        self,
        scenario: Scenario,
        threads: Optional[int] = None,
        settle: bool = True,
        progress: Progress = None,
        drive: Optional[Dict[str, Tuple[Sequence[float], Sequence[float], Sequence[float]]]] = None,
    ) -> None:
        """`drive`: driven bodies' (displacement_m, velocity_m_s, acceleration_m_s2) at t = 0."""
    def step(self, n: int = 1) -> None:
        """Advances by `n` time steps."""
    def run_until(self, t_s: Optional[float] = None, progress: Progress = None) -> None:
        """Steps until the clock reaches `t_s` s (default: the scenario's duration)."""
    @property
    def time_s(self) -> float: ...
    @property
    def dt_s(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def duration_s(self) -> float: ...
    @property
    def settling_time_s(self) -> float: ...
    def __len__(self) -> int: ...
    @property
    def positions_m(self) -> npt.NDArray[np.float64]:
        """(n, 3) particle centres, m (read-only view, no copy)."""
    @property
    def velocities_m_s(self) -> npt.NDArray[np.float64]:
        """(n, 3) particle velocities, m/s (read-only view, no copy)."""
    @property
    def angular_velocities_rad_s(self) -> npt.NDArray[np.float64]:
        """(n, 3) particle angular velocities, rad/s (read-only view, no copy)."""
    @property
    def forces_n(self) -> npt.NDArray[np.float64]:
        """(n, 3) total particle forces, N (read-only view, no copy)."""
    @property
    def radii_m(self) -> npt.NDArray[np.float64]:
        """(n,) particle radii, m (read-only view, no copy)."""
    @property
    def masses_kg(self) -> npt.NDArray[np.float64]:
        """(n,) particle masses, kg (read-only view, no copy)."""
    @property
    def body_names(self) -> List[str]: ...
    def body_load(self, name: str) -> Tuple[Vec3, Vec3]:
        """Contact force (N) and torque (N·m) of the particles on body `name` in the last step."""
    def body_state(self, name: str) -> Tuple[Vec3, Vec3]:
        """Position (m) and velocity (m/s) of body `name`'s reference point."""
    def drive_body(
        self,
        name: str,
        displacement_m: Sequence[float],
        velocity_m_s: Sequence[float],
        acceleration_m_s2: Sequence[float] = (0.0, 0.0, 0.0),
        at_s: Optional[float] = None,
    ) -> None:
        """Moves a driven body: its state at `at_s` (default: the end of the next step)."""
    def wall_vertices(self, body: str, wall: str) -> npt.NDArray[np.float64]:
        """(n, 3) vertices of a mesh wall (body frame, m), a copy."""
    def move_wall_vertices(self, body: str, wall: str, positions: npt.NDArray[np.float64]) -> None:
        """Deforms a mesh wall: its vertices at the end of the next step (body frame, m)."""
    def wall_nodal_forces(self, body: str, wall: str) -> npt.NDArray[np.float64]:
        """(n, 3) loads of the particles on the wall's vertices in the last step, N."""
    def energy(self) -> Dict[str, float]:
        """The energy ledger, J, with `time_s`, `dissipated_j` and `closure_error_j`."""
    def check_health(self) -> None: ...

def run(
    scenario: Scenario, out: str, threads: Optional[int] = None, progress: Progress = None
) -> str: ...
def fields(
    scenario: Scenario, out: str, threads: Optional[int] = None, progress: Progress = None
) -> Columns: ...
def couple(
    path: str,
    out: str,
    threads: Optional[int] = None,
    resume: bool = False,
    checkpoint_interval_s: float = 0.0,
    progress: Progress = None,
) -> str: ...
def structure_modes(path: str, out: str) -> str: ...
def powder_run(
    path: str,
    out: str,
    packings: int = 1,
    threads: Optional[int] = None,
    resume: bool = False,
    checkpoint_interval_s: float = 0.0,
    progress: Progress = None,
) -> str: ...
def cor(
    sphere: str,
    wall: str,
    sphere_radius_m: float,
    velocities_m_s: Sequence[float],
    model: str = "fe",
    mesh: str = "medium",
    repeat: int = 1,
    thornton_pressure_factor: float = 1.6,
    materials: Optional[str] = None,
    threads: Optional[int] = None,
    progress: Progress = None,
) -> Columns: ...
def impact(
    radius_m: float,
    youngs_modulus_pa: float,
    poisson_ratio: float,
    density_kg_m3: float,
    velocity_m_s: float,
    partner: str = "wall",
    law: str = "hertz",
    restitution: float = 1.0,
    stiffness_n_m: Optional[float] = None,
) -> str: ...
def horizontal_formulas(
    amplitudes_m: Sequence[float],
    frequency_hz: float,
    rolling_clearance_m: float,
    bouncing_clearance_m: float,
    bouncing_mass_ratio: float = 1.0,
) -> Columns: ...
