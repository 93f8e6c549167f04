"""wheelsoil.model: the terramechanics core (Wong's rigid-wheel model, slip sinkage, metrics).

Public API (docs/architecture.md)::

    from wheelsoil.model import Terrain, Wheel, load_terrain, TERRAINS, DEFAULT_WHEEL
    from wheelsoil.model import wong_forces, WheelForces, MODELS, get_model, SinkageModel, Param
    from wheelsoil.model import m0_pct, r0, r2
    from wheelsoil.model import HYPOTHESES, get_hypothesis      # the causes the diagnosis tries

Fitting and diagnosis (import the submodules; they pull in scipy)::

    from wheelsoil.model.data import prepare_data            # selection, cells, model-free noise
    from wheelsoil.model.crossval import fit_hypothesis      # penalised Gauss-Newton, CV
    from wheelsoil.model.structure import structure_test     # is a model's error systematic, and relevant?
    from wheelsoil.model.diagnosis import diagnose           # the verdict; .to_dict() = contract D

Example::

    >>> from wheelsoil.model import load_terrain, DEFAULT_WHEEL, get_model
    >>> f = get_model("lyasko").predict(load_terrain("clay"), DEFAULT_WHEEL,
    ...                                 [11000.0, 11000.0], [0.1, 0.5], {"m1": 0.1, "m2": 0.05})
    >>> f.drawbar_pull_n.shape
    (2,)
"""

from .metrics import m0_pct, r0, r2
from .hypotheses import HYPOTHESES, get_hypothesis
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
    "HYPOTHESES",
    "get_hypothesis",
]
