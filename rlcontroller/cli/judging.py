"""Commands that judge controllers: `rlc evaluate`, `compare lqg`, `compare passive`, `robustness`,
`check`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rlcontroller.cli.app import (
    RUN_HELP,
    SCENARIOS_DEFAULT,
    AddressOption,
    CriteriaOption,
    Engine,
    EngineOption,
    ModelOption,
    OutOption,
    Printed,
    ProgressOption,
    RecordsOption,
    ScaleOption,
    app,
    user_errors,
)
from rlcontroller.cli.experiments import print_verdict
from rlcontroller.simulation.fanout import engine as fan_out

RunOption = Annotated[Path | None, typer.Argument(help=RUN_HELP)]


@app.command(short_help="A controller against LQG and no control on records.")
@user_errors
def evaluate(
    *,
    run_dir: RunOption = None,
    records: RecordsOption = None,
    out: OutOption = None,
    scale_pga: ScaleOption = None,
    model: ModelOption = "best",
    progress: ProgressOption = None,
    config: Annotated[
        Path | None,
        typer.Option(
            help="Experiment YAML to judge the controller in (e.g. an OpenSees plant); default its own."
        ),
    ] = None,
    engine: EngineOption = Engine.local,
    address: AddressOption = None,
    criteria: CriteriaOption = "paper",
) -> None:
    """Uncontrolled vs LQG vs the trained policy on the records: J1-J4 tables and the paper's plots."""
    from rlcontroller import api

    with fan_out(engine.value, address):
        judging = api.Judging(records=records, scale_pga=scale_pga, model=model, criteria=criteria)
        evaluation, out = api.evaluate(
            run_dir=run_dir, judging=judging, out=out, config=config, report=Printed(progress)
        )
    typer.echo(api.summary_text(evaluation, out))


compare_app = typer.Typer(
    no_args_is_help=True,
    short_help="The classical answers: LQG, passive devices.",
    help="The classical answers: LQG with the same cost (rlc compare lqg), passive devices (rlc compare "
    "passive).",
)
app.add_typer(compare_app, name="compare")


@compare_app.command("lqg", short_help="LQG with the same cost: its J tables and trade-off curve.")
@user_errors
def compare_lqg(
    *,
    run_dir: Annotated[
        Path | None, typer.Argument(help=f"Whose policy joins: {RUN_HELP[0].lower()}{RUN_HELP[1:]}")
    ] = None,
    config: Annotated[Path | None, typer.Option(help="Experiment YAML instead of a run: LQG only.")] = None,
    records: RecordsOption = None,
    out: OutOption = None,
    scale_pga: ScaleOption = None,
    sweep: Annotated[
        bool,
        typer.Option(
            help="Trace LQG's J1-J3 trade-off over force weights (dampers: passive levels and "
            "clipped-optimal weights)."
        ),
    ] = False,
    preview: Annotated[
        bool, typer.Option(help="Full-state LQR knowing the ground 0-1 s ahead: what prediction could buy.")
    ] = False,
    mpc: Annotated[
        int | None,
        typer.Option(
            help="Add MPC over this many control steps (20: 0.4 s): force limits, strokes (soft) and "
            "dampers' passivity as constraints."
        ),
    ] = None,
    model: ModelOption = "best",
    progress: ProgressOption = None,
    engine: EngineOption = Engine.local,
    address: AddressOption = None,
    criteria: CriteriaOption = "paper",
) -> None:
    """LQG (same cost) against the uncontrolled building, and against the RL policy of a run; MPC too with
    --mpc."""
    from rlcontroller import api

    with fan_out(engine.value, address):
        judging = api.Judging(records=records, scale_pga=scale_pga, model=model, criteria=criteria)
        compared = api.compare_lqg(
            run_dir=run_dir,
            config=config,
            judging=judging,
            out=out,
            sweep=sweep,
            preview=preview,
            mpc=mpc,
            report=Printed(progress),
        )
    typer.echo(api.summary_text(compared.evaluation, compared.out))
    for text in (compared.sweep, compared.preview):
        if text is not None:
            typer.echo(text)


@compare_app.command("passive", short_help="The building with its mass devices passive, and without them.")
@user_errors
def compare_passive(
    *,
    config: Annotated[Path, typer.Argument(help="Experiment YAML with a devices part.")],
    records: RecordsOption = None,
    out: OutOption = None,
    scale_pga: ScaleOption = None,
    progress: ProgressOption = None,
) -> None:
    """The building without its devices (uncontrolled) and with them passive: tuned masses as tuned,
    active mass drivers as the tuned masses they are without a command; strokes and damper energy. Under
    ground motion also the devices' own verdict: the safety check's suite, passive devices against the
    building without them (passive_check.yaml)."""
    from rlcontroller import api

    evaluation, out, verdict = api.compare_passive(
        config, records=records, out=out, scale_pga=scale_pga, report=Printed(progress)
    )
    typer.echo(api.summary_text(evaluation, out))
    if verdict is not None:
        typer.echo("\n".join(verdict.lines()).replace("safety check of", "the devices' own verdict:", 1))


@app.command(short_help="Every controller on plants that differ from the design.")
@user_errors
def robustness(
    *,
    run_dir: RunOption = None,
    records: RecordsOption = None,
    scenarios: Annotated[
        Path | None,
        typer.Option(
            help="Scenario YAML: named plants that differ from the design model.",
            show_default=SCENARIOS_DEFAULT,
        ),
    ] = None,
    out: OutOption = None,
    scale_pga: ScaleOption = None,
    model: ModelOption = "best",
    progress: ProgressOption = None,
) -> None:
    """Every controller on every scenario's plant and every record: how each copes with model error."""
    from rlcontroller import api
    from rlcontroller.evaluation.tables import markdown_table

    mean_j1, label, named, seconds, out = api.robustness(
        run_dir=run_dir,
        records=records,
        scenarios=scenarios,
        out=out,
        scale_pga=scale_pga,
        model=model,
        report=Printed(progress),
    )
    typer.echo(f"# {label}")
    typer.echo(markdown_table(mean_j1))
    typer.echo(f"{len(named)} scenarios evaluated in {seconds:.0f} s; tables and plot in {out}")


@app.command(short_help="The safety check: never worse than failed safe.")
@user_errors
def check(
    *,
    run_dir: Annotated[Path | None, typer.Argument(help=RUN_HELP)] = None,
    model: ModelOption = "best",
    standard: Annotated[
        Path | None,
        typer.Option(
            help="The check's standard: suite, seed, bounds.",
            show_default="configs/checks/standard.yaml; under wind configs/checks/wind.yaml",
        ),
    ] = None,
    scenarios: Annotated[
        Path | None, typer.Option(help="Plants for the stability report.", show_default=SCENARIOS_DEFAULT)
    ] = None,
    progress: ProgressOption = None,
    show: Annotated[
        bool,
        typer.Option(
            "--show", help="Print the folder's verdict and whether it judged these files; no check."
        ),
    ] = False,
    verify: Annotated[
        bool,
        typer.Option(
            "--verify", help="Re-run the check and compare it with the folder's verdict, figure by figure."
        ),
    ] = False,
    config: Annotated[
        Path | None,
        typer.Option(
            help="Experiment YAML to check the controller in (e.g. an OpenSees plant); default its own."
        ),
    ] = None,
    engine: EngineOption = Engine.local,
    address: AddressOption = None,
) -> None:
    """The safety check a controller passes before it is shipped: on a broad suite of generated motions
    (generated wind for a controller against wind) never worse than the building when the controller fails
    safe (no control; devices at their fail-safe command), no higher floor accelerations on average, quiet
    at rest, a stable closed loop. Writes MODEL_check.yaml in the run folder (for a shipped model: in a new
    folder under results/); exit code 1 when it fails. --verify re-runs it and compares with the recorded
    verdict (exit code 1 when a figure differs beyond 1 % plus its rounding)."""
    from rlcontroller import api

    report = Printed(progress)
    folder = api.model_folder(run_dir, report)
    if show:
        lines, passed = api.verdict_lines(folder, model)
        typer.echo("\n".join(lines))
    elif verify:
        if standard is not None or config is not None:
            from rlcontroller.config import ConfigError

            raise ConfigError("--verify re-runs the folder's own verdict: leave out --standard and --config")
        with fan_out(engine.value, address):
            differing = api.verify(folder, model, scenarios, report)
        typer.echo(
            "\n".join(differing) or "verified: the re-run reproduces every figure of the recorded verdict"
        )
        passed = not differing
    else:
        with fan_out(engine.value, address):
            verdict, path = api.check(
                folder, model=model, standard=standard, scenarios=scenarios, report=report, config=config
            )
        print_verdict(verdict, path)
        typer.echo(api.certificate_line(folder, model))
        passed = verdict.passed
    if not passed:
        raise typer.Exit(1)


@app.command(short_help="A proven region of stability for a controller.")
@user_errors
def certify(
    *,
    run_dir: Annotated[Path | None, typer.Argument(help=RUN_HELP)] = None,
    model: ModelOption = "best",
    design_only: Annotated[
        bool, typer.Option("--design-only", help="Certify on the design model only, not the scenario plants.")
    ] = False,
) -> None:
    """Prove a region of starts from which the controller brings the building back to rest: quadratic
    constraints on every unit of its network (tanh, ReLU, the clips) and a linear matrix inequality, on the
    design model and on each linear plant of the standard's scenarios (stiffness, mass, damping, actuator
    lag, delay), with a bound on the response to ground motion inside it. Every region is checked by
    simulations from its boundary. Writes MODEL_certificate.yaml in the folder (docs/certificate.md)."""
    from rlcontroller import api
    from rlcontroller.config import display_path

    report = Printed(None)
    folder = api.model_folder(run_dir, report)
    path = api.certify(folder, model=model, robust=not design_only, report=report)
    typer.echo(f"certificate written to {display_path(path)}")
