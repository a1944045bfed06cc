"""Command line: each command parses its arguments, calls one function of `rlcontroller.api` and prints;
no physics or RL logic lives here. One module per group of commands, in the order `rlc --help` lists them:
`experiments` (info, train, demo), `judging` (evaluate, compare, robustness, check), `multirun` (tune, sweep,
aggregate), `shipping` (models, export, convert), `identification` (simulate-test, identify); `app` holds what
they share."""

from rlcontroller.assets import DEFAULT_MODEL, MODELS
from rlcontroller.cli import experiments, identification, judging, multirun, shipping  # noqa: F401  (each registers its commands)
from rlcontroller.cli.app import app

__all__ = ["DEFAULT_MODEL", "MODELS", "app", "main"]


def main() -> None:
    app(prog_name="rlc")
