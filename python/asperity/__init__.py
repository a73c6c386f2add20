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

The data flow, in the order of the modules: ``Surface`` (generate, read, stats) →
``NormalSolver`` / ``normal_sweep`` → ``TangentialSolver`` (hysteresis loops) →
``ValanisParams`` / ``valanis_integrate`` / ``fit_valanis`` → ``CalibrationTable`` (read,
interpolate; or ``calibrate``, the whole chain) → ``film`` (or ``FilmMap`` / ``film_preloads``) →
``join_elements`` → ``ResponseModel`` (forced response, harmonic balance) → ``diagnose``.
"""

from . import errors
from ._native import (
    CalibrationTable,
    FilmMap,
    FilmResult,
    NormalSolution,
    NormalSolver,
    ResponseModel,
    PolyFit,
    Profile,
    Region,
    Surface,
    TangentialSolver,
    ValanisFit,
    ValanisParams,
    __version__,
    calibrate,
    composite_modulus,
    diagnose,
    dissipated_energy,
    equivalent_surface,
    film,
    film_preloads,
    fit_valanis,
    fit_valanis_loops,
    student_t_975,
    join_elements,
    normal_load_history,
    normal_sweep,
    read_nodes,
    read_preloads,
    read_record,
    read_topography,
    reduce_preloads,
    sine_history,
    valanis_integrate,
    write_preloads,
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
    *errors.__all__,
    "Surface",
    "Profile",
    "read_topography",
    "composite_modulus",
    "equivalent_surface",
    "NormalSolver",
    "NormalSolution",
    "normal_sweep",
    "TangentialSolver",
    "ValanisParams",
    "ValanisFit",
    "valanis_integrate",
    "normal_load_history",
    "dissipated_energy",
    "sine_history",
    "fit_valanis",
    "fit_valanis_loops",
    "student_t_975",
    "CalibrationTable",
    "calibrate",
    "join_elements",
    "read_preloads",
    "write_preloads",
    "film",
    "FilmResult",
    "FilmMap",
    "Region",
    "PolyFit",
    "read_nodes",
    "film_preloads",
    "reduce_preloads",
    "ResponseModel",
    "read_record",
    "diagnose",
]
