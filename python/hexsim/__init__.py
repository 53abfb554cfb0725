"""hexsim from Python: a hexapod walking on uneven ground, stepped from Python.

``Simulation`` runs a walk scenario (a scenario file, or its fields as keyword arguments) a
stretch at a time: step it through the gait with a velocity command or drive its joints directly,
read its state as NumPy arrays and its metrics as ``hexsim run --metrics`` writes them, record it
for the rerun viewer. Importing the package registers the Gymnasium environments
``hexsim/HexapodRough-v0`` (joint targets) and ``hexsim/HexapodGait-v0`` (gait commands);
``step_many`` steps several simulations at once on threads, and ``HexapodVectorEnv`` (or
``gym.make_vec``) is the vector environment, each world's whole step (action, physics,
observation, reward) on those threads in one call.
See docs/python.md.
"""

from ._hexsim import DivergedError, HexsimError, Simulation, __version__, step_many
from . import env as _env
from .env import HexapodEnv, HexapodVectorEnv

_env.register()

__all__ = [
    "Simulation",
    "step_many",
    "HexapodEnv",
    "HexapodVectorEnv",
    "HexsimError",
    "DivergedError",
    "__version__",
]
