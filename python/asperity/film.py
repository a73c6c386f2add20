"""Pressure-measurement film → pressure map, regions, polynomial fit, preloads per node.

Film frame in m, pressures in Pa, preloads in N. ``asperity.film(...)`` calls
:func:`asperity.film.film`.
"""

from ._native import (
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
    film,
    film_preloads,
    read_nodes,
    reduce_preloads,
)
from ._stage import make_callable

__all__ = [
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
]

make_callable(__name__)
