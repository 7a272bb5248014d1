"""The errors invflame raises for bad input, one type per domain.

Every message names what was wrong (the configuration key, the file and line, the variable),
the value found and what is allowed or how to fix it. The command line (:func:`invflame.cli.main`)
prints the message of any :class:`InvflameError` without a traceback and exits with status 2;
a :class:`ConfigError` may hold several messages, printed one per line.

The types subclass the built-in exceptions a caller would otherwise catch (``ValueError`` for
bad values, ``OSError`` for files and folders), so ``except ValueError`` keeps working.
"""

from __future__ import annotations


class InvflameError(Exception):
    """Base class of the errors in this module: bad input, explained in the message."""


class ConfigError(InvflameError, ValueError):
    """Configuration keys or values are invalid; each message names a key and what is allowed.

    Parameters
    ----------
    *messages : str
        One line per error found (a configuration is checked whole: every error at once).

    Attributes
    ----------
    messages : list of str
        The errors, one line each; ``str(error)`` joins them with newlines.
    """

    def __init__(self, *messages: str):
        super().__init__("\n".join(messages))
        self.messages = list(messages)


class InputDataError(InvflameError, ValueError):
    """A data file or array (line list, field, checkpoint, cached table) is unusable; the
    message names the file (and line) and what to do."""


class GeometryError(InvflameError, ValueError):
    """The cameras, rays or grid cannot make a measurement (cameras inside the grid, no ray
    crossing it)."""


class NumericsError(InvflameError, ValueError):
    """A computation produced non-finite or meaningless numbers."""


class OutputError(InvflameError, OSError):
    """An output path cannot be written: it is a file where a folder is needed, it lies under
    a file, or another process is writing the same run folder."""
