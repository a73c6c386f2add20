"""Rough-surface contact by boundary elements: normal load sweeps and tangential loops.

Pressures in Pa, gaps and displacements in m, forces in N.
"""

from ._native import (
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

__all__ = [
    "NormalSolver",
    "NormalSolution",
    "Convergence",
    "normal_sweep",
    "TangentialSolver",
    "TangentialStep",
    "TangentialMetadata",
    "OscillationResult",
    "CycleEnergy",
    "AmplitudeHistory",
    "AmplitudeLoop",
    "tangential_sweep",
    "TangentialSweepResult",
    "VaryingLoadCheck",
]
