"""What the commands share: checked command-line values and the option groups declared once
(the model options of every command that simulates, the simulated rig's seed, the wire
protocol, ``--json`` and rerun output, ``--force``). Output files follow one rule, checked
before anything starts: :mod:`station.outputs`.

A numeric option is declared with ``type=number(low, high, ...)`` (:mod:`station.ranges`, where
the simulated rig's ranges are shared with the ``sim://`` URL handler): argparse calls it on
the text, so a value that is not finite or outside the range is refused while the
arguments are parsed - before any file is opened or any device is touched - with
argparse's own one-line ``argument --x: ...`` error and exit code 2
(:class:`StationParser`). :func:`document_ranges` appends each option's range to its
``--help`` text, so the documented range is the checked one.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from station.errors import StationError
from station.inputs import exists, sim_model_file
from station.outputs import DEFAULT_OUT_DIR, FORCE_HELP, Input
from station.protocol import PROTOCOLS
from station.ranges import SIM_RIG, Number, number  # noqa: F401 (Number, number: the commands' import place)
from station.rig import DEFAULT_SOFT_LIMIT, DEFAULT_TIMEOUT


class StationParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line: ``station step: error: argument --x: ...``, exit 2.

    (argparse's default prints the usage first; the user asked for one line naming the
    option, and ``--help`` is there for the usage.)
    """

    def error(self, message: str):
        """argparse's hook: print ``PROG: error: MESSAGE`` on one line and exit 2.

        Parameters
        ----------
        message : str
            argparse's message (names the option and what was expected).
        """
        self.exit(2, f"{self.prog}: error: {message}\n")

    def _get_value(self, action: argparse.Action, arg_string: str):
        # argparse's one place where each value's text is converted: an empty value is refused
        # for every option and argument alike (Path("") is the working folder, silently; a
        # model, controller or reference of "" names nothing)
        if isinstance(arg_string, str) and not arg_string.strip() and action.nargs not in (argparse.PARSER,
                                                                                          argparse.REMAINDER):
            raise argparse.ArgumentError(action, f"an empty value {arg_string!r}: expected "
                                                 f"{action.metavar or action.dest.replace('_', ' ')}")
        return super()._get_value(action, arg_string)


def document_ranges(parser: argparse.ArgumentParser) -> None:
    """Append each :class:`Number` option's range to its help text (idempotent).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A command's parser, its options added.
    """
    for action in parser._actions:
        if isinstance(action.type, Number) and action.help not in (None, argparse.SUPPRESS):
            text = action.type.range_text()
            if text not in action.help:
                action.help = f"{action.help} [{text}]"


def numeric_actions(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The parser's options that take numbers: those with a :class:`Number` type or int/float.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A command's parser, its options added.
    """
    return [a for a in parser._actions if a.option_strings and (isinstance(a.type, Number) or a.type in (int, float))]


def warn(message: str) -> None:
    """One line on stderr that says which value wins (``station: note: ...``).

    Parameters
    ----------
    message : str
        The note, one line.
    """
    print(f"station: note: {message}", file=sys.stderr)


def check_port(port: str, option: str = "--port") -> None:
    """Refuse a port that is neither a URL nor an existing device, before anything starts.

    Parameters
    ----------
    port : str
        A port path or pyserial URL (``sim://``, ``socket://``, ...).
    option : str
        The option's name, for the message.

    Raises
    ------
    StationError
        ``--port PATH: no such device`` with the hint to ``station ports``.
    """
    port = str(port)
    if "://" not in port and not exists(port):
        raise StationError(f"{option} {port}: no such device; `station ports` lists this machine's serial ports "
                           f"(the simulated rig is sim://)")


MANY_ELEMENTS = (1, 2, 4, 10, 20, 50, 100)
"""Default element counts of ``--elements N [N ...]`` (a convergence study)."""


MODEL_HELP = "a built-in model's name (station/plant/models) or a model file (default tmm-fit)"
"""What ``--model NAME|FILE`` takes, in every command's help (DESIGN.md "Model file")."""


def add_model_options(parser: argparse.ArgumentParser, model_help: str = "", *, subject: str = "the model",
                      elements: str | None = "one", params: bool = True, no_model: str | None = None,
                      note: str = "") -> None:
    """``--model NAME|FILE`` and, as the command has them, ``--elements``, ``--params`` and
    ``--no-model``: the one declaration of the model options of every command that simulates.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    model_help : str
        What the command does with the model, appended to ``--model``'s help.
    subject : str
        How ``--model``'s help names the model (e.g. "the nominal model").
    elements : {"one", "many"} or None
        ``--elements N`` (overrides the model's element count), ``--elements N [N ...]``
        (``MANY_ELEMENTS``: the element counts to go through) or no ``--elements``.
    params : bool
        Add ``--params SET`` (a parameter set replacing the model's).
    no_model : str, optional
        Help of ``--no-model`` (skip the model); the option is added when given, and then
        ``args.model`` is False with ``--no-model`` (True otherwise) and ``--model``'s value
        is ``args.model_spec`` (see :func:`chosen_model`).
    note : str
        Appended to each option's help; ``{key}`` is replaced by the option's name without
        dashes (e.g. "simulated rig only (sim://?{key}=...)").
    """
    def more(text: str, key: str) -> str:
        return text + (f"; {note.format(key=key)}" if note else "")

    if no_model is not None:
        parser.add_argument("--no-model", dest="model", action="store_false", help=no_model)
    parser.add_argument("--model", dest="model_spec" if no_model is not None else "model", default=None,
                        metavar="NAME|FILE",
                        help=more(f"{subject}: {MODEL_HELP}" + (f"; {model_help}" if model_help else ""), "model"))
    count = SIM_RIG["elements"]  # the model's and sim://?elements='s range
    if elements == "one":
        parser.add_argument("--elements", type=count, default=None, metavar="N",
                            help=more("beam elements of the model (default: the model's, 4)", "elements"))
    elif elements == "many":
        parser.add_argument("--elements", type=count, nargs="+", default=list(MANY_ELEMENTS), metavar="N",
                            help=more(f"element counts (default {' '.join(map(str, MANY_ELEMENTS))})", "elements"))
    if params:
        parser.add_argument("--params", default=None, metavar="SET",
                            help=more("parameter set name or TOML file (default: the model's, tmm-fit)", "params"))


def chosen_model(args: argparse.Namespace) -> bool | str:
    """What ``--no-model``, ``--model`` and ``--elements`` ask for (:func:`add_model_options` with ``no_model``).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed options with ``model`` (False after ``--no-model``), ``model_spec`` and
        ``elements``.

    Returns
    -------
    bool or str
        False: no model; True: the default model (tmm-fit); else the ``--model`` value.

    Raises
    ------
    StationError
        ``--model`` or ``--elements`` with ``--no-model``.
    """
    if not args.model:
        if args.model_spec is not None or args.elements is not None:
            raise StationError(f"{'--model' if args.model_spec is not None else '--elements'}: not with --no-model")
        return False
    return args.model_spec or True


def add_seed_option(parser: argparse.ArgumentParser, default: int | None = None, note: str = "") -> None:
    """``--seed N``: the simulated rig's sensor noise seed, the same for every run.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    default : int, optional
        The default seed (None: the simulated rig's, 0).
    note : str
        Appended to the help; ``{key}`` becomes "seed" (as in :func:`add_model_options`).
    """
    parser.add_argument("--seed", type=SIM_RIG["seed"], default=default, metavar="N",
                        help="sensor noise seed, the same for every run (default 0)" + (f"; {note.format(key='seed')}" if note else ""))


def add_protocol_option(parser: argparse.ArgumentParser) -> None:
    """``--protocol v1|legacy``: the wire protocol of the device (default v1).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    """
    parser.add_argument("--protocol", choices=PROTOCOLS, default="v1", help="wire protocol (default v1)")


def add_report_options(parser: argparse.ArgumentParser, json: str | None = None, rerun: str | None = None) -> None:
    """``--json OUT`` and ``--rrd FILE`` or ``--spawn`` (one of them), as the command has them.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    json : str, optional
        What the JSON holds (e.g. "the report"); None: no ``--json``.
    rerun : str, optional
        What goes to a rerun recording or viewer (e.g. "the run"); None: neither option.
    """
    if json is not None:
        parser.add_argument("--json", type=Path, default=None, metavar="OUT", help=f"write {json} as JSON")
    if rerun is not None:
        viz = parser.add_mutually_exclusive_group()
        viz.add_argument("--rrd", type=Path, default=None, metavar="FILE", help=f"record {rerun} to a rerun .rrd file")
        viz.add_argument("--spawn", action="store_true", help=f"stream {rerun} to a rerun viewer")


def add_force_option(parser: argparse.ArgumentParser) -> None:
    """``--force``: replace output files that exist (the one rule, :mod:`station.outputs`).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The subparser of a command that writes files.
    """
    parser.add_argument("--force", action="store_true", help=FORCE_HELP)


def model_inputs(args: argparse.Namespace) -> list[Input]:
    """Every file a command reads because of its shared options and settings: inputs no
    output may replace (:func:`station.outputs.check_outputs`). One list for every command,
    so none forgets one: ``--model`` and ``--params``, the model file ``--port``'s
    ``sim://?model=FILE`` serves, and the settings file in use (``station.toml``, for the
    commands that read it: :func:`station.config.apply_config`). A command adds the files
    it is given itself (its logs, ``--robust``, ...).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed options (``model`` or ``model_spec``, ``params``, ``port``, ``_config``; any
        may be missing).
    """
    model = getattr(args, "model_spec", None) or getattr(args, "model", None)
    return [Input("--model", model if isinstance(model, (str, Path)) else None),
            Input("--params", getattr(args, "params", None)),
            Input("--port's model", sim_model_file(getattr(args, "port", None))),
            Input("station.toml", getattr(args, "_config", None))]


def add_link_options(parser: argparse.ArgumentParser, soft_limit_help: str = "") -> None:
    """Add the device's link and fail-safe bounds, one definition for every command that runs
    the rig (``station step``, ``station identify``): ``--baud``, ``--timeout``,
    ``--soft-limit``, ``--max-lag``, ``--max-miss``, ``--max-step``; ``station.toml`` may set
    each (:data:`station.config.KEYS`). :func:`link_limits` turns them into the link's limits.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        Gets the options.
    soft_limit_help : str, optional
        What the command adds to ``--soft-limit``'s help.
    """
    from station.link import LinkLimits  # lazy: start-up time (pyserial), every command builds its parser
    from station.plan import RANGES  # lazy: start-up time (numpy)

    parser.add_argument("--baud", type=RANGES["baudrate"], default=None,
                        help="baud rate (default 921600 for v1, 115200 legacy)")
    parser.add_argument("--timeout", type=RANGES["timeout"], default=DEFAULT_TIMEOUT, metavar="S",
                        help="longest wait for a sample before stopping safely (default 0.1 s)")
    parser.add_argument("--soft-limit", type=RANGES["soft_limit"], default=DEFAULT_SOFT_LIMIT, metavar="COUNTS",
                        help="stop safely when |θ| exceeds this (default 2048 = two revolutions)" + soft_limit_help)
    parser.add_argument("--max-lag", type=number(0, 1000, unit="ms"), default=1000 * LinkLimits.max_lag,
                        metavar="MS", help="how far the station may fall behind the device and catch up (skipped "
                        "samples and those that arrive while it computes, × 2 ms); more stops the run (reason lag). "
                        "A command is only ever computed from the newest sample (default 20 ms, the v1 watchdog's "
                        "10 ticks)")
    parser.add_argument("--max-miss", type=number(0, 99, integer=True), default=LinkLimits.max_miss, metavar="TICKS",
                        help="stop when more of the last 100 ticks than this were dropped, stale or duplicated "
                             "(reason sequence), or ran on a held command (late or skipped) beyond one catch-up of "
                             "--max-lag (reason lag) (default 10)")
    parser.add_argument("--max-step", type=number(1.0, 10000.0), default=LinkLimits.max_step, metavar="COUNTS",
                        help="largest plausible encoder change per tick; more stops the run (reason sequence; "
                             "default 40)")


def link_limits(args: argparse.Namespace):
    """The link's limits from the options of :func:`add_link_options`.

    Parameters
    ----------
    args : argparse.Namespace
        ``--timeout``, ``--max-lag`` (ms), ``--max-miss``, ``--max-step``.

    Returns
    -------
    station.link.LinkLimits
    """
    from station.link import LinkLimits  # lazy: start-up time (pyserial)

    return LinkLimits(timeout=args.timeout, max_lag=args.max_lag / 1000, max_miss=args.max_miss,
                      max_step=args.max_step)


OUT_DIR_HELP = f"(default: station.toml's out_dir, else {DEFAULT_OUT_DIR}/ in the working folder)"
"""How every ``--out-dir`` says where the station's output folder is by default."""


def add_out_dir_option(parser: argparse.ArgumentParser, what: str) -> None:
    """``--out-dir DIR``: the output folder where the command puts the files it names itself
    (one rule for every command, :mod:`station.outputs`); ``station.toml``'s ``out_dir`` is its
    default (:func:`station.config.apply_config`, called by the command after this).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    what : str
        What goes there (e.g. "the figures, <log stem>_compare.png").
    """
    parser.add_argument("--out-dir", type=Path, default=None, metavar="DIR", help=f"folder for {what} {OUT_DIR_HELP}")


def out_dir(args: argparse.Namespace) -> Path:
    """The output folder: ``--out-dir``, else ``station.toml``'s ``out_dir``, else ``runs``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed options of :func:`add_out_dir_option` (``out_dir``).
    """
    return Path(args.out_dir) if getattr(args, "out_dir", None) is not None else Path(DEFAULT_OUT_DIR)


def out_dir_label(args: argparse.Namespace) -> str:
    """How a message names the output folder, before its path: the option the user gave, the
    settings file that set it, or the default (never an option the user did not give).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed options (``out_dir``, and ``_config``/``_config_values`` from
        :func:`station.config.apply_config`).

    Returns
    -------
    str
        ``--out-dir``, ``station.toml's out_dir`` or ``the output folder``.
    """
    config = (getattr(args, "_config_values", None) or {}).get("out_dir")
    if getattr(args, "out_dir", None) is None:
        return "the output folder"
    if config is not None and Path(config) == Path(args.out_dir):
        return f"{getattr(args, '_config', None) or 'station.toml'}'s out_dir"
    return "--out-dir"


def out_dir_remedy(args: argparse.Namespace) -> str:
    """What a refusal of a file the command named in the output folder suggests besides
    ``--force``: another folder, naming the one in use and where it came from.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed options (as :func:`out_dir_label`).
    """
    return f"another folder than {out_dir_label(args)} {out_dir(args)} (--out-dir DIR)"


def config_error(args: argparse.Namespace) -> None:
    """Raise the settings file's error kept by :func:`station.config.apply_config`, if any.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed options.

    Raises
    ------
    StationError
        ``station.toml`` is not a regular file, not valid or holds a bad value.
    """
    if getattr(args, "_config_error", None):
        raise StationError(args._config_error)
