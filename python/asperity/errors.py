"""Exceptions of asperity.

Every error raised by the Rust library arrives as one of these classes, with the library's
message as its text and the fields of the error as attributes. All derive from
:class:`asperity.Error`, and each also from the built-in exception a Python user expects:

==========================  =====================  =========================================
class                       also a                 raised for
==========================  =====================  =========================================
``FileError``               ``OSError``            a file that cannot be read or written
                                                   (``filename``, ``errno``, ``strerror``)
``ParseError``              ``ValueError``         a malformed file (``path``, 1-based
                                                   ``line``; 0 = the whole file)
``ParameterError``          ``ValueError``         an impossible argument value, array shape
                                                   or layout, NaN in an array (``name``)
``DataError``               ``ValueError``         well-formed data that cannot be used
                                                   (no contact, no complete cycle, ...)
``ConvergenceError``        ``RuntimeError``       a solver hit its iteration cap (``solver``,
                                                   ``iterations``, ``residual``, ``tolerance``)
``ArrayTypeError``          ``TypeError``          an argument that is not a numpy array of
                                                   the required dtype (float64)
``ResourceLimitError``      ``MemoryError``        a request beyond a documented limit (grid
                                                   size, memory, file size, steps; ``name``)
==========================  =====================  =========================================
"""


class Error(Exception):
    """Base class of every exception raised by asperity."""


class FileError(Error, OSError):
    """A file could not be read or written. Attributes: ``filename``, ``errno``, ``strerror``."""


class ParseError(Error, ValueError):
    """A file was read but is malformed. Attributes: ``path``, ``line`` (1-based; 0 = whole file)."""


class ParameterError(Error, ValueError):
    """A parameter or array argument has an impossible value, shape or layout. Attribute: ``name``."""


class DataError(Error, ValueError):
    """Well-formed input that cannot be used (no contact, no complete cycle, ...)."""


class ConvergenceError(Error, RuntimeError):
    """An iterative solver reached its iteration cap before its tolerance.

    Attributes: ``solver``, ``iterations``, ``residual``, ``tolerance``.
    """


class ArrayTypeError(Error, TypeError):
    """An argument is not a numpy array of the required dtype (float64)."""


class ResourceLimitError(Error, MemoryError):
    """A request beyond a documented resource limit, refused before allocation. Attribute: ``name``."""


__all__ = [
    "Error",
    "FileError",
    "ParseError",
    "ParameterError",
    "DataError",
    "ConvergenceError",
    "ArrayTypeError",
    "ResourceLimitError",
]
