"""Type stubs of the compiled module ``asperity._native`` (re-exported by ``asperity``).

Units: SI throughout — lengths and gaps in m, pressures and moduli in Pa, forces in N, energies
in J, stiffnesses per unit area in N/m³ (per element N/m). Array arguments: C-contiguous
``numpy.ndarray`` of dtype float64 with the stated shape; anything else raises
``asperity.ArrayTypeError`` (wrong type/dtype) or ``asperity.ParameterError`` (wrong number of
dimensions, not contiguous, non-finite values).
"""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union, final, overload

import numpy as np
import numpy.typing as npt

F64Array = npt.NDArray[np.float64]
Path = Union[str, "PathLike[str]"]
Columns = Dict[str, np.ndarray]

__version__: str
__all__ = [
    "AmplitudeHistory",
    "AmplitudeLoop",
    "BelowRangePatch",
    "CalibrationConvergence",
    "CalibrationRun",
    "CalibrationTable",
    "ClassCounts",
    "Convergence",
    "ConvergenceCheck",
    "CycleEnergy",
    "DecayResult",
    "DiagnoseErrors",
    "DiagnoseReport",
    "ElementSummary",
    "FilePrediction",
    "FilmMap",
    "FilmResult",
    "FilmSummary",
    "IdentifyReport",
    "LevelError",
    "LoopFit",
    "NodeClassReading",
    "NodePlacement",
    "NodeSummary",
    "NonlinearModeResult",
    "NormalSolution",
    "NormalSolver",
    "NotFitted",
    "OscillationResult",
    "ParameterEstimate",
    "PolyFit",
    "PowerSpectrum",
    "PredictReport",
    "PreloadSummary",
    "PressureConvergence",
    "Profile",
    "Record",
    "ReductionSummary",
    "Region",
    "RegionSummary",
    "ResponseModel",
    "SampleSummary",
    "StageTimes",
    "Surface",
    "SurfaceSpec",
    "SurfaceStats",
    "SweepResult",
    "TableColumns",
    "TableValues",
    "TangentialMetadata",
    "TangentialSolver",
    "TangentialStep",
    "TangentialSweepResult",
    "ValanisFit",
    "ValanisParams",
    "VaryingLoadCheck",
    "__version__",
    "calibrate",
    "composite_modulus",
    "diagnose",
    "dissipated_energy",
    "equivalent_surface",
    "film",
    "film_preloads",
    "fit_valanis",
    "fit_valanis_loops",
    "identify",
    "join_elements",
    "normal_load_history",
    "normal_sweep",
    "tangential_sweep",
    "predict",
    "read_nodes",
    "read_preloads",
    "read_record",
    "read_topography",
    "reduce_preloads",
    "sine_history",
    "student_t_975",
    "valanis_integrate",
    "write_preloads",
]

# ---------------------------------------------------------------- surfaces

@final
class Surface:
    """Heights (m) on a regular grid, ``heights[i, j]`` at ``(i·dx_m, j·dy_m)``.

    ``periodic``: the patch is one period of an infinite surface (periodic contact kernel);
    otherwise a finite window (zero-padded kernel). Immutable; ``heights`` is a read-only view.
    """

    def __new__(
        cls, heights: F64Array, dx_m: float, dy_m: Optional[float] = None, periodic: bool = False
    ) -> "Surface":
        """From heights (m), shape (nx, ny), spacings (m; ``dy_m`` defaults to ``dx_m``).
        Copies the heights once. NaN/inf raise ``ParameterError`` naming the grid point."""
    @staticmethod
    def from_topography(t: Any) -> "Surface":
        """From a SurfaceTopography ``Topography`` (duck-typed: ``heights()``,
        ``physical_sizes``, ``nb_grid_pts``, ``unit``, ``is_periodic``), converted to metres."""
    @staticmethod
    def generate(
        *,
        rq_m: float = 0.177e-6,
        clx_m: float = 6.6e-6,
        cly_m: Optional[float] = None,
        lx_m: float = 250e-6,
        ly_m: Optional[float] = None,
        nx: int = 1024,
        ny: Optional[int] = None,
        seed: int = 1,
    ) -> "Surface":
        """Periodic Gaussian patch: RMS height ``rq_m``, 1/e correlation lengths ``clx_m``,
        ``cly_m`` (m), size ``lx_m`` × ``ly_m`` (m), ``nx`` × ``ny`` points, ChaCha8 ``seed``.
        Defaults: the reference case. Bit-identical to ``asperity surface generate``."""
    @staticmethod
    def read(path: Path) -> "Surface":
        """Read a height map (``.npy`` + ``.npy.json`` sidecar, ``.x3p``, height-matrix text)."""
    def write(self, path: Path) -> None:
        """Write (``.npy``, ``.x3p``, ``.csv``/``.txt``/``.asc``, ``.png``), atomically."""
    @property
    def heights(self) -> F64Array:
        """Heights (m), shape (nx, ny); read-only view, no copy."""
    @property
    def dx_m(self) -> float: ...
    @property
    def dy_m(self) -> float: ...
    @property
    def periodic(self) -> bool: ...
    @property
    def shape(self) -> Tuple[int, int]: ...
    @property
    def size_m(self) -> Tuple[float, float]:
        """(nx·dx, ny·dy) (m)."""
    def stats(self, detrend: str = "mean") -> "SurfaceStats":
        """Ra, Rq (m), Rsk, Rku, rms slopes/gradient, correlation lengths (m), ...: those of
        ``asperity surface stats --json``. ``detrend``: "mean" or "plane"."""
    def power_spectrum(self, detrend: str = "mean") -> "PowerSpectrum":
        """Radially averaged PSD (``c`` in m⁴, ``dim`` 2)."""

@final
class Profile:
    """A 1-D line scan (heights in m), as read from a Dektak CSV or a profile text file."""

    @property
    def heights(self) -> F64Array: ...
    @property
    def positions_m(self) -> Optional[F64Array]:
        """Measured positions (m) of a nonuniform profile, else None."""
    @property
    def dx_m(self) -> float: ...
    @property
    def periodic(self) -> bool: ...
    def stats(self, detrend: str = "mean") -> "SurfaceStats": ...
    def power_spectrum(self, detrend: str = "mean") -> "PowerSpectrum":
        """PSD (``c`` in m³, ``dim`` 1)."""
    def __len__(self) -> int: ...

def read_topography(path: Path) -> Union[Surface, Profile]:
    """Any readable topography file: a ``Surface`` (area) or a ``Profile`` (line scan)."""

def composite_modulus(
    youngs_modulus_pa: float,
    poisson_ratio: float,
    youngs_modulus_2_pa: Optional[float] = None,
    poisson_ratio_2: Optional[float] = None,
) -> float:
    """E* (Pa): 1/E* = (1-ν1²)/E1 + (1-ν2²)/E2 (body 2 defaults to body 1)."""

def equivalent_surface(body1: Surface, body2: Surface) -> Surface:
    """h1 − h2 on a common grid: the equivalent rough surface against a flat half-space."""

# ---------------------------------------------------------------- normal contact

@final
class SurfaceStats:
    """Statistics of a topography (SI units; None where undefined)."""

    @property
    def kind(self) -> str:
        """"profile" or "area"."""
    @property
    def uniform(self) -> bool: ...
    @property
    def periodic(self) -> bool: ...
    @property
    def detrend(self) -> str:
        """"mean" or "plane"."""
    @property
    def nx(self) -> int: ...
    @property
    def ny(self) -> int: ...
    @property
    def missing_points(self) -> int: ...
    @property
    def dx_m(self) -> float: ...
    @property
    def dy_m(self) -> Optional[float]:
        """None for a profile."""
    @property
    def lx_m(self) -> float: ...
    @property
    def ly_m(self) -> Optional[float]: ...
    @property
    def ra_m(self) -> float:
        """Ra (m)."""
    @property
    def rq_m(self) -> float:
        """Rq (m)."""
    @property
    def rsk(self) -> float: ...
    @property
    def rku(self) -> float: ...
    @property
    def rms_slope(self) -> float:
        """Along x."""
    @property
    def rms_slope_y(self) -> Optional[float]: ...
    @property
    def rms_gradient(self) -> Optional[float]: ...
    @property
    def correlation_length_1_over_e_m(self) -> Optional[float]: ...
    @property
    def correlation_length_0_2_m(self) -> Optional[float]: ...
    @property
    def correlation_length_x_1_over_e_m(self) -> Optional[float]: ...
    @property
    def correlation_length_y_1_over_e_m(self) -> Optional[float]: ...

@final
class PowerSpectrum:
    """A power spectral density, radially averaged for areas."""

    @property
    def dim(self) -> int:
        """1 (profile) or 2 (area)."""
    @property
    def q_rad_per_m(self) -> F64Array:
        """Angular wavenumbers, bin centres (rad/m)."""
    @property
    def c(self) -> F64Array:
        """PSD: m³ (profile) or m⁴ (area)."""
    @property
    def count(self) -> npt.NDArray[np.uint64]:
        """Fourier coefficients per bin."""

@final
class NormalSolution:
    """A converged normal-contact solution (SI). Arrays are read-only views (no copy)."""

    @property
    def pressure(self) -> F64Array:
        """Contact pressure (Pa), shape (nx, ny); 0 outside the contact."""
    @property
    def gap(self) -> F64Array:
        """Gap g = h0 − δ + u (m), ≥ 0, 0 in contact."""
    @property
    def displacement(self) -> F64Array:
        """Elastic surface displacement u = K ⊛ p (m), both bodies combined."""
    @property
    def spacing_m(self) -> Tuple[float, float]: ...
    @property
    def hardness_pa(self) -> Optional[float]:
        """Hardness H that bounded the pressure (Pa); None for elastic contact."""
    @property
    def elastic_points(self) -> int:
        """Grid points in elastic contact, 0 < p < H."""
    @property
    def plastic_points(self) -> int:
        """Grid points in plastic contact, p = H."""
    @property
    def elastic_area_ratio(self) -> float: ...
    @property
    def plastic_area_ratio(self) -> float: ...
    @property
    def plastic_volume_m3(self) -> float:
        """Plastically displaced volume (m³)."""
    def plastic_penetration(self) -> F64Array:
        """max(−g, 0) at the plastic points, 0 elsewhere (m): the residual surface after
        unloading is the heights minus it."""
    @property
    def periodic(self) -> bool: ...
    @property
    def mean_pressure_pa(self) -> float: ...
    @property
    def contact_area_ratio(self) -> float:
        """Real over nominal contact area (-)."""
    @property
    def contact_points(self) -> int: ...
    @property
    def contact_spots(self) -> int: ...
    @property
    def smallest_spot_points(self) -> int: ...
    @property
    def median_spot_points(self) -> int: ...
    @property
    def mean_gap_m(self) -> float:
        """Mean separation of the surfaces (m)."""
    @property
    def approach_m(self) -> float:
        """Rigid approach from first contact of the highest point (m)."""
    @property
    def elastic_energy_j(self) -> float: ...
    @property
    def iterations(self) -> int: ...
    @property
    def residual(self) -> float:
        """Final relative gap error ε (-)."""
    @property
    def converged(self) -> bool: ...
    @property
    def wall_time_s(self) -> float: ...
    @property
    def convergence(self) -> "Convergence": ...

@final
class Convergence:
    """How a normal solve converged."""

    @property
    def iterations(self) -> int: ...
    @property
    def residual(self) -> float:
        """Final relative residual."""
    @property
    def tolerance(self) -> float: ...
    @property
    def converged(self) -> bool: ...
    @property
    def wall_time_s(self) -> float: ...

@final
class NormalSolver:
    """Normal contact solver of one surface against an elastic half-space (E* in Pa):
    projected CG, preconditioned or Polonsky–Keer (``method`` "auto", "preconditioned",
    "polonsky-keer").

    Plan and kernel are built once; solves release the GIL. Reaching ``max_iterations`` raises
    ``ConvergenceError``."""

    def __new__(
        cls,
        surface: Surface,
        *,
        e_star_pa: float,
        hardness_pa: Optional[float] = None,
        tolerance: float = 1e-10,
        max_iterations: int = 5000,
        method: str = "auto",
    ) -> "NormalSolver":
        """``hardness_pa``: elastic–perfectly plastic contact, pressure ≤ H (Pa)."""
    def solve_load(
        self, mean_pressure_pa: float, warm_start: Optional[NormalSolution] = None
    ) -> NormalSolution:
        """Load control at mean pressure p̄ (Pa) over the patch."""
    def solve_approach(
        self, approach_m: float, warm_start: Optional[NormalSolution] = None
    ) -> NormalSolution:
        """Displacement control at rigid approach δ (m) from first contact."""
    def loading_stiffness(self, solution: NormalSolution) -> float:
        """Loading tangent dp̄/dδ (N/m³) of a hardness-limited solution (plastic points held at
        H); ``contact_stiffness`` is the unloading/reloading one an element carries."""
    def contact_stiffness(self, solution: NormalSolution) -> float:
        """kn = dp̄/dδ (N/m³) of a converged solution of this solver, from the tangent problem
        on its contact set (one linear solve; what ``normal_sweep`` and ``calibrate`` use)."""
    def displacement_of(self, pressure: F64Array) -> F64Array:
        """u = K ⊛ p (m) for a pressure field (Pa) on this grid."""
    @property
    def shape(self) -> Tuple[int, int]: ...
    @property
    def e_star_pa(self) -> float: ...
    @property
    def tolerance(self) -> float: ...
    @property
    def max_iterations(self) -> int: ...

def normal_sweep(
    surface: Surface,
    pressures_pa: Sequence[float],
    *,
    e_star_pa: float,
    hardness_pa: Optional[float] = None,
    tolerance: float = 1e-10,
    max_iterations: int = 5000,
    method: str = "auto",
) -> Columns:
    """Warm-started pressure sweep with kn = dp̄/dδ (N/m³) from the tangent problem.

    Columns, as in ``normal_sweep.csv``: pressure_Pa, contact_area_ratio, mean_gap_m,
    kn_N_per_m3, approach_m, contact_spots, smallest_spot_points, median_spot_points,
    points_across_contact, points_across_free, method (list of str), iterations,
    stiffness_iterations, residual, wall_time_s (numpy arrays)."""

# ---------------------------------------------------------------- tangential contact

@final
class TangentialSolver:
    """Coulomb partial slip with history on a fixed pressure field (quasi-identical materials)."""

    def __new__(
        cls,
        pressure: Union[NormalSolution, F64Array],
        *,
        friction_coefficient: float,
        spacing_m: Optional[Tuple[float, float]] = None,
        periodic: Optional[bool] = None,
        youngs_modulus_pa: float = 210e9,
        poisson_ratio: float = 0.3,
        youngs_modulus_2_pa: Optional[float] = None,
        poisson_ratio_2: Optional[float] = None,
        tolerance: float = 1e-6,
        max_iterations: int = 20000,
        operator: str = "auto",
    ) -> "TangentialSolver":
        """``pressure``: a NormalSolution, or pressures (Pa, (nx, ny)) with ``spacing_m`` and
        ``periodic``. ``operator``: "auto", "dense" or "fft"."""
    def step(
        self,
        *,
        displacement_m: Optional[Tuple[float, float]] = None,
        force_n: Optional[Tuple[float, float]] = None,
    ) -> "TangentialStep":
        """One step imposing a rigid shift (m) or a total tangential force (N)."""
    def oscillate(
        self,
        *,
        amplitude_m: Optional[Tuple[float, float]] = None,
        amplitude_n: Optional[Tuple[float, float]] = None,
        cycles: int = 3,
        steps_per_cycle: int = 40,
    ) -> "OscillationResult":
        """Sinusoidal history from the virgin state (step 0 = unloaded)."""
    def amplitude_loops(self, factors: Sequence[float], steps_per_cycle: int = 40) -> "AmplitudeHistory":
        """The calibration's history of increasing amplitudes (factors × gross-slip
        displacement); per amplitude the steady loop and its fit data (``fit_q``, ``fit_force``,
        ``steady``)."""
    def gross_slip_displacement(self, direction: Tuple[float, float] = (1.0, 0.0)) -> float:
        """Shift (m) at which every contact point slips."""
    def traction(self) -> Tuple[F64Array, F64Array]:
        """Shear tractions (qx, qy) (Pa), shape (nx, ny)."""
    def stick_mask(self) -> npt.NDArray[np.bool_]: ...
    def reset(self) -> None: ...
    @property
    def friction_limit_n(self) -> float:
        """μP (N)."""
    @property
    def metadata(self) -> "TangentialMetadata": ...

@final
class TangentialStep:
    """One tangential load step (SI)."""

    @property
    def shift_m(self) -> Tuple[float, float]:
        """Rigid shift (dx, dy) (m)."""
    @property
    def force_n(self) -> Tuple[float, float]:
        """Total tangential force (Tx, Ty) (N)."""
    @property
    def mean_shear_pa(self) -> Tuple[float, float]: ...
    @property
    def stick_fraction(self) -> float: ...
    @property
    def accumulated_slip_m(self) -> float: ...
    @property
    def frictional_work_j(self) -> float: ...
    @property
    def iterations(self) -> int: ...
    @property
    def residual(self) -> float: ...
    @property
    def converged(self) -> bool: ...
    @property
    def wall_time_s(self) -> float: ...

@final
class CycleEnergy:
    """Energy of one load cycle."""

    @property
    def cycle(self) -> int:
        """1-based; cycle 1 includes the initial loading branch."""
    @property
    def dissipated_j(self) -> float:
        """Loop area (J)."""
    @property
    def dissipated_j_per_m2(self) -> float: ...
    @property
    def frictional_work_j(self) -> float: ...

@final
class TangentialMetadata:
    """Set-up facts of a tangential solver."""

    @property
    def assumption(self) -> str: ...
    @property
    def friction_coefficient(self) -> float: ...
    @property
    def grid(self) -> Tuple[int, int]: ...
    @property
    def boundary(self) -> str: ...
    @property
    def operator(self) -> str: ...
    @property
    def contact_points(self) -> int: ...
    @property
    def normal_force_n(self) -> float: ...
    @property
    def nominal_area_m2(self) -> float: ...
    @property
    def compliance_norm_m_per_pa(self) -> float: ...
    @property
    def setup_time_s(self) -> float: ...

@final
class OscillationResult:
    """A sinusoidal tangential history (the results of ``asperity contact tangential``)."""

    @property
    def steps(self) -> Columns:
        """Columns per step: displacement_m, displacement_y_m, force_N, force_y_N,
        mean_shear_stress_Pa, mean_shear_stress_y_Pa, stick_fraction, accumulated_slip_m,
        frictional_work_J, iterations, residual, wall_time_s."""
    @property
    def cycles(self) -> List[CycleEnergy]: ...
    @property
    def metadata(self) -> TangentialMetadata: ...
    @property
    def wall_time_s(self) -> float: ...

@final
class VaryingLoadCheck:
    """The table's element, its refit and the load-following element against the contact solver
    under the varying normal load at one pressure (``tangential_element.csv``); energies per
    cycle in J/m²."""

    @property
    def table_params(self) -> ValanisParams: ...
    @property
    def table_fit_r2(self) -> float: ...
    @property
    def bem_constant_energy_j_per_m2(self) -> float: ...
    @property
    def bem_energy_j_per_m2(self) -> float: ...
    @property
    def element_energy_j_per_m2(self) -> float: ...
    @property
    def energy_rel_error(self) -> float: ...
    @property
    def r2(self) -> float: ...
    @property
    def element_shear_pa(self) -> F64Array: ...
    @property
    def normal_pressure_pa(self) -> F64Array: ...
    @property
    def refit_params(self) -> ValanisParams: ...
    @property
    def refit_r2(self) -> float: ...
    @property
    def refit_energy_rel_error(self) -> float: ...
    @property
    def load_following_loads_pa(self) -> list[float]: ...
    @property
    def load_following_params(self) -> list[ValanisParams]: ...
    @property
    def load_following_energy_j_per_m2(self) -> float: ...
    @property
    def load_following_energy_rel_error(self) -> float: ...
    @property
    def load_following_r2(self) -> float: ...

@final
class TangentialSweepResult:
    """A tangential sweep: one loop history per nominal pressure."""

    @property
    def source(self) -> str: ...
    @property
    def e_star_pa(self) -> float: ...
    @property
    def friction_coefficient(self) -> float: ...
    @property
    def hardness_pa(self) -> Optional[float]: ...
    @property
    def pressures_pa(self) -> List[float]: ...
    @property
    def contact_area_ratios(self) -> List[float]: ...
    @property
    def plastic_area_ratios(self) -> List[float]: ...
    @property
    def amplitude_m(self) -> float: ...
    @property
    def amplitude_note(self) -> str: ...
    @property
    def results(self) -> List[OscillationResult]: ...
    @property
    def element_checks(self) -> List[VaryingLoadCheck]: ...
    @property
    def edge_warning(self) -> Optional[str]: ...
    @property
    def written(self) -> List[str]: ...

def tangential_sweep(
    *,
    pressures_pa: Optional[Sequence[float]] = None,
    friction_coefficient: float = 0.6,
    amplitude_m: Optional[float] = None,
    cycles: int = 3,
    steps_per_cycle: int = 40,
    grid: Optional[int] = None,
    surface: Optional[Sequence[Path]] = None,
    youngs_modulus_pa: float = 210e9,
    poisson_ratio: float = 0.3,
    hardness_pa: Optional[str] = None,
    normal_amplitude_ratio: float = 0.0,
    normal_phase_deg: float = 0.0,
    direction_deg: float = 0.0,
    path_minor_ratio: float = 0.0,
    tolerance: Optional[float] = None,
    max_iterations: Optional[int] = None,
    operator: str = "auto",
    out_dir: Optional[Path] = None,
) -> TangentialSweepResult:
    """``asperity contact tangential`` as one call: normal contact at each pressure, then the
    sinusoidal partial-slip history (hardness-limited, varying normal load, in-plane path as
    the keywords say). With ``out_dir`` the command's files are written there."""

@final
class AmplitudeLoop:
    """One amplitude's steady loop and the data the calibration fits."""

    @property
    def amplitude_factor(self) -> float: ...
    @property
    def amplitude_m(self) -> float: ...
    @property
    def displacement_m(self) -> F64Array: ...
    @property
    def shear_stress_pa(self) -> F64Array: ...
    @property
    def loop_area_j_per_m2(self) -> float: ...
    @property
    def dissipation_j_per_m2(self) -> float: ...
    @property
    def closure_error(self) -> float: ...
    @property
    def fit_q(self) -> F64Array: ...
    @property
    def fit_force(self) -> F64Array: ...
    @property
    def steady(self) -> Tuple[int, int]:
        """[start, end) of the steady cycle in ``fit_q``."""

@final
class AmplitudeHistory:
    """The calibration's history of increasing amplitudes."""

    @property
    def gross_slip_displacement_m(self) -> float: ...
    @property
    def steps(self) -> int: ...
    @property
    def loops(self) -> List[AmplitudeLoop]: ...

# ---------------------------------------------------------------- Valanis element

@final
class LoopFit:
    """How well a fitted element reproduces one loop."""

    @property
    def r2(self) -> float: ...
    @property
    def nrmse(self) -> float: ...
    @property
    def energy_data(self) -> float: ...
    @property
    def energy_model(self) -> float: ...
    @property
    def energy_rel_error(self) -> float:
        """energy_model / energy_data − 1."""

@final
class ValanisParams:
    """Valanis element, in the order of the Rust constructor: e0 (N/m³ per area or N/m per
    element), 0 ≤ k < 1, 0 ≤ et < e0, mu > 0."""

    def __new__(cls, e0: float, k: float, et: float, mu: float) -> "ValanisParams": ...
    @property
    def e0(self) -> float: ...
    @property
    def k(self) -> float: ...
    @property
    def et(self) -> float: ...
    @property
    def mu(self) -> float: ...
    @property
    def reload_slope(self) -> float:
        """2·E0/(1+k)."""
    def slip_limit(self, fz: float) -> float:
        """μ·Fz·(1 − Et/E0)."""

def valanis_integrate(
    params: ValanisParams,
    q: F64Array,
    fz: Union[F64Array, float],
    method: str = "implicit-euler",
) -> F64Array:
    """Force history of a virgin element driven by displacements q (m) under normal load fz
    (Pa or N; array or constant; fz ≤ 0 is separation). ``method``: "implicit-euler" or
    "reference"."""

def normal_load_history(n0: float, kn: float, uz: F64Array) -> F64Array:
    """Fz = max(0, N0 + kn·uz)."""

def dissipated_energy(q: F64Array, f: F64Array) -> float:
    """∮ F dq over one closed cycle (trapezoidal)."""

def sine_history(amplitude: float, cycles: int, points_per_cycle: int) -> F64Array:
    """amplitude·sin(2π i / points_per_cycle), i = 0 … cycles·points_per_cycle."""

@final
class ValanisFit:
    @property
    def params(self) -> ValanisParams: ...
    @property
    def r2(self) -> float: ...
    @property
    def nrmse(self) -> float: ...
    @property
    def energy_data(self) -> float: ...
    @property
    def energy_model(self) -> float: ...
    @property
    def energy_rel_error(self) -> float: ...
    @property
    def model_force(self) -> F64Array: ...
    @property
    def loops(self) -> List["LoopFit"]: ...
    @property
    def iterations(self) -> int: ...
    @property
    def final_cost(self) -> float: ...
    @property
    def converged(self) -> bool: ...
    @property
    def wall_time_s(self) -> float: ...

def fit_valanis(
    q: F64Array,
    force: F64Array,
    normal_load: Union[F64Array, float],
    steady: Tuple[int, int],
    *,
    mu: float,
    fit_et: bool = False,
    max_iterations: int = 600,
    k_starts: Sequence[float] = (0.1, 0.5, 0.9),
) -> ValanisFit:
    """Least-squares E0, k (and Et) with μ fixed, measured on samples [start, stop)."""

def fit_valanis_loops(
    loops: Sequence[Tuple[F64Array, F64Array, Union[F64Array, float], Tuple[int, int]]],
    *,
    mu: float,
    fit_et: bool = False,
    max_iterations: int = 600,
    k_starts: Sequence[float] = (0.1, 0.5, 0.9),
) -> ValanisFit:
    """One element fitted to several loops together (mean of 1 − R²)."""

def student_t_975(dof: float) -> float:
    """Two-sided 95 % quantile of Student's t."""

# ---------------------------------------------------------------- calibration table, elements

@final
class CalibrationTable:
    """kn, E0, Et (N/m³), k, μ, area ratio, fit R², energy per cycle (J/m²) versus pressure (Pa)."""

    @staticmethod
    def read_csv(path: Path) -> "CalibrationTable": ...
    def write_csv(self, path: Path) -> None: ...
    def columns(self) -> Columns:
        """Columns named as in the CSV header."""
    @property
    def pressure_range(self) -> Tuple[float, float]: ...
    @overload
    def interpolate(self, pressure_pa: float) -> "TableValues": ...
    @overload
    def interpolate(self, pressure_pa: F64Array) -> "TableColumns":
        """Monotone cubic in ln p; outside the table the end pair's power law for kn, E0 and the
        contact area ratio (Et keeps Et/E0, k and μ the end row's); ``range``: −1 below,
        0 within, +1 above."""
    def __len__(self) -> int: ...

@final
class TableValues:
    """Element parameters the table gives at one pressure (per unit area, N/m³)."""

    @property
    def pressure_pa(self) -> float: ...
    @property
    def contact_area_ratio(self) -> float: ...
    @property
    def kn_n_per_m3(self) -> float: ...
    @property
    def e0_n_per_m3(self) -> float: ...
    @property
    def k(self) -> float: ...
    @property
    def mu(self) -> float: ...
    @property
    def et_n_per_m3(self) -> float: ...
    @property
    def range(self) -> int:
        """−1 below, 0 within, +1 above the table's pressures."""

@final
class TableColumns:
    """Element parameters the table gives at each of several pressures: float64 arrays
    (N/m³ per unit area), ``range`` int8."""

    @property
    def pressure_pa(self) -> F64Array: ...
    @property
    def contact_area_ratio(self) -> F64Array: ...
    @property
    def kn_n_per_m3(self) -> F64Array: ...
    @property
    def e0_n_per_m3(self) -> F64Array: ...
    @property
    def k(self) -> F64Array: ...
    @property
    def mu(self) -> F64Array: ...
    @property
    def et_n_per_m3(self) -> F64Array: ...
    @property
    def range(self) -> "npt.NDArray[np.int8]":
        """−1 below, 0 within, +1 above the table's pressures."""
    def __len__(self) -> int: ...

def calibrate(
    config: Optional[Path] = None,
    *,
    grid: Optional[int] = None,
    realisations: Optional[int] = None,
    surface: Optional[Surface] = None,
    out_dir: Optional[Path] = None,
) -> "CalibrationRun":
    """The chain of ``asperity calibrate`` (surfaces → normal sweep → tangential loops at several
    amplitudes → Valanis fits → table with 95 % intervals, grid and patch checks) on the TOML
    ``config`` (None: the built-in reference case), ``grid``/``realisations`` overriding it, or
    on one given ``surface`` (heights in m). With ``out_dir`` the CLI's files, identical to its
    own on the same inputs (``calibration_timings.csv`` excepted).

    Returns a ``CalibrationRun``."""

@final
class CalibrationRun:
    """What ``calibrate`` produced."""

    @property
    def table(self) -> CalibrationTable:
        """Means per pressure (Pa); kn, E0, Et in N/m³."""
    @property
    def realisations(self) -> Columns:
        """Columns per realisation × pressure: realisation, seed (−1: given surface),
        pressure_Pa, contact_area_ratio, kn_N_per_m3, mean_gap_m, gross_slip_displacement_m (m),
        E0_N_per_m3, k, Et_N_per_m3, fit_R2, contact_spots, median_spot_points."""
    @property
    def convergence(self) -> "CalibrationConvergence":
        """The grid and patch checks per pressure, as in calibration.json."""
    @property
    def warnings(self) -> List[str]: ...
    @property
    def written(self) -> List[str]:
        """Files written into ``out_dir`` (empty without one)."""
    @property
    def times(self) -> "StageTimes":
        """Wall and CPU time of each stage (s)."""

@final
class StageTimes:
    """Wall and CPU time (s) of each stage of ``calibrate()``, summed over the chains."""

    @property
    def surface_s(self) -> float: ...
    @property
    def normal_s(self) -> float: ...
    @property
    def tangential_s(self) -> float: ...
    @property
    def fit_s(self) -> float: ...
    @property
    def surface_cpu_s(self) -> float: ...
    @property
    def normal_cpu_s(self) -> float: ...
    @property
    def tangential_cpu_s(self) -> float: ...
    @property
    def fit_cpu_s(self) -> float: ...
    @property
    def total_s(self) -> float:
        """Wall time of the whole run."""

@final
class CalibrationConvergence:
    """The grid and patch checks of ``calibrate()``."""

    @property
    def grid_spec(self) -> Optional["SurfaceSpec"]:
        """The grid check's surfaces (half the points per side); None: not run."""
    @property
    def patch_spec(self) -> Optional["SurfaceSpec"]:
        """The patch check's surfaces (half the patch side, same spacing); None: not run."""
    @property
    def notes(self) -> List[str]:
        """Why a check was not run."""
    @property
    def pressures(self) -> List["PressureConvergence"]: ...

@final
class SurfaceSpec:
    """A generated Gaussian surface: Rq, 1/e correlation lengths and patch (m), grid, seed."""

    @property
    def rq_m(self) -> float: ...
    @property
    def clx_m(self) -> float: ...
    @property
    def cly_m(self) -> float: ...
    @property
    def lx_m(self) -> float: ...
    @property
    def ly_m(self) -> float: ...
    @property
    def nx(self) -> int: ...
    @property
    def ny(self) -> int: ...
    @property
    def seed(self) -> int: ...

@final
class PressureConvergence:
    """Convergence facts and verdicts at one nominal pressure (Pa)."""

    @property
    def pressure_pa(self) -> float: ...
    @property
    def contact_spots(self) -> "SampleSummary": ...
    @property
    def median_spot_points(self) -> float: ...
    @property
    def min_median_spot_points(self) -> int: ...
    @property
    def under_resolved_realisations(self) -> int: ...
    @property
    def min_points_across(self) -> float: ...
    @property
    def narrowest_is_contact(self) -> bool: ...
    @property
    def grid(self) -> List["ConvergenceCheck"]:
        """kn, E0, k: n against n/2 points per side."""
    @property
    def patch(self) -> List["ConvergenceCheck"]:
        """kn, E0, k: patch L against L/2."""
    @property
    def grid_verdict(self) -> str: ...
    @property
    def patch_verdict(self) -> str: ...

@final
class ConvergenceCheck:
    """Change of a quantity (kn, E0 or k) from the coarser to the main configuration, with its
    95 % interval, against the allowed change; verdict ``converged``, ``undetermined``,
    ``not-converged`` or ``not-checked``."""

    @property
    def quantity(self) -> str: ...
    @property
    def change(self) -> float: ...
    @property
    def change_ci95(self) -> float: ...
    @property
    def tolerance(self) -> float: ...
    @property
    def verdict(self) -> str: ...

@final
class SampleSummary:
    """Mean, standard deviation and 95 % interval half-width over the realisations."""

    @property
    def n(self) -> int: ...
    @property
    def mean(self) -> float: ...
    @property
    def sd(self) -> float: ...
    @property
    def ci95(self) -> float: ...

def join_elements(
    preloads: Columns, table: CalibrationTable, out: Optional[Path] = None
) -> Tuple[Columns, "ElementSummary"]:
    """One element per preloaded node: kn, E0, Et (N/m) = table values × area, k, μ; columns as
    in ``asperity elements``' CSV (id, x_m, y_m, area_m2, pressure_Pa, N0_N, kn_N_per_m,
    E0_N_per_m, k, mu, Et_N_per_m, out_of_range) and a summary; nodes of zero pressure (open
    contact) are left out and counted (``n_open``, ``open_ids``, ``open_area_m2``)."""

@final
class ElementSummary:
    """Counts and totals of ``join_elements`` (areas m², loads N, pressures Pa)."""

    @property
    def n_elements(self) -> int: ...
    @property
    def n_open(self) -> int:
        """Nodes of zero pressure (open contact), left out."""
    @property
    def open_ids(self) -> List[int]: ...
    @property
    def open_area_m2(self) -> float: ...
    @property
    def n_below_range(self) -> int: ...
    @property
    def n_above_range(self) -> int: ...
    @property
    def below_range_ids(self) -> List[int]: ...
    @property
    def above_range_ids(self) -> List[int]: ...
    @property
    def not_converged_row_ids(self) -> List[int]:
        """Elements whose table rows were judged not converged in grid or patch size."""
    @property
    def undetermined_row_ids(self) -> List[int]: ...
    @property
    def total_area_m2(self) -> float: ...
    @property
    def total_load_n(self) -> float: ...
    @property
    def table_pressure_min_pa(self) -> float: ...
    @property
    def table_pressure_max_pa(self) -> float: ...
    @property
    def element_pressure_min_pa(self) -> float: ...
    @property
    def element_pressure_max_pa(self) -> float: ...

def read_preloads(path: Path) -> Columns:
    """Preload CSV → columns id, x_m, y_m, area_m2, pressure_Pa, N0_N."""

def write_preloads(path: Path, preloads: Columns, comment: str = "") -> None:
    """Preload CSV as ``asperity film`` writes it (with ``pixel_class`` when the columns have it)."""

# ---------------------------------------------------------------- film

@final
class Region:
    @property
    def id(self) -> int: ...
    @property
    def pixels(self) -> npt.NDArray[np.uint64]:
        """(i, j) pixel indices, shape (n, 2)."""
    def bounds_m(self, film_map: "FilmMap") -> List[float]:
        """[x0, x1, y0, y1] (m), pixel edges included."""
    def __len__(self) -> int: ...

@final
class PolyFit:
    @property
    def order(self) -> int: ...
    @property
    def coefficients_pa(self) -> F64Array: ...
    @property
    def exponents(self) -> List[Tuple[int, int]]: ...
    @property
    def r_squared(self) -> float: ...
    @property
    def rms_residual_pa(self) -> float: ...
    @property
    def n_points(self) -> int: ...
    @overload
    def __call__(self, x_m: float, y_m: float) -> float: ...
    @overload
    def __call__(self, x_m: F64Array, y_m: F64Array) -> F64Array:
        """Fitted pressure (Pa) at film points (m)."""

@final
class FilmMap:
    """Film image → per-pixel class and pressure (Pa). Frame: x right, y up, m, origin at the
    centre of the bottom-left pixel."""

    class_names: List[str]
    @staticmethod
    def read(
        image: Path,
        pixel_size_m: float,
        *,
        colour_table: Optional[Path] = None,
        density_calibration: Optional[Path] = None,
        max_colour_distance: float = 20.0,
    ) -> "FilmMap": ...
    @property
    def pressure_pa(self) -> F64Array:
        """Pressure (Pa), shape (nx, ny); NaN unless in range. Read-only view."""
    @property
    def pixel_class(self) -> npt.NDArray[np.uint8]:
        """Codes into ``class_names``."""
    @property
    def class_counts(self) -> "ClassCounts": ...
    @property
    def pixel_size_m(self) -> float: ...
    @property
    def shape(self) -> Tuple[int, int]: ...
    def detect_patches(
        self, min_diameter_m: float = 2e-3, rim_pixels: int = 3
    ) -> Tuple[List[Region], int]: ...
    def roi_rectangle(
        self, x0_m: float, y0_m: float, x1_m: float, y1_m: float, id: int = 1
    ) -> Region: ...
    def roi_polygon(self, vertices_m: Sequence[Tuple[float, float]], id: int = 1) -> Region: ...
    def summarise(self, region: Region) -> "RegionSummary": ...
    def fit(self, region: Region, order: int = 4) -> PolyFit: ...

@final
class ClassCounts:
    """Pixel counts per class."""

    @property
    def in_range(self) -> int: ...
    @property
    def unstained(self) -> int: ...
    @property
    def below_range(self) -> int: ...
    @property
    def above_range(self) -> int:
        """Saturated pixels."""
    @property
    def off_curve(self) -> int:
        """Pixels far from the colour curve (rejected)."""

@final
class RegionSummary:
    """Summary of a region of a film map (film frame, m; pressures in Pa)."""

    @property
    def id(self) -> int: ...
    @property
    def centre_x_m(self) -> float: ...
    @property
    def centre_y_m(self) -> float: ...
    @property
    def area_m2(self) -> float: ...
    @property
    def equivalent_diameter_m(self) -> float: ...
    @property
    def mean_pressure_pa(self) -> float:
        """NaN when no pixel is in range."""
    @property
    def max_pressure_pa(self) -> float: ...
    @property
    def in_range_load_n(self) -> float:
        """Load of the in-range pixels (N): a lower bound of the region's load."""
    @property
    def counts(self) -> ClassCounts: ...
    @property
    def saturated_fraction(self) -> float: ...

def read_nodes(path: Path) -> Columns:
    """Nodes CSV (mesh frame) → id, x_m, y_m, area_m2 (NaN where absent)."""

def film_preloads(
    film_map: FilmMap,
    region: Region,
    fit: PolyFit,
    nodes: Columns,
    *,
    offset_m: Tuple[float, float] = (0.0, 0.0),
    rotation_rad: float = 0.0,
    scale: float = 1.0,
    total_load_n: Optional[float] = None,
) -> Tuple[Columns, "PreloadSummary"]:
    """N0 = σ_fit(x, y)·A (N) per node placed on the film; optional rescale to a total load.

    The columns include ``pixel_class`` (list of str: in_range, above_range, below_range, hole),
    what the film says under each node, as ``preload.csv`` of ``asperity film``."""

@final
class PreloadSummary:
    """Totals of the node preloads: nodes, tributary area (m²), load before and after
    rescaling (N)."""

    @property
    def n_nodes(self) -> int: ...
    @property
    def total_area_m2(self) -> float: ...
    @property
    def raw_total_load_n(self) -> float: ...
    @property
    def total_load_n(self) -> float: ...
    @property
    def load_scale(self) -> float: ...
    @property
    def clamped_negative(self) -> int:
        """Nodes whose fitted pressure was negative, set to zero."""
    @property
    def areas_from_triangulation(self) -> bool: ...
    @property
    def gap_area_m2(self) -> float: ...
    @property
    def gap_triangles(self) -> int: ...

def reduce_preloads(preloads: Columns, mesh_size_m: float) -> Columns:
    """Keep one node per triangle of an h-mesh (m) with summed area and load."""

@final
class FilmSummary:
    """The ``summary`` of ``film.json``: pixel counts, regions, fits, what was left out, nodes."""

    @property
    def image_pixels(self) -> ClassCounts: ...
    @property
    def discarded_small_components(self) -> int: ...
    @property
    def rejected_marks(self) -> int: ...
    @property
    def below_range_patches(self) -> List["BelowRangePatch"]: ...
    @property
    def regions_not_fitted(self) -> List["NotFitted"]: ...
    @property
    def regions(self) -> List[RegionSummary]: ...
    @property
    def fits(self) -> List[Optional[PolyFit]]: ...
    @property
    def nodes(self) -> Optional["NodeSummary"]: ...

@final
class BelowRangePatch:
    """A stained component entirely below the film's range (film frame, m)."""

    @property
    def centre_x_m(self) -> float: ...
    @property
    def centre_y_m(self) -> float: ...
    @property
    def equivalent_diameter_m(self) -> float: ...

@final
class NotFitted:
    """A region (1-based id) that could not be fitted, and why."""

    @property
    def region(self) -> int: ...
    @property
    def reason(self) -> str: ...

@final
class NodeSummary:
    """The nodes of a film run: region, placement, preload totals, readings per pixel class,
    reduction."""

    @property
    def region(self) -> int: ...
    @property
    def placement(self) -> "NodePlacement": ...
    @property
    def preloads(self) -> PreloadSummary: ...
    @property
    def pixel_classes(self) -> List["NodeClassReading"]: ...
    @property
    def reduction(self) -> Optional["ReductionSummary"]: ...

@final
class NodePlacement:
    """Mesh frame → film frame: offset (m), counter-clockwise rotation (rad), scale."""

    @property
    def offset_x_m(self) -> float: ...
    @property
    def offset_y_m(self) -> float: ...
    @property
    def rotation_rad(self) -> float: ...
    @property
    def scale(self) -> float: ...

@final
class NodeClassReading:
    """Nodes on one film pixel class and the fitted pressure under them (Pa)."""

    @property
    def pixel_class(self) -> str:
        """in_range, above_range, below_range or hole."""
    @property
    def n_nodes(self) -> int: ...
    @property
    def fitted_pressure_min_pa(self) -> Optional[float]: ...
    @property
    def fitted_pressure_max_pa(self) -> Optional[float]: ...

@final
class ReductionSummary:
    """The reduction on a coarse mesh of side ``mesh_size_m`` (m): nodes kept, area (m²), load (N)."""

    @property
    def mesh_size_m(self) -> float: ...
    @property
    def n_kept(self) -> int: ...
    @property
    def total_area_m2(self) -> float: ...
    @property
    def total_load_n(self) -> float: ...

@final
class FilmResult:
    """What ``film()`` found: the pressure map, its regions with summaries and fits, the node
    preloads and their reduction, and the run's notes and warnings."""

    @property
    def film_map(self) -> FilmMap: ...
    @property
    def regions(self) -> List[Region]: ...
    @property
    def fits(self) -> List[Optional[PolyFit]]:
        """The fit of each region, ``None`` where it could not be fitted."""
    @property
    def summaries(self) -> List["RegionSummary"]: ...
    @property
    def pixel_size_m(self) -> float: ...
    @property
    def pixel_size_source(self) -> str: ...
    @property
    def range_pa(self) -> Tuple[float, float]: ...
    @property
    def preloads(self) -> Optional[Columns]:
        """With nodes: id, x_m, y_m, area_m2, pressure_Pa, N0_N and pixel_class (``preload.csv``)."""
    @property
    def reduced_preloads(self) -> Optional[Columns]:
        """With a reduction mesh: the reduced preloads (``preload_reduced.csv``)."""
    @property
    def summary(self) -> "FilmSummary":
        """The ``summary`` of ``film.json``."""
    @property
    def messages(self) -> List[str]:
        """Notes and warnings, in order (the CLI prints them to stderr)."""
    @property
    def written(self) -> List[Path]: ...

def film(
    image: Path,
    *,
    pixel_size_mm: Optional[float] = None,
    colour_table: Optional[Path] = None,
    density_calibration: Optional[Path] = None,
    max_colour_distance: float = 20.0,
    channel: str = "luma",
    stain_rgb: Optional[Sequence[float]] = None,
    unstained_density: Optional[float] = None,
    smooth_mm: Optional[float] = None,
    roi_rect_mm: Optional[Sequence[float]] = None,
    roi_polygon_mm: Optional[Sequence[Tuple[float, float]]] = None,
    min_patch_diameter_mm: float = 2.0,
    rim_pixels: int = 3,
    max_elongation: float = 3.0,
    min_solidity: float = 0.6,
    fit_order: int = 4,
    nodes: Optional[Path] = None,
    nodes_region: Optional[int] = None,
    node_offset_mm: Optional[Tuple[float, float]] = None,
    node_rotation_deg: float = 0.0,
    node_scale: float = 1.0,
    total_load_n: Optional[float] = None,
    reduce_mesh_size_mm: Optional[float] = None,
    out_dir: Optional[Path] = None,
) -> FilmResult:
    """The pipeline of ``asperity film`` (the library function the CLI calls), keyword arguments
    named after its flags (lengths on the film in mm, rotation in degrees). With ``out_dir``,
    writes the command's files there."""

# ---------------------------------------------------------------- forced response

@final
class ResponseModel:
    """Linear structure with contact elements, excitation and observed responses, for the
    multi-harmonic-balance forced response of ``asperity response`` (AFT, pseudo-arclength
    continuation). SI units: kg, N·s/m, N/m, N, m, Hz."""

    @staticmethod
    def read(path: Path) -> "ResponseModel":
        """The model file (TOML) of ``asperity response``, read as the CLI reads it."""
    @staticmethod
    def lumped(
        labels: Sequence[str],
        mass: F64Array,
        damping: F64Array,
        stiffness: F64Array,
        force: F64Array,
        *,
        harmonic: int = 1,
        responses: Optional[Dict[str, F64Array]] = None,
    ) -> "ResponseModel":
        """Lumped model: (n, n) symmetric M (kg, positive definite), C (N·s/m, positive
        semi-definite), K (N/m, positive definite); ``force`` (n,) N per unit level, applied as
        level·force·cos(harmonic·ωt); ``responses``: label → observation row (n,) (default:
        every coordinate)."""
    @staticmethod
    def modal(
        frequencies_hz: Sequence[float],
        damping_ratios: Sequence[float],
        force: F64Array,
        *,
        harmonic: int = 1,
        responses: Optional[Dict[str, F64Array]] = None,
    ) -> "ResponseModel":
        """Mass-normalised modal model; ``force`` the modal force Φᵀf per unit level."""
    def attach_jenkins(self, label: str, kt_n_per_m: float, slip_force_n: float, map: F64Array) -> None:
        """1-D Jenkins element; ``map`` (1, n): its displacement per coordinate."""
    def attach_cubic_spring(self, label: str, k3_n_per_m3: float, map: F64Array) -> None:
        """f = k3·u³; ``map`` (1, n)."""
    def attach_valanis_contact(
        self, label: str, params: ValanisParams, kn_n_per_m: float, n0_n: float, map: F64Array
    ) -> None:
        """3-D Valanis microslip contact (E0, Et in N/m, kn in N/m, preload N0 in N) of the
        element table; ``map`` (3, n): local (t1, t2, n) displacements per coordinate."""
    def attach_jenkins_contact(
        self, label: str, kt_n_per_m: float, mu: float, kn_n_per_m: float, n0_n: float, map: F64Array
    ) -> None:
        """3-D Jenkins contact with a unilateral normal spring; ``map`` (3, n)."""
    @property
    def labels(self) -> List[str]: ...
    @property
    def coordinates(self) -> str:
        """``"physical"`` or ``"modal"``."""
    @property
    def matrices(self) -> Dict[str, F64Array]:
        """mass (kg), damping (N·s/m), stiffness (N/m), (n, n) copies."""
    @property
    def force(self) -> F64Array: ...
    @property
    def response_labels(self) -> List[str]: ...
    @property
    def elements(self) -> List[Tuple[str, str, int]]:
        """(label, law, dofs) of each element."""
    @property
    def levels_n(self) -> Optional[List[float]]:
        """Excitation levels (N) of the model file; None for a model built from arrays."""
    def sweep(
        self,
        level_n: float,
        frequency_start_hz: Optional[float] = None,
        frequency_end_hz: Optional[float] = None,
        *,
        harmonics: Optional[int] = None,
        odd_only: Optional[bool] = None,
        time_samples: Optional[int] = None,
        points: Optional[int] = None,
        formulation: Optional[str] = None,
    ) -> "SweepResult":
        """Force-controlled frequency sweep at ``level_n`` (N) over [start, end] Hz (unset
        values: the model file's [sweep]; for array models harmonics 5, points 200, formulation
        "auto")."""
    def free_decay(
        self,
        amplitude_m: float,
        *,
        mode: int = 1,
        periods: int = 100,
        steps_per_period: int = 256,
    ) -> "DecayResult":
        """Free decay (ring-down) by Newmark time integration with the elements, from rest in
        the linearised (stuck) mode ``mode``, the first response starting at ``amplitude_m``
        (m); frequency and damping ratio per period (``asperity decay``)."""
    def nonlinear_mode(
        self,
        amplitude_min_m_sqrt_kg: float,
        amplitude_max_m_sqrt_kg: float,
        *,
        mode: int = 1,
        points: int = 60,
        harmonics: Optional[int] = None,
        odd_only: Optional[bool] = None,
        time_samples: Optional[int] = None,
    ) -> "NonlinearModeResult":
        """Nonlinear mode ``mode`` by the extended periodic motion concept (``asperity
        modes``): ``points`` modal amplitudes log-spaced between the two bounds (m·kg^½),
        continued from the linear mode with the elements stuck; harmonics as in ``sweep``."""

@final
class NonlinearModeResult:
    """A nonlinear mode (``asperity modes``): frequency, modal damping ratio, element energies
    and coordinate harmonics per modal amplitude."""

    @property
    def mode(self) -> int: ...
    @property
    def linear_frequency_hz(self) -> float: ...
    @property
    def linear_damping_ratio(self) -> float: ...
    @property
    def modal_amplitude_m_sqrt_kg(self) -> F64Array: ...
    @property
    def frequency_hz(self) -> F64Array: ...
    @property
    def damping_ratio(self) -> F64Array: ...
    @property
    def element_energy_j(self) -> F64Array:
        """Energy all elements dissipate per cycle (J)."""
    @property
    def energy_per_element_j(self) -> F64Array:
        """(points, elements) energy per cycle of every element (J)."""
    @property
    def coordinate_harmonics(self) -> F64Array:
        """(points, n, coefficients) harmonic coefficients of every coordinate (m)."""
    @property
    def harmonic_orders(self) -> List[int]: ...
    @property
    def stopped(self) -> Optional[str]:
        """Why the continuation stopped before the last amplitude; None when complete."""
    @property
    def wall_time_s(self) -> float: ...

@final
class DecayResult:
    """A free decay (``asperity decay``): the first response at every step, and frequency and
    damping ratio per period (one estimate per half period)."""

    @property
    def linear_frequency_hz(self) -> float: ...
    @property
    def time_s(self) -> F64Array: ...
    @property
    def response_m(self) -> F64Array: ...
    @property
    def cycle_time_s(self) -> F64Array: ...
    @property
    def cycle_amplitude_m(self) -> F64Array: ...
    @property
    def cycle_frequency_hz(self) -> F64Array: ...
    @property
    def cycle_damping_ratio(self) -> F64Array: ...
    @property
    def wall_time_s(self) -> float: ...

@final
class SweepResult:
    """One level's force-controlled sweep (the results of ``asperity response``)."""

    @property
    def columns(self) -> Columns:
        """The columns of response_level_<i>.csv: frequency_Hz, <dof>_h<k>_amplitude_m (m),
        <dof>_h<k>_phase_rad, dissipated_energy_J (J per cycle), stick/slip/separation
        fractions, newton_iterations, relative_residual."""
    @property
    def coordinate_harmonics(self) -> F64Array:
        """(points, n, coefficients) harmonic coefficients of every coordinate (m)."""
    @property
    def harmonic_orders(self) -> List[int]: ...
    @property
    def peak(self) -> int:
        """Index of the largest first-harmonic amplitude of the first response."""
    @property
    def peak_elements(self) -> Dict[str, Any]:
        """Columns per element at the peak: element, law, dissipated_energy_J, stick_fraction,
        slip_fraction, separation_fraction."""
    @property
    def level_n(self) -> float: ...
    @property
    def formulation(self) -> str:
        """``"coordinates"`` or ``"receptance"``."""
    @property
    def unknowns(self) -> int: ...
    @property
    def rejected_steps(self) -> int: ...
    @property
    def turning_points(self) -> int: ...
    @property
    def jacobians(self) -> int: ...
    @property
    def wall_time_s(self) -> float: ...

# ---------------------------------------------------------------- identify and diagnose

@final
class Record:
    """A measured hysteresis record (float64 arrays)."""

    @property
    def time_s(self) -> F64Array:
        """Sample times (s)."""
    @property
    def displacement_m(self) -> F64Array:
        """Tangential displacement (m)."""
    @property
    def force_n(self) -> F64Array:
        """Tangential force (N)."""
    @property
    def normal_force_n(self) -> Optional[F64Array]:
        """Normal force (N); None without a normal-force column."""
    @property
    def derived(self) -> List[str]:
        """How columns were derived from accelerations, one line each; empty when read as
        they are."""

def read_record(
    path: Path,
    *,
    time_column: str = "time_s",
    displacement_column: str = "displacement_m",
    force_column: str = "friction_force_N",
    normal_force_column: Optional[str] = None,
    relative_acceleration_column: Optional[str] = None,
    inertia_acceleration_column: Optional[str] = None,
    mass_kg: Optional[float] = None,
) -> Record:
    """Record CSV → time (s), displacement (m), force (N)[, normal force (N)].
    ``relative_acceleration_column`` (m/s²) instead of the displacement column: its double
    integral in the frequency domain; ``inertia_acceleration_column`` (m/s²) with ``mass_kg``
    instead of the force column: F = m·a (``asperity diagnose``'s flags of the same names)."""

@final
class DiagnoseErrors:
    """Errors of a model's force against the record, over all complete cycles."""

    @property
    def nrms(self) -> float:
        """RMS force residual / force amplitude."""
    @property
    def peak_force_error(self) -> float:
        """Mean absolute error of the cycles' maximum and minimum force / force amplitude."""
    @property
    def energy_error(self) -> float:
        """Mean |E_model − E_measured| / E_measured of the energy dissipated per cycle."""
    @property
    def held_out_nrms(self) -> float:
        """Normalised RMS force error on the held-out cycles."""
    @property
    def held_out_rms_over_noise(self) -> float:
        """RMS force residual on the held-out cycles / noise floor."""

@final
class DiagnoseReport:
    """The report of ``asperity diagnose``; ``json`` is its diagnose.json."""

    @property
    def verdict(self) -> str:
        """effect(s) found, model adequate, model inadequate, or undecided."""
    @property
    def conclusion(self) -> str: ...
    @property
    def effects_added(self) -> List[str]:
        """Effect ids, in the order accepted."""
    @property
    def errors_before(self) -> DiagnoseErrors:
        """Errors of the Valanis baseline."""
    @property
    def errors_after(self) -> DiagnoseErrors:
        """Errors of the final model."""
    @property
    def noise_sigma_n(self) -> float:
        """Noise floor of the force per sample (N)."""
    @property
    def samples_analysed(self) -> int: ...
    @property
    def complete_cycles(self) -> int: ...
    @property
    def training_cycles(self) -> List[int]:
        """0-based."""
    @property
    def held_out_cycles(self) -> List[int]:
        """0-based."""
    @property
    def text(self) -> str:
        """The report as diagnose.txt holds it."""
    @property
    def json(self) -> str:
        """The report as diagnose.json holds it (JSON text)."""
    @property
    def time_s(self) -> F64Array:
        """Sample times analysed (s)."""
    @property
    def displacement_m(self) -> F64Array:
        """Displacement analysed (m)."""
    @property
    def force_n(self) -> F64Array:
        """Measured force analysed (N)."""
    @property
    def baseline_force_n(self) -> F64Array:
        """Force of the baseline (N)."""
    @property
    def final_force_n(self) -> F64Array:
        """Force of the final model (N)."""

def diagnose(
    time_s: F64Array,
    displacement_m: F64Array,
    force_n: F64Array,
    normal_force_n: Optional[F64Array] = None,
    *,
    baseline: Optional[ValanisParams] = None,
    normal_n: Optional[float] = None,
    max_effects: int = 2,
    source: str = "numpy arrays",
) -> DiagnoseReport:
    """Valanis baseline (fitted, or ``baseline`` with ``normal_n``) → missing effect selected on
    held-out cycles → errors before and after: ``asperity diagnose`` on arrays."""

@final
class ParameterEstimate:
    """A parameter of an identified model, its value and 95 % interval (unit ``unit``)."""

    @property
    def name(self) -> str: ...
    @property
    def unit(self) -> str:
        """SI unit; "-" for a ratio."""
    @property
    def value(self) -> float: ...
    @property
    def lo_95(self) -> Optional[float]:
        """2.5 % quantile over the posterior ensemble; None without bands or on a bound."""
    @property
    def hi_95(self) -> Optional[float]:
        """97.5 % quantile; None as for ``lo_95``."""
    @property
    def at_bound(self) -> bool: ...

@final
class LevelError:
    """A model's errors on one measured level or file (relative to its measured peak)."""

    @property
    def file(self) -> str: ...
    @property
    def role(self) -> str:
        """``"fit"`` or ``"predicted"`` (held out)."""
    @property
    def mean_force_n(self) -> float:
        """Mean drive force amplitude (N)."""
    @property
    def resonance_measured_hz(self) -> float: ...
    @property
    def resonance_model_hz(self) -> float: ...
    @property
    def resonance_error_hz(self) -> Optional[float]:
        """Model minus measured (Hz); None where the measured peak is on the band's edge."""
    @property
    def phase_resonance_error_hz(self) -> float:
        """Model minus measured quadrature frequency (Hz; NaN where not available)."""
    @property
    def peak_measured(self) -> float:
        """Peak response per unit force (the level's quantity per N)."""
    @property
    def peak_model(self) -> float: ...
    @property
    def peak_error(self) -> float:
        """peak_model / peak_measured − 1."""
    @property
    def rms_complex(self) -> float:
        """RMS complex residual over the rows / peak."""
    @property
    def failed_rows(self) -> int: ...

@final
class IdentifyReport:
    """The report of ``asperity identify``."""

    @property
    def kind(self) -> str:
        """``"mode"`` (single nonlinear mode) or ``"reduced"`` (reduced model updated)."""
    @property
    def selected_effects(self) -> List[str]:
        """Effect ids the held-out evidence added, in the order accepted."""
    @property
    def verdict(self) -> str: ...
    @property
    def fit_levels(self) -> List[int]:
        """1-based, by increasing mean force."""
    @property
    def parameters(self) -> List[ParameterEstimate]:
        """The final model's parameters with their 95 % intervals."""
    @property
    def uncertainty_reason(self) -> Optional[str]:
        """Why the parameters have no intervals; None where they have."""
    @property
    def errors_before(self) -> List[LevelError]:
        """Per level: errors of the baseline (reduced: the model as given)."""
    @property
    def errors_after(self) -> List[LevelError]:
        """Per level: errors of the final model."""
    @property
    def held_out_errors(self) -> List[LevelError]:
        """Errors of the final model on the levels not fitted."""
    @property
    def text(self) -> str:
        """The report as identify.txt holds it."""
    @property
    def written(self) -> List[str]:
        """Files written into ``out_dir`` (empty without one)."""
    @property
    def wall_time_s(self) -> float: ...

def identify(
    files: Sequence[Path],
    *,
    fit_levels: Optional[Sequence[int]] = None,
    family: str = "jenkins",
    candidates: Optional[Sequence[str]] = None,
    max_effects: int = 3,
    thorough: bool = False,
    starts: Optional[int] = None,
    particles: Optional[int] = None,
    swarm_iterations: Optional[int] = None,
    local_iterations: Optional[int] = None,
    seed: int = 1,
    response_amplitude: Optional[Sequence[float]] = None,
    chain_steps: Optional[int] = None,
    rows: str = "all",
    structure: Optional[Path] = None,
    out_dir: Optional[Path] = None,
) -> IdentifyReport:
    """``asperity identify``: one measured sweep per level → identified nonlinear mode (or the
    reduced model of ``structure`` updated) → errors on the levels not used. Keywords follow the
    command's flags (errors name the flag); ``out_dir`` writes the command's files."""

@final
class FilePrediction:
    """A saved model's prediction of one measured file."""

    @property
    def file(self) -> str: ...
    @property
    def errors(self) -> LevelError: ...
    @property
    def force_rms_error(self) -> Optional[float]:
        """Response control: RMS of F_model/F_meas − 1; None under force control."""
    @property
    def peak_amplitude_m(self) -> float:
        """Largest drive-point displacement amplitude (m)."""
    @property
    def extrapolation(self) -> Optional[str]: ...
    @property
    def not_one_mode(self) -> Optional[str]: ...

@final
class PredictReport:
    """The report of ``asperity predict``."""

    @property
    def model_file(self) -> str: ...
    @property
    def control(self) -> str:
        """``"force"`` or ``"response"``."""
    @property
    def control_source(self) -> str: ...
    @property
    def convention_source(self) -> str: ...
    @property
    def files(self) -> List[FilePrediction]: ...
    @property
    def text(self) -> str:
        """The report as predict.txt holds it."""
    @property
    def written(self) -> List[str]: ...

def predict(
    model: Path,
    files: Sequence[Path],
    *,
    control: Optional[str] = None,
    out_dir: Optional[Path] = None,
) -> PredictReport:
    """``asperity predict``: score a saved model (model.json of ``identify``) on measured
    files; ``control`` "force" or "response" (default: the files' headers)."""
