"""asperity: rough-surface contact (boundary elements) and microslip-element calibration.

A thin Python layer over the Rust library ``asperity``: numpy arrays in and out, SI units
throughout (m, Pa, N), exceptions carrying the library's messages (see :mod:`asperity.errors`).

Quick start::

    import asperity
    s = asperity.Surface.generate(nx=256, seed=1)           # reference statistics, 250 µm patch
    solver = asperity.NormalSolver(s, e_star_pa=asperity.composite_modulus(210e9, 0.3))
    sol = solver.solve_load(1e6)                            # mean pressure 1 MPa
    sol.contact_area_ratio, sol.mean_gap_m, sol.pressure    # pressure: read-only (nx, ny) view

Arrays passed in must be C-contiguous float64 ``numpy.ndarray``s (they are borrowed, not
copied; a ``Surface`` copies its heights once). Arrays handed out are either read-only views of
a result object's memory or new arrays; nothing is copied twice. Long computations release the
GIL.

The data flow, one sub-module per stage (every name is also at the top level):
:mod:`asperity.surface` (``Surface``: generate, read, stats, ``from_topography``) →
:mod:`asperity.contact` (``NormalSolver`` / ``normal_sweep``, ``TangentialSolver``: hysteresis
loops) → :mod:`asperity.calibrate` (``ValanisParams`` / ``valanis_integrate`` / ``fit_valanis``,
``CalibrationTable``, ``calibrate``: the whole chain, ``join_elements``) → :mod:`asperity.film`
(``film``, or ``FilmMap`` / ``film_preloads``) → :mod:`asperity.dynamics` (``ResponseModel``:
forced response, harmonic balance) → :mod:`asperity.identify` (``identify`` / ``predict`` on
measured frequency responses, ``diagnose`` on a hysteresis record).

``asperity.film``, ``asperity.calibrate`` and ``asperity.identify`` are modules that can also be
called as their function (``asperity.film(...)`` is ``asperity.film.film(...)``), so that code
written before the modules keeps working; typed code calls the function by its full name.
"""

from . import calibrate, contact, dynamics, errors, film, identify, surface
from ._native import __version__
from .calibrate import (
    CalibrationRun,
    SurfaceSpec,
    SampleSummary,
    ConvergenceCheck,
    PressureConvergence,
    CalibrationConvergence,
    StageTimes,
    ElementSummary,
    TableColumns,
    TableValues,
    CalibrationTable,
    LoopFit,
    ValanisFit,
    ValanisParams,
    dissipated_energy,
    fit_valanis,
    fit_valanis_loops,
    join_elements,
    normal_load_history,
    read_preloads,
    sine_history,
    student_t_975,
    valanis_integrate,
    write_preloads,
)
from .contact import (
    AmplitudeHistory,
    AmplitudeLoop,
    Convergence,
    CycleEnergy,
    NormalSolution,
    NormalSolver,
    OscillationResult,
    TangentialMetadata,
    TangentialSolver,
    TangentialStep,
    TangentialSweepResult,
    VaryingLoadCheck,
    normal_sweep,
    tangential_sweep,
)
from .dynamics import DecayResult, NonlinearModeResult, ResponseModel, SweepResult
from .film import (
    ClassCounts,
    FilmMap,
    FilmResult,
    ReductionSummary,
    NodeClassReading,
    NodePlacement,
    NodeSummary,
    NotFitted,
    BelowRangePatch,
    PreloadSummary,
    FilmSummary,
    PolyFit,
    Region,
    RegionSummary,
    film_preloads,
    read_nodes,
    reduce_preloads,
)
from .identify import (
    DiagnoseErrors,
    DiagnoseReport,
    FilePrediction,
    IdentifyReport,
    LevelError,
    ParameterEstimate,
    PredictReport,
    Record,
    diagnose,
    predict,
    read_record,
)
from .surface import (
    PowerSpectrum,
    Profile,
    Surface,
    SurfaceStats,
    composite_modulus,
    equivalent_surface,
    read_topography,
)
from .errors import (
    ArrayTypeError,
    ConvergenceError,
    DataError,
    Error,
    FileError,
    ParameterError,
    ParseError,
    ResourceLimitError,
)

__all__ = [
    "__version__",
    "errors",
    "Error",
    "FileError",
    "ParseError",
    "ParameterError",
    "DataError",
    "ConvergenceError",
    "ArrayTypeError",
    "ResourceLimitError",
    "Surface",
    "Profile",
    "SurfaceStats",
    "PowerSpectrum",
    "read_topography",
    "composite_modulus",
    "equivalent_surface",
    "NormalSolver",
    "NormalSolution",
    "Convergence",
    "normal_sweep",
    "tangential_sweep",
    "TangentialSolver",
    "TangentialStep",
    "TangentialSweepResult",
    "VaryingLoadCheck",
    "TangentialMetadata",
    "OscillationResult",
    "CycleEnergy",
    "AmplitudeHistory",
    "AmplitudeLoop",
    "ValanisParams",
    "ValanisFit",
    "LoopFit",
    "valanis_integrate",
    "normal_load_history",
    "dissipated_energy",
    "sine_history",
    "fit_valanis",
    "fit_valanis_loops",
    "student_t_975",
    "CalibrationTable",
    "CalibrationRun",
    "SurfaceSpec",
    "SampleSummary",
    "ConvergenceCheck",
    "PressureConvergence",
    "CalibrationConvergence",
    "StageTimes",
    "ElementSummary",
    "TableColumns",
    "TableValues",
    "calibrate",
    "join_elements",
    "read_preloads",
    "write_preloads",
    "film",
    "FilmResult",
    "ReductionSummary",
    "NodeClassReading",
    "NodePlacement",
    "NodeSummary",
    "NotFitted",
    "BelowRangePatch",
    "PreloadSummary",
    "FilmSummary",
    "FilmMap",
    "Region",
    "PolyFit",
    "RegionSummary",
    "ClassCounts",
    "read_nodes",
    "film_preloads",
    "reduce_preloads",
    "ResponseModel",
    "SweepResult",
    "DecayResult",
    "NonlinearModeResult",
    "read_record",
    "Record",
    "diagnose",
    "DiagnoseReport",
    "DiagnoseErrors",
    "identify",
    "IdentifyReport",
    "ParameterEstimate",
    "LevelError",
    "predict",
    "PredictReport",
    "FilePrediction",
    "surface",
    "contact",
    "dynamics",
]
