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
    normal_sweep,
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
]
