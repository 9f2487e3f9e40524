"""mesolab: meso-scale appearance (micro-geometry, bump synthesis, translucency, cloth) from Python.

The compiled core (mesolab._mesolab) with the names users call; `client=` on Workbench.render (the
truth), sweep, frontier and bench spreads the work over a Dask.distributed cluster
(mesolab.cluster). See python/README.md.
"""
from . import _mesolab as _core
from ._mesolab import *  # noqa: F401,F403  Scene, Frame, load_preset, info, schema, InputError, ...
from ._mesolab import __version__  # noqa: F401

from .cluster import Workbench, bench, frontier, sweep  # noqa: F401  (client= beside the core's arguments)

# The core's classes and errors print as mesolab.X, as users name them.
for _name in ("Scene", "Frame", "InputError", "MemoryBudgetError"):
    try:
        getattr(_core, _name).__module__ = __name__
    except (AttributeError, TypeError):
        pass
del _name
Workbench.__module__ = __name__
