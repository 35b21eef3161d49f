"""``camopt calibrate``: fit a case's dynamics to measured travel curves.

``--set KEY=VALUE`` belongs to the ``--curve`` before it (that curve's design or latch
delay); a ``--set`` before the first ``--curve`` overrides the case file as in ``camopt
run`` (``case.FIELD=VALUE``). click gives each option's values without their order, so the
command keeps the raw arguments (:class:`OrderedCommand`) to pair them.

Each command imports the engine, archives and reports it needs inside its function: a
command line loads only its own command's modules (tests/cli/test_imports.py)."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Annotated, Any

import typer
from typer.core import TyperCommand

from camopt.cli.app import Format, app, errors, load_case
from camopt.cli.console import visible
from camopt.errors import ConfigError

RAW = "camopt.raw_args"
MAX_TRAVEL_MM = 500.0
"""Largest travel of a velocity calculation point (mm): the physical range of a case's
strokes (``Stroke``, 0.1 to 500 mm)."""


class OrderedCommand(TyperCommand):
    """A typer command that keeps its raw arguments in ``ctx.meta`` (for the order of
    repeated options)."""

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        ctx.meta[RAW] = list(args)
        return super().parse_args(ctx, args)


def pair_sets(raw: list[str]) -> tuple[list[str], list[tuple[str, list[str]]]]:
    """The case overrides (``--set`` before any ``--curve``) and each curve with the
    ``--set`` values after it, from the raw arguments (``--opt value`` or
    ``--opt=value``)."""
    case: list[str] = []
    curves: list[tuple[str, list[str]]] = []
    i = 0
    while i < len(raw):
        arg = raw[i]
        name, eq, inline = arg.partition("=")
        if name in ("--curve", "--set"):
            if eq:
                value = inline
            elif i + 1 < len(raw):
                value, i = raw[i + 1], i + 1
            else:
                break  # click reports the missing value
            if name == "--curve":
                curves.append((value, []))
            elif curves:
                curves[-1][1].append(value)
            else:
                case.append(value)
        i += 1
    return case, curves


def velocity_points(text: str | None) -> tuple[float, float] | None:
    """``LOW,HIGH`` travel in mm, or None."""
    if text is None:
        return None
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError:
        raise ConfigError("--velocity-points", text, "expected LOW,HIGH travel in mm "
                          "(e.g. 7.333,11)") from None
    if not (math.isfinite(low) and math.isfinite(high) and 0 < low < high <= MAX_TRAVEL_MM):
        raise ConfigError("--velocity-points", text, f"need 0 < LOW < HIGH <= "
                          f"{MAX_TRAVEL_MM:g} (travel in mm)")
    return low, high


def check_design_values(config: Any, pairs: list[tuple[str, list[str]]],
                        predict: list[str]) -> None:
    """Every number of a per-curve ``--set`` and of a ``--predict`` through the checks a
    case file's numbers get: a key that is a field of the case (the closing springs'
    ``kc1_n_per_mm``) through the case's model (its physical range, unless
    ``run.check_plausibility = false``, and the 1e12 cap), any other number (the law's
    ``a1``..``a3``, a latch delay) finite and within the cap. A bad value is one line
    naming the curve file (or ``--predict``) and the key, before any fit."""
    from pydantic import ValidationError

    from camopt.config.models import MAX_MAGNITUDE, PLAUSIBILITY_KEY

    case = config.case
    model = type(case)
    context = {PLAUSIBILITY_KEY: config.run.check_plausibility}
    given = [(p, items) for p, items in pairs] + [("--predict", p.split(","))
                                                  for p in predict]
    for where, items in given:
        for item in items:
            key, _, text = (part.strip() for part in item.partition("="))
            try:
                value = float(text)
            except ValueError:
                continue  # not a number: a label, a cam file, or refused by the case
            if key in model.model_fields:
                try:
                    model.model_validate({**case.model_dump(), key: value}, context=context)
                except ValidationError as exc:
                    error = exc.errors()[0]
                    raise ConfigError(where, key, error["msg"].removeprefix(
                        "Value error, ") + f" (got {text})") from None
            elif not abs(value) <= MAX_MAGNITUDE:
                what = "not a finite number" if value != value or abs(value) == float(
                    "inf") else f"{value:g} is beyond {MAX_MAGNITUDE:g} in size"
                raise ConfigError(where, key, what)


@app.command(cls=OrderedCommand)
def calibrate(
    ctx: typer.Context,
    case: Annotated[Path, typer.Argument(help="case file (TOML)")],
    curve: Annotated[list[Path], typer.Option(
        "--curve", metavar="FILE.csv",
        help="travel curve CSV (time_ms,travel_mm or time_s,travel_m; time from "
        "the close command); repeatable")],
    set_: Annotated[list[str] | None, typer.Option(
        "--set", metavar="KEY=VALUE",
        help="after a --curve: that curve's design or latch delay (kc1_n_per_mm, "
        "kc2_n_per_mm, a1, a2, a3 or cam_points=FILE.csv, latch_delay_ms, label); before any: "
        "case.FIELD=VALUE")]
    = None,
    predict: Annotated[list[str] | None, typer.Option(
        "--predict", metavar="KEY=VALUE[,...]",
        help="another design to predict: KEY=VALUE[,KEY=VALUE] (the --set "
        "keys of a design); repeatable")] = None,
    points: Annotated[str | None, typer.Option(
        "--velocity-points", metavar="LOW,HIGH",
        help="contact velocity between these travels, LOW,HIGH mm, 0 < LOW < HIGH <= 500 "
        "(default the case's: 2/3 of the contact gap to the touch)")] = None,
    form: Annotated[list[str] | None, typer.Option(
        "--form", metavar="NAME",
        help="model form to fit (default every form of the case); repeatable")]
    = None,
    out_path: Annotated[Path | None, typer.Option(
        "--out", help="write the calibrated values as a case fragment (TOML that extends "
        "CASE)")] = None,
    plot: Annotated[Path | None, typer.Option(
        help="write measured vs fitted curves and residuals (PNG per form) to this "
        "folder")] = None,
    archive_path: Annotated[Path | None, typer.Option(
        "--archive", metavar="FILE.h5",
        help="write a calibration archive (curves, fits, report) for camopt show, plot "
        "and report")] = None,
    force: Annotated[bool, typer.Option(help="overwrite an existing --out, --archive and "
                                        "--plot's PNGs")] = False,
    allow_unexplained: Annotated[bool, typer.Option(
        "--allow-unexplained", help="write --out even when no model form explains the "
        "curves (the fragment's first line says so)")] = False,
    format: Annotated[Format, typer.Option("--format", help="output")] = Format.table,
) -> None:
    """Calibrate a case's dynamics on measured travel curves (breaker analyser CSV)."""
    from camopt.archive.files import write_files
    from camopt.cases.registry import get_case
    from camopt.core.calibration import CalibrationRequest, CurveRequest
    from camopt.reporting.calibration_report import CalibrationReportView
    from camopt.reporting.report import jsonable

    overrides, pairs = pair_sets(ctx.meta.get(RAW, []))
    del set_  # read in order from the raw arguments
    with errors():
        config = load_case(case, overrides)
        check_design_values(config, pairs, list(predict or ()))
        request = CalibrationRequest(
            curves=tuple(CurveRequest(Path(p), tuple(s)) for p, s in pairs),
            predict=tuple(predict or ()), velocity_points_mm=velocity_points(points),
            forms=tuple(form or ()))
        for target, key in ((out_path, "--out"), (archive_path, "--archive")):
            if target is not None:  # refuse an existing output before the work
                from camopt.archive.files import check_not_input, check_writable

                check_writable(target, force, key)
                check_not_input(target, (case, *curve), key)
        if out_path is not None and archive_path is not None and out_path.resolve() == \
                archive_path.resolve():
            raise ConfigError(str(archive_path), "--archive", "the same file as --out")
        if plot is not None:  # a --plot that is a file, or unwritable, before the work
            from camopt.archive.files import ensure_folder

            ensure_folder(plot, "--plot")
        report = CalibrationReportView(get_case(config.case.kind).calibrate(config.case, request))
        written = []
        data: Any = report.to_json()
        if plot is not None:
            from camopt.cli.outputs import writing
            from camopt.reporting.calibration_figures import figures, rms_of
            from camopt.reporting.plots import save

            with writing(plot):
                written = save(figures(report.curves(), rms_of(data)), plot, "calibration",
                               force, (case, *curve), key="--plot")
        explained = data.get("verdict") != "not explained"
        withheld = out_path is not None and not explained and not allow_unexplained
        if out_path is not None and not withheld:
            extends = os.path.relpath(case.resolve(), out_path.resolve().parent)
            write_files({out_path: report.fragment(Path(extends).as_posix()).encode()},
                        force, inputs=(case, *curve))
        if archive_path is not None:
            from camopt.archive.calibrations import write_calibration

            write_calibration(archive_path, jsonable(data), report.lines(), report.curves(),
                              config.case.kind, config.text, force)
    if format == Format.json:
        print(json.dumps(jsonable(data), indent=2))
    else:
        print("\n".join(visible(line) for line in report.lines()))
    if format != Format.json:
        if out_path is not None and not withheld:
            print(f"\ncalibrated values written to {visible(out_path)} (a case can extend it)")
        if archive_path is not None:
            print(f"calibration archive: {visible(archive_path)} (camopt show / plot / report)")
        for p in written:
            print(f"figure: {visible(p)}")
        if (out_path is not None and not withheld) or archive_path is not None or written:
            print(visible(data.get("verdict_line", "")))  # the verdict, last
    if withheld:
        typer.echo(f"error: {visible(out_path)}: --out: not written: no model form explains "
                   "the curves (--allow-unexplained writes it all the same)", err=True)
        raise typer.Exit(1)
