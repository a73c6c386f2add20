"""Surfaces: generate, read, write, statistics and power spectrum; composite modulus.

Heights in m, spacings in m, moduli in Pa. ``Surface.from_topography`` takes a
SurfaceTopography ``Topography``.
"""

from ._native import (
    PowerSpectrum,
    Profile,
    Surface,
    SurfaceStats,
    composite_modulus,
    equivalent_surface,
    read_topography,
)

__all__ = [
    "Surface",
    "Profile",
    "SurfaceStats",
    "PowerSpectrum",
    "read_topography",
    "composite_modulus",
    "equivalent_surface",
]
