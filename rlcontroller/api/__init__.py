"""The public Python API: what each `rlc` command does, as a function (the command line only parses
its arguments, calls one of these and prints). Each takes paths as the command does and a `Report`
to hear how the work goes (default `QUIET`); user mistakes raise `rlcontroller.config.ConfigError`
with a one-line message. docs/architecture.md has an example per command.

Each function imports the modules it runs inside itself (measured here: `from rlcontroller import api` takes
0.65 s, 5.7-6.5 s with them at its modules' tops, as torch, stable-baselines3, scipy and matplotlib come with
them), so that a command pays only for what it runs."""

from rlcontroller.api.certify import certificate_line, certificate_summary, certify
from rlcontroller.api.common import QUIET, Judging, Report, load, model_folder
from rlcontroller.api.describe import describe
from rlcontroller.api.identification import identify, reduce, simulate_test
from rlcontroller.api.judging import compare_lqg, compare_passive, evaluate, robustness, summary_text
from rlcontroller.api.multirun import aggregate, sweep, tune
from rlcontroller.api.safety import check, unchecked_note, verdict_lines, verdict_state, verify
from rlcontroller.api.shipping import convert, design, export, shipped_models
from rlcontroller.api.training import demo, train

__all__ = [
    "QUIET",
    "Judging",
    "aggregate",
    "sweep",
    "tune",
    "Report",
    "certificate_line",
    "certificate_summary",
    "certify",
    "check",
    "compare_lqg",
    "compare_passive",
    "convert",
    "demo",
    "describe",
    "design",
    "evaluate",
    "export",
    "identify",
    "load",
    "model_folder",
    "reduce",
    "robustness",
    "shipped_models",
    "simulate_test",
    "summary_text",
    "train",
    "unchecked_note",
    "verify",
    "verdict_lines",
    "verdict_state",
]
