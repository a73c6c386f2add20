"""Stage modules that are also their stage's function.

``asperity.film``, ``asperity.calibrate`` and ``asperity.identify`` are modules (the stage's
names) and, for the code written before the modules, the stage's function as well:
``asperity.film(...)`` calls ``asperity.film.film(...)``. Type checkers see the modules; typed
code calls the function by its full name.
"""

import inspect
import sys
import types


class CallableStage(types.ModuleType):
    """A stage module whose call is its function of the same name."""

    def __call__(self, *args, **kwargs):
        return getattr(self, self.__name__.rpartition(".")[2])(*args, **kwargs)


def make_callable(module_name: str) -> None:
    """Make the module ``module_name`` call its function of the same name."""
    module = sys.modules[module_name]
    function = getattr(module, module_name.rpartition(".")[2])
    module.__class__ = CallableStage
    try:
        module.__signature__ = inspect.signature(function)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        pass
