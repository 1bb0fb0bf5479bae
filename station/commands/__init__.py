"""The ``station`` command line: one module per command, each option declared once.

Every command module defines ``NAME`` (the subcommand), ``HELP`` (one line),
``configure(parser)`` (adds its arguments) and ``run(args) -> int`` (the exit code);
:mod:`station.cli` builds the parser from them. :mod:`station.commands.options` holds what
commands share: checked numbers (``number``) and the option groups declared once
(``add_model_options``: ``--model``/``--elements``/``--params``/``--no-model`` for every
command that simulates; ``add_seed_option``, ``add_protocol_option``,
``add_report_options``: ``--json``, ``--rrd``/``--spawn``; ``add_force_option``). A command
that writes files lists them all, derived ones included, with its inputs, and checks them with
:func:`station.outputs.check_outputs` before it starts; it writes them through a
:class:`station.outputs.Transaction` (tests/output_cases.py: one line per command).

A command parses, checks and prints; the work is a function of the package a notebook can
call too. Commands may import any ``station`` module; nothing in ``station`` imports them
except :mod:`station.cli`.
"""
