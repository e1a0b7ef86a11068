"""The exceptions of :mod:`hbid`.

Every error of the Rust library arrives as one of these, with the message the command line
``hbid`` prints (the options named as the Python arguments that set them). Catch
:class:`HbidError` for all of them; the bad-value ones are also :class:`ValueError`, and a
capability the library does not have yet is also :class:`NotImplementedError`.

::

    HbidError
    ├── InputError           (ValueError)  the record: file, columns, time stamps, values
    ├── OptionsError         (ValueError)  an argument's value, or a combination of arguments
    ├── IdentificationError                a valid record that cannot be analysed as asked
    ├── SimulationError                    a simulation that failed
    ├── ModelError                         a saved model that cannot be read or made
    ├── OutputError          (OSError)     a result file that cannot be written
    └── NotSupportedError    (NotImplementedError)  not in the library yet
"""

from __future__ import annotations

__all__ = [
    "HbidError",
    "InputError",
    "OptionsError",
    "IdentificationError",
    "SimulationError",
    "ModelError",
    "OutputError",
    "NotSupportedError",
]


class HbidError(Exception):
    """Any error of :mod:`hbid`; its text is the command line's message."""


class InputError(HbidError, ValueError):
    """The record cannot be read or used: a missing file or column, a value that is not a
    number, time stamps that do not fit a grid (an isolated glitch can be repaired with
    ``repair=True``), too few samples."""


class OptionsError(HbidError, ValueError):
    """An argument's value is out of its range, or two arguments do not go together."""


class IdentificationError(HbidError):
    """A valid record that cannot be analysed as asked: too few orbit segments or windows, a
    rank-deficient system, no first minimum of the mutual information, a drive that cannot be
    estimated."""


class SimulationError(HbidError):
    """A simulation failed (the integrator could not reach the end)."""


class ModelError(HbidError):
    """A saved model cannot be read, or made from what was given (a file that cannot be
    written is an :class:`OutputError`)."""


class OutputError(HbidError, OSError):
    """A result file (a simulated record, its truth) cannot be written: its folder is missing, or
    it names a folder."""


class NotSupportedError(HbidError, NotImplementedError):
    """Asked for a capability the library does not have yet; the message names it."""
