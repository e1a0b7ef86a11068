"""hbid: identify the equation of motion of a forced (chaotic, whirling) oscillator from a
measured record, by harmonic balance.

The work is done in Rust (the application layer behind the command line ``hbid``), without the
interpreter's lock, so threads and Dask workers run side by side. Every function is the command
line's subcommand of the same name: its keywords are the subcommand's options, spelled with
``_`` for ``-``, with the same defaults, and results and messages are the command line's. Every
result is a plain, picklable object.

Example: the paper's pendulum, simulated and identified in three lines::

    import hbid
    t, x, v = hbid.simulate(samples=6000)
    result = hbid.identify(x, t=t, bootstrap=200)
    print(result.equation)
    result.coefficients["sin(t)*cos(x)"]     # about -1.52
    result.intervals["sin(t)*cos(x)"]        # 95 % bootstrap interval

A record from a file (text or ``.npy``), its drive frequency in Hz::

    result = hbid.identify("rig.csv", drive_frequency=1.02, repair=True)
    result.model.save("rig-model.json")

The functions:

- :func:`read` a record from a file; :func:`simulate` a rig's record;
- :func:`identify` the equation of motion (:class:`Identification`, with its :class:`Model`);
- :func:`embed`: the delay and the embedding dimension (:class:`Embedding`);
- :func:`upos`: unstable periodic orbits by close returns (:class:`Orbits`);
- :func:`compare`: a saved model run freely under a record's measured input and scored against
  its measured output (:class:`Comparison`), the validation on held-out data.

Several coordinates (a double pendulum's two angles, a robot arm's joints) are one system, one
equation per coordinate, from the record to the saved model, its free run and its comparison::

    sim = hbid.simulate(system="double-pendulum", samples=6400)
    result = hbid.identify({"theta1": sim.named["theta1"], "theta2": sim.named["theta2"]},
                           t=sim.t, terms={"theta1": "...", "theta2": "..."}, bootstrap=0)
    result.equations["theta1"].coefficients
    run = result.model.simulate(t=sim.t, x0=[...], v0=[...])   # t, theta1, theta2, theta1', theta2'

Errors are the exceptions of :mod:`hbid.errors`, all :class:`HbidError`.
"""

from __future__ import annotations

from . import _hbid
from ._common import HbidWarning
from ._compare import Comparison, ModelRun, RangeScore, RunPiece, compare
from ._embed import Embedding, Orbit, Orbits, embed, upos
from ._equation import DroppedTerm, Equation, Selection, SelectionStep
from ._identify import Identification, identify
from ._model import Model, SystemRun
from ._record import Record, read
from ._simulate import Simulation, simulate
from .errors import (
    HbidError,
    IdentificationError,
    InputError,
    ModelError,
    NotSupportedError,
    OptionsError,
    OutputError,
    SimulationError,
)

__version__: str = _hbid.__version__

__all__ = [
    "read",
    "simulate",
    "identify",
    "embed",
    "upos",
    "compare",
    "Record",
    "Comparison",
    "RangeScore",
    "RunPiece",
    "ModelRun",
    "Simulation",
    "Identification",
    "Equation",
    "Selection",
    "DroppedTerm",
    "SelectionStep",
    "Model",
    "SystemRun",
    "Embedding",
    "Orbits",
    "Orbit",
    "HbidWarning",
    "HbidError",
    "InputError",
    "OptionsError",
    "IdentificationError",
    "SimulationError",
    "ModelError",
    "OutputError",
    "NotSupportedError",
]
