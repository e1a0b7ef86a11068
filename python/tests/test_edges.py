"""Arguments and results at their edges: sizes no memory holds, flags that are not flags, a
result file that cannot be written, a Record's arrays edited, and a Record that left out a
logger's first rows, each met with a clear exception or warning rather than a crash, a silently
ignored edit or a shifted score."""

from __future__ import annotations

import numpy as np
import pytest

import hbid


def test_a_size_no_memory_holds_is_an_error_not_an_abort():
    for call in (
        lambda: hbid.simulate(samples=10**12),
        lambda: hbid.simulate(system="double-pendulum", samples=10**12),
    ):
        with pytest.raises(hbid.SimulationError, match="cannot be held in memory"):
            call()
    model = hbid.identify(hbid.simulate(samples=3000).x, dt=2 * np.pi / 25, bootstrap=0).model
    with pytest.raises(hbid.SimulationError, match="cannot be held in memory"):
        model.simulate(samples=10**12)
    with pytest.raises(hbid.OptionsError, match="at most 4096"):
        hbid.identify(hbid.simulate(samples=3000).x, dt=2 * np.pi / 25, basis="hat:1000000000")


def test_a_flag_is_true_or_false():
    x = hbid.simulate(samples=3000).x
    for name in ("repair", "no_repair", "skip_missing", "no_parametric"):
        with pytest.raises(hbid.OptionsError, match=f"{name}: 'no' is not True or False"):
            hbid.identify(x, dt=2 * np.pi / 25, bootstrap=0, **{name: "no"})
    for name in ("stream", "no_stream"):
        with pytest.raises(hbid.OptionsError, match=f"{name}: 'no' is not True or False"):
            hbid.identify(x, dt=2 * np.pi / 25, bootstrap=0, **{name: "no"})
    model = hbid.identify(x, dt=2 * np.pi / 25, bootstrap=0).model
    with pytest.raises(hbid.OptionsError, match="wrapped: 'no' is not True or False"):
        model.simulate(samples=100, wrapped="no")
    # NumPy's booleans are flags too.
    hbid.identify(x, dt=2 * np.pi / 25, bootstrap=0, repair=np.False_)


def test_save_model_is_checked_before_the_work(tmp_path):
    x = hbid.simulate(samples=3000).x
    with pytest.raises(hbid.OutputError, match="does not exist"):
        hbid.identify(x, dt=2 * np.pi / 25, bootstrap=0, save_model=tmp_path / "missing" / "m.json")
    with pytest.raises(hbid.OutputError):
        hbid.identify(x, dt=2 * np.pi / 25, bootstrap=0, save_model=tmp_path)


def test_a_model_with_a_measured_drive_needs_its_samples():
    sim = hbid.simulate(samples=3000, write_drive=True)
    model = hbid.identify(sim.x, t=sim.t, drive=sim.drive, bootstrap=0).model
    with pytest.raises(hbid.OptionsError, match="measured drive p: give its samples at the times t="):
        model.simulate(samples=100)


def test_a_records_first_coordinate_is_one_array(tmp_path):
    sim = hbid.simulate(samples=3000, write_drive=True, out=tmp_path / "r.csv")
    record = hbid.read(tmp_path / "r.csv", drive_col="p")
    assert np.shares_memory(record.x, record.positions["x"])
    assert np.shares_memory(record.drive, record.drives["p"])
    before = hbid.identify(record, bootstrap=0).coefficients["sin(x)"]
    # Another pendulum's motion (a weaker pull of gravity) written into the Record's array.
    record.x[:] = hbid.simulate(samples=3000, r=1 / np.sqrt(1.2), write_drive=True).x
    after = hbid.identify(record, bootstrap=0).coefficients["sin(x)"]
    assert before == pytest.approx(1.44, rel=1e-3) and after == pytest.approx(1.2, rel=1e-2)
    # A Record made anew with another first coordinate is that one's.
    import dataclasses

    again = dataclasses.replace(record, x=hbid.simulate(samples=3000, write_drive=True).x)
    assert hbid.identify(again, bootstrap=0).coefficients["sin(x)"] == pytest.approx(1.44, rel=1e-3)


def test_a_comparisons_repr_is_short():
    sim = hbid.simulate(samples=3000)
    model = hbid.identify(sim.x, dt=2 * np.pi / 25, bootstrap=0).model
    c = hbid.compare(model, sim.x, dt=2 * np.pi / 25, range=[(0, 1000), (1000, 2000), (2000, 3000)])
    assert len(repr(c)) < 5000


def test_comparing_a_record_without_the_loggers_first_rows_warns(tmp_path):
    """A logger's first rows stamped before it settled (1.7 steps apart, then 1): a Record read
    from the file leaves them out, so its comparison's ranges count from the grid, not row 0."""
    sim = hbid.simulate(samples=3000, write_drive=True)
    dt = sim.t[1] - sim.t[0]
    t = sim.t.copy()
    # The first four stamps early by 0.7 step each, one after the other: a slow start.
    t[:4] = t[4] - dt * (1 + 1.7 * np.arange(4, 0, -1) - 1.7)
    path = tmp_path / "late.csv"
    np.savetxt(path, np.column_stack([t, sim.x, sim.drive]), delimiter=",", header="t,theta,p", comments="")
    record = hbid.read(path, drive_col="p")
    assert record.lead_rows > 0
    model = hbid.identify(record, bootstrap=0).model
    with pytest.warns(hbid.HbidWarning, match=f"first {record.lead_rows} rows"):
        hbid.compare(model, record, range=(0, 500))
    # Left out of the file's comparison too, they count alike: nothing to warn of.
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", hbid.HbidWarning)
        hbid.compare(model, record, range=(0, 500), skip_unsettled=True)


def test_a_step_is_a_number_and_samples_are_an_array():
    x = hbid.simulate(samples=3000).x
    for dt in ("abc", "0.25", 1j, True):
        with pytest.raises(hbid.OptionsError, match="dt=.*: give a number"):
            hbid.read(x, dt=dt)
    with pytest.raises(hbid.OptionsError, match=r"x: no samples \(None\)"):
        hbid.identify(None, dt=0.25)
    with pytest.raises(hbid.OptionsError, match=r"not shape \(\)"):
        hbid.identify(np.float64(3.0), dt=0.25)


def test_a_masked_sample_is_a_missing_value():
    sim = hbid.simulate(samples=3000)
    x = np.ma.masked_array(sim.x, mask=np.zeros(sim.x.size, bool))
    x.mask[100] = True
    with pytest.raises(hbid.InputError, match="sample 101: a value is NaN.*skip_missing=True"):
        hbid.identify(x, t=sim.t, bootstrap=0)
    left_out = hbid.identify(x, t=sim.t, bootstrap=0, skip_missing=True)
    assert left_out.coefficients["sin(x)"] == pytest.approx(1.44, rel=1e-3)
