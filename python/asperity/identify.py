"""Measured responses → model: identify a jointed structure's nonlinear mode (or update a
reduced model) from stepped-sine sweeps and predict other tests (``identify``, ``predict``);
find the effect a hysteresis record's element lacks (``diagnose``).

Frequencies in Hz, forces in N, displacements in m. ``asperity.identify(...)`` calls
:func:`asperity.identify.identify`.
"""

from ._native import (
    DiagnoseErrors,
    DiagnoseReport,
    FilePrediction,
    IdentifyReport,
    LevelError,
    ParameterEstimate,
    PredictReport,
    Record,
    diagnose,
    identify,
    predict,
    read_record,
)
from ._stage import make_callable

__all__ = [
    "identify",
    "IdentifyReport",
    "ParameterEstimate",
    "LevelError",
    "predict",
    "PredictReport",
    "FilePrediction",
    "read_record",
    "Record",
    "diagnose",
    "DiagnoseReport",
    "DiagnoseErrors",
]

make_callable(__name__)
