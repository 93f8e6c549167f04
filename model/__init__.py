"""wheelsoil.model: the terramechanics core (Wong's rigid-wheel model, slip sinkage, metrics).

Public API (docs/architecture.md)::

    from wheelsoil.model import Terrain, Wheel, load_terrain, TERRAINS, DEFAULT_WHEEL
    from wheelsoil.model import wong_forces, WheelForces, MODELS, get_model, SinkageModel, Param
    from wheelsoil.model import m0_pct, r0, r2

Example::

    >>> from wheelsoil.model import load_terrain, DEFAULT_WHEEL, get_model
    >>> f = get_model("lyasko").predict(load_terrain("clay"), DEFAULT_WHEEL,
    ...                                 [11000.0, 11000.0], [0.1, 0.5], {"m1": 0.1, "m2": 0.05})
    >>> f.drawbar_pull_n.shape
    (2,)
"""

from .metrics import m0_pct, r0, r2
from .slip_sinkage import MODELS, Param, SinkageModel, get_model
from .terrain import DEFAULT_WHEEL, TERRAINS, Terrain, Wheel, load_terrain, load_terrain_file
from .wong import WheelForces, sinkage_eq10, wong_forces

__all__ = [
    "Terrain",
    "Wheel",
    "DEFAULT_WHEEL",
    "TERRAINS",
    "load_terrain",
    "load_terrain_file",
    "wong_forces",
    "sinkage_eq10",
    "WheelForces",
    "SinkageModel",
    "Param",
    "MODELS",
    "get_model",
    "m0_pct",
    "r0",
    "r2",
]
