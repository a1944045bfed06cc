"""rlcontroller: reinforcement-learning active control of buildings under earthquakes."""

from importlib.metadata import version

import gymnasium

__version__ = version("rlcontroller")

ENV_ID = "rlcontroller/Building-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="rlcontroller.learning.env:BuildingEnv")
