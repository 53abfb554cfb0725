"""hexsim from Python: a hexapod walking on uneven ground, stepped from Python.

``Simulation`` runs a walk scenario (a scenario file, or its fields as keyword arguments) a
stretch at a time: step it through the gait with a velocity command or drive its joints directly,
read its state as NumPy arrays and its metrics as ``hexsim run --metrics`` writes them, record it
for the rerun viewer. Importing the package registers the Gymnasium environments
``hexsim/HexapodRough-v0`` (joint targets) and ``hexsim/HexapodGait-v0`` (gait commands).
See docs/python.md.
"""

from ._hexsim import DivergedError, HexsimError, Simulation, __version__
from . import env as _env

_env.register()

__all__ = ["Simulation", "HexsimError", "DivergedError", "__version__"]
