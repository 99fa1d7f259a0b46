"""Command line: ``iwan-element <subcommand> ...``.

Subcommands
-----------
fit
    Identify the four Iwan parameters from a CSV test record and print the report::

        iwan-element fit data.csv --units mm,kN [--method loops|dissipation|seed]
                     [--slip-force 9] [--plot out.png] [--json result.json]

diagnose
    Fit the Iwan model, decide whether its misfit is more than the noise, and name the effect
    that explains it (viscous damping, pinning stiffness, backlash, slip degradation,
    asymmetric slip)::

        iwan-element diagnose data.csv --units mm,kN [--plot out.png] [--json out.json]
                     [--max-effects 3] [--noise SIGMA] [--progress]

    Several records (a test campaign) are diagnosed on local processes, with one table and
    one JSON for the run::

        iwan-element diagnose runs/*.csv --units in,lbf --lowpass 20 --jobs 2 --progress
                     [--json campaign.json] [--table campaign.csv]

curve
    Frequency and damping ratio against amplitude from a ring-down or stepped-sine sweep file
    (:mod:`iwan_element.cli_curve`)::

        iwan-element curve hammer.csv [--band 60,120] [--out curve.csv] [--plot curve.png]

Units are read from the header (``time [s],displacement [mm],force [kN]``) or given with
``--units``; a unit neither given nor labelled is refused (exit status 1), never guessed.

Exit status follows the result's ``success`` (docs/guards.md): 0 when it is usable, 3 when
it is not (the report is still printed; its first line says why), 1 on bad input (one line on
stderr saying why), 2 on a usage error.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from pathlib import Path

from .cli_curve import add_curve_command, run_curve

__all__ = ["main", "build_parser"]

PROG = "iwan-element"
EXIT_OK, EXIT_INPUT, EXIT_USAGE, EXIT_NOT_USABLE = 0, 1, 2, 3


class _UsageError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage dump) that main() turns into exit status 2."""

    def error(self, message):
        raise _UsageError(message)


def _add_record_args(parser, *, many: bool = False) -> None:
    """The arguments that locate and read a test record (shared by the subcommands)."""
    if many:
        parser.add_argument(
            "csv", type=Path, nargs="+", help="test record(s): time, displacement, force columns"
        )
    else:
        parser.add_argument("csv", type=Path, help="test record: time, displacement, force columns")
    parser.add_argument(
        "--units",
        metavar="DISP,FORCE[,TIME]",
        help="units of the displacement, force (and time) columns, e.g. mm,kN "
        "(displacement: m, mm, um, in; force: N, kN, MN, lbf, kip; "
        "time: s, ms, min; default time unit s). Default: read from the "
        "header ('displacement [mm]'); a unit is never guessed",
    )
    parser.add_argument(
        "--columns",
        metavar="T,U,F",
        help="names or 0-based indices of the time, displacement, force columns",
    )
    parser.add_argument("--delimiter", help="field separator (default: guessed)")


def _add_fit_command(sub):
    """The ``fit`` command and its options."""
    fit = sub.add_parser(
        "fit",
        help="identify Fs, KT, chi, beta from a quasi-static test record (CSV)",
        description="Identify the four Iwan parameters from a CSV of time, displacement and "
        "force and print the report. Methods: 'loops' fits the measured force "
        "history with the exact model (default); 'dissipation' fits the per-cycle "
        "force amplitude and dissipation by least squares; 'seed' is the seed "
        "paper's procedure (needs --slip-force).",
    )
    _add_record_args(fit)
    fit.add_argument("--method", choices=("loops", "dissipation", "seed"), default="loops")
    fit.add_argument(
        "--slip-force",
        type=float,
        metavar="FS",
        help="slip force Fs in the force unit of --units (method 'seed' only)",
    )
    fit.add_argument(
        "--smooth",
        type=int,
        default=None,
        metavar="N",
        help="Savitzky-Golay window (odd, samples, >= 7; 0 = none) for the "
        "displacement that drives the model (method 'loops'; default: "
        "automatic, from the estimated displacement noise)",
    )
    fit.add_argument("--seed", type=int, default=0, help="seed of the random starts (default 0)")
    fit.add_argument("--starts", type=int, default=6, help="optimiser starts (default 6)")
    fit.add_argument(
        "--plot",
        type=Path,
        metavar="PNG",
        help="write measured vs fitted loops and the dissipation plot",
    )
    fit.add_argument(
        "--json",
        type=Path,
        metavar="FILE",
        help="write the result as JSON (params loadable with IwanParameters.from_dict(d['joint']))",
    )


def _add_diagnose_command(sub):
    """The ``diagnose`` command and its options."""
    dg = sub.add_parser(
        "diagnose",
        help="find which physical effect the Iwan fit misses (CSV test record)",
        description="Fit the four-parameter Iwan model with the sensor offsets as nuisance "
        "parameters, estimate the force noise from the record, decide whether the "
        "misfit is more than noise, locate it, refit with each candidate effect and "
        "name the ones the data support (or none).",
    )
    _add_record_args(dg, many=True)
    dg.add_argument(
        "--max-effects", type=int, default=3, metavar="N", help="most effects named (default 3)"
    )
    dg.add_argument(
        "--noise",
        type=float,
        metavar="SIGMA",
        help="force noise standard deviation in the force unit of --units "
        "(default: estimated from the record)",
    )
    dg.add_argument(
        "--lowpass",
        type=float,
        metavar="HZ",
        help="zero-phase low-pass [Hz] removing test-rig ringing before fitting",
    )
    dg.add_argument("--seed", type=int, default=0, help="seed of the base fit's random starts")
    dg.add_argument(
        "--plot",
        type=Path,
        metavar="PNG",
        help="write data, base and augmented fit and the residuals before/after",
    )
    dg.add_argument("--json", type=Path, metavar="FILE", help="write the diagnosis as JSON")
    dg.add_argument(
        "--jobs",
        type=int,
        default=None,
        metavar="N",
        help="with several records: worker processes (default: one per core)",
    )
    dg.add_argument(
        "--table", type=Path, metavar="CSV", help="with several records: write the table as CSV"
    )
    dg.add_argument("--progress", action="store_true", help="show a progress bar (needs tqdm)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (subcommands; more will be added, e.g. ``diagnose``)."""
    from . import __version__

    parser = _Parser(prog=PROG, description="Segalman's four-parameter Iwan bolted-joint model.")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="<command>", parser_class=_Parser)
    sub.required = True
    _add_fit_command(sub)
    _add_diagnose_command(sub)
    add_curve_command(sub)
    return parser


def _run_diagnose(args) -> tuple[int, list[str]]:
    from .diagnose import diagnose
    from .identify.files.csv_input import FORCE_UNITS

    if len(args.csv) > 1 or args.jobs is not None or args.table is not None:
        return _run_diagnose_many(args)
    data = _load_loops(args.csv[0], args)
    noise = None if args.noise is None else args.noise * FORCE_UNITS[data.units["force"]]
    result = diagnose(
        data.t,
        data.u,
        data.F,
        max_effects=args.max_effects,
        noise=noise,
        lowpass=args.lowpass,
        seed=args.seed,
        progress=args.progress,
    )
    wrote = []  # files first: a closed stdout must not cost the outputs
    if args.json is not None:
        args.json.write_text(json.dumps(result.to_dict(), indent=2, allow_nan=False) + "\n")
        wrote.append(f"wrote {args.json}")
    if args.plot is not None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(11, 4.5))
        result.plot(ax=[fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)])
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
        wrote.append(f"wrote {args.plot}")
    status = EXIT_OK if result.success else EXIT_NOT_USABLE
    return status, [
        f"{data.source}: {len(data.u)} samples, {len(data.cycles)} cycles, units "
        f"{_units_text(data)} (converted to SI)",
        result.report(),
    ] + wrote


def _run_diagnose_many(args) -> tuple[int, list[str]]:
    """Several records: one table on stdout, one JSON (and CSV table) for the run."""
    from concurrent.futures import ProcessPoolExecutor

    from .diagnose import diagnose_many
    from .identify.files.csv_input import FORCE_UNITS

    if args.plot is not None:
        raise ValueError(
            "--plot draws one record; with several records use --json/--table "
            "(or diagnose the record alone)"
        )
    if args.jobs is not None and args.jobs < 1:
        raise ValueError(f"--jobs must be >= 1, got {args.jobs}")
    records = []
    for path in args.csv:
        data = _load_loops(path, args)
        records.append((data.t, data.u, data.F))
    noise = None if args.noise is None else args.noise * FORCE_UNITS[data.units["force"]]
    opts = {
        "max_effects": args.max_effects,
        "noise": noise,
        "lowpass": args.lowpass,
        "seed": args.seed,
    }
    names = [p.name for p in args.csv]
    if args.jobs == 1:
        batch = diagnose_many(
            records, names=names, executor="serial", progress=args.progress, **opts
        )
    else:
        with ProcessPoolExecutor(args.jobs) as pool:
            batch = diagnose_many(
                records, names=names, executor=pool, progress=args.progress, **opts
            )
    wrote = []
    if args.json is not None:
        args.json.write_text(json.dumps(batch.to_dict(), indent=2, allow_nan=False) + "\n")
        wrote.append(f"wrote {args.json}")
    if args.table is not None:
        wrote.append(f"wrote {batch.to_csv(args.table)}")
    return EXIT_OK if batch.success else EXIT_NOT_USABLE, [batch.report()] + wrote


def _run_curve(args) -> tuple[int, list[str]]:
    ok, lines = run_curve(args)
    return EXIT_OK if ok else EXIT_NOT_USABLE, lines


def _load_loops(path: Path, args):
    """A loop record (``load_test``) with the flags' units and columns; a ring-down or sweep
    file is refused naming ``curve``, and the columns are spoken of as the flag.
    """
    from .identify.files.csv_input import load_test
    from .identify.files.vibration import file_kind

    kind = file_kind(path)
    if kind in ("ringdown", "sweep"):
        raise ValueError(
            f"{path} is a {'ring-down' if kind == 'ringdown' else 'stepped-sine sweep'} record "
            f"(its header has no displacement and force columns): `{PROG} {args.command}` reads "
            f"force-displacement loops; use `{PROG} curve {path}` for its frequency and damping "
            "against amplitude"
        )
    du, fu, tu = _parse_units(args.units)
    try:
        return load_test(
            path,
            displacement_unit=du,
            force_unit=fu,
            time_unit=tu,
            columns=_parse_columns(args.columns),
            delimiter=args.delimiter,
        )
    except ValueError as exc:
        text = str(exc).replace("columns=(time, displacement, force)", "--columns T,U,F")
        text = text.replace("read by read_vibration_csv", f"read by `{PROG} curve`")
        raise ValueError(text) from None


def _units_text(data) -> str:
    u = data.units
    return f"{u['displacement']}, {u['force']}, {u['time']}"


def _parse_units(text: str | None) -> tuple:
    if text is None:  # from the file's header (load_test refuses a guess)
        return None, None, None
    parts = [s.strip() for s in text.split(",")]
    if len(parts) not in (2, 3) or not all(parts):
        raise ValueError(
            f"--units must be DISP,FORCE or DISP,FORCE,TIME (e.g. mm,kN), got {text!r}"
        )
    return parts[0], parts[1], parts[2] if len(parts) == 3 else "s"


def _parse_columns(text: str | None):
    if text is None:
        return None
    parts = [s.strip() for s in text.split(",")]
    if len(parts) != 3 or not all(parts):
        raise ValueError(f"--columns must name three columns T,U,F, got {text!r}")
    return tuple(int(p) if p.lstrip("-").isdigit() else p for p in parts)


def _run_fit(args) -> tuple[int, list[str]]:
    from .identify.files.csv_input import FORCE_UNITS
    from .identify.loops.dissipation import fit_dissipation
    from .identify.loops.fit import fit_loops

    data = _load_loops(args.csv, args)
    if args.method != "seed" and args.slip_force is not None:
        raise ValueError("--slip-force is only used by --method seed")
    if args.slip_force is not None:
        from .base.validation import check_scalar

        check_scalar("--slip-force", args.slip_force, low=0.0, low_open=True)
    with warnings.catch_warnings(record=True):  # the report lists every warning
        warnings.simplefilter("always")
        if args.method == "loops":
            result = fit_loops(
                data.t,
                data.u,
                data.F,
                smooth="auto" if args.smooth is None else args.smooth,
                seed=args.seed,
                n_starts=args.starts,
            )
        else:
            if args.smooth is not None:
                raise ValueError("--smooth is only used by --method loops")
            table = data.amplitude_table()
            if args.method == "seed":
                if args.slip_force is None:
                    raise ValueError(
                        "--method seed needs --slip-force (the paper takes Fs as known)"
                    )
                result = fit_dissipation(
                    table["u0"],
                    table["F0"],
                    table["D"],
                    method="seed",
                    Fs=args.slip_force * FORCE_UNITS[data.units["force"]],
                )
            else:
                result = fit_dissipation(
                    table["u0"],
                    table["F0"],
                    table["D"],
                    method="least_squares",
                    seed=args.seed,
                    n_starts=args.starts,
                )
    wrote = []  # files first: a closed stdout must not cost the outputs
    if args.json is not None:
        out = result.to_dict()
        out["data"] = {
            "source": data.source,
            "units": data.units,
            "samples": len(data.u),
            "cycles": len(data.cycles),
            "usable_cycles": len(data.usable_cycles()),
        }
        args.json.write_text(json.dumps(out, indent=2, allow_nan=False) + "\n")
        wrote.append(f"wrote {args.json}")
    if args.plot is not None:
        from .plotting import fit_figure

        fig, notes = fit_figure(data, result)
        fig.savefig(args.plot, dpi=120)
        wrote += notes + [f"wrote {args.plot}"]
    head = (
        f"{data.source}: {len(data.u)} samples, {len(data.cycles)} cycles "
        f"({len(data.usable_cycles())} usable), units {_units_text(data)} (converted to SI)"
    )
    return EXIT_OK if result.success else EXIT_NOT_USABLE, [head, result.report()] + wrote


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status (see the module docstring)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except _UsageError as exc:
        print(f"{PROG}: error: {exc} (see {PROG} --help)", file=sys.stderr)
        return EXIT_USAGE
    runners = {"fit": _run_fit, "diagnose": _run_diagnose, "curve": _run_curve}
    try:
        status, lines = runners[args.command](args)
    except (ValueError, OSError) as exc:
        _print_or_drop(f"{PROG}: error: {' '.join(str(exc).split())}", sys.stderr)
        return EXIT_INPUT
    _print_or_drop("\n".join(lines), sys.stdout)
    return status


def _print_or_drop(text: str, stream) -> None:
    """Print ``text``; if the reader has gone (``| head -1``, ``| true``), drop the rest quietly.

    The runners write their files before anything is printed, so a closed pipe only loses the
    printed copy. The stream's descriptor is pointed at /dev/null so that the interpreter's
    final flush does not raise ``BrokenPipeError`` again.
    """
    try:
        print(text, file=stream)
        stream.flush()
    except BrokenPipeError:
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, stream.fileno())
            os.close(devnull)
        except (OSError, ValueError, AttributeError):  # not a real file (e.g. captured)
            pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
