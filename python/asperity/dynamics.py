"""Structural dynamics with the calibrated contact elements: forced response by harmonic
balance, nonlinear modes (EPMC) and time integration of a linear structure with nonlinear joints.

Frequencies in Hz, forces in N, displacements in m.
"""

from ._native import DecayResult, NonlinearModeResult, ResponseModel, SweepResult

__all__ = ["DecayResult", "NonlinearModeResult", "ResponseModel", "SweepResult"]
