"""wheelsoil: wheel-soil field testing, from CAN frames to a fitted terramechanics model.

Sub-packages (one-way flow, each usable from a notebook):

- :mod:`wheelsoil.daq`: bus capture, MCAP recordings, import/export, replay.
- :mod:`wheelsoil.processing`: vectorised DBC decode, time-sync, filters, slip.
- :mod:`wheelsoil.model`: Wong's terramechanics model, slip-sinkage models,
  Gauss-Newton fitting, diagnosis and the fitted-model report.

The top-level modules (:mod:`wheelsoil.cli`, :mod:`wheelsoil.pipeline`,
:mod:`wheelsoil.simulate`) only orchestrate the three.
"""

__version__ = "0.1.0"
