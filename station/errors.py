"""Errors meant for the user: the CLI prints them as one line, without a traceback."""


class StationError(Exception):
    """A failure the user can act on (bad file, missing port, bad option).

    The message names the file, line, field or port and what was expected.
    """
