"""Structural dynamics with the calibrated contact elements: forced response by harmonic
balance and time integration of a linear structure with nonlinear joints.

Frequencies in Hz, forces in N, displacements in m.
"""

from ._native import ResponseModel, SweepResult

__all__ = ["ResponseModel", "SweepResult"]
