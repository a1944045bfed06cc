"""rlcontroller: reinforcement-learning active control of buildings under earthquakes.

The Gymnasium env is registered as `ENV_ID` by `import rlcontroller.learning`, and by `import rlcontroller`
when gymnasium is already imported; the package itself loads neither gymnasium nor numpy, so the
command line starts quickly."""

import sys

ENV_ID = "rlcontroller/Building-v0"


def register_env() -> None:
    """Register `ENV_ID` with gymnasium (once): `gymnasium.make(ENV_ID, config=...)`."""
    import gymnasium

    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point="rlcontroller.learning.env:BuildingEnv")


if "gymnasium" in sys.modules:
    register_env()


def __getattr__(name: str):
    if name == "__version__":  # read when asked: importlib.metadata costs 50 ms at start-up
        from importlib.metadata import version

        return version("rlcontroller")
    raise AttributeError(f"module 'rlcontroller' has no attribute {name!r}")
