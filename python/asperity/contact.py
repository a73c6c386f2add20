"""Rough-surface contact by boundary elements: normal load sweeps and tangential loops.

Pressures in Pa, gaps and displacements in m, forces in N.
"""

from ._native import Convergence, NormalSolution, NormalSolver, TangentialSolver, normal_sweep

__all__ = ["NormalSolver", "NormalSolution", "Convergence", "normal_sweep", "TangentialSolver"]
