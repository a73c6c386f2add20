"""Element laws and their calibration: the Valanis element, its fits to loops, calibration
tables, the whole chain (``calibrate``), preloads and the elements of a joint.

Stiffnesses in N/m or Pa/m, forces in N, pressures in Pa. ``asperity.calibrate(...)`` calls
:func:`asperity.calibrate.calibrate`.
"""

from ._native import (
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
    calibrate,
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
from ._stage import make_callable

__all__ = [
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
]

make_callable(__name__)
