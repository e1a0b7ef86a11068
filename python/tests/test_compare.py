"""hbid.compare, hbid.simulate(model=, input=) and Model.simulate(t=, drive=): a saved model run
freely under a held-out record's measured drive, the same numbers as the command line."""

from __future__ import annotations

import dataclasses
import json
import subprocess

import numpy as np
import pytest

import hbid


def _shaker(**kwargs) -> hbid.Simulation:
    """A one-well Duffing oscillator on a shaker, its drive written as the column p."""
    common = dict(
        system="duffing", f=0.1, drive_frequency=6.5, sample_rate=2048, time_origin="first-sample", write_drive=True
    )
    common.update(kwargs)
    return hbid.simulate(**common)


@pytest.fixture(scope="module")
def shaker(tmp_path_factory):
    dir = tmp_path_factory.mktemp("shaker")
    train = _shaker(duration=30, x0=1.0)
    test = _shaker(duration=10, phase=1.0, noise=1e-3, seed=3, out=dir / "test.csv")
    result = hbid.identify(
        train.x,
        t=train.t,
        drive=train.drive,
        signal="line",
        drive_frequency=6.5,
        terms="x', x, x^3, p",
        bootstrap=0,
    )
    model = dir / "m.json"
    result.model.save(model)
    return dict(dir=dir, train=train, test=test, model=result.model, model_path=model, csv=dir / "test.csv")


def test_a_held_out_record_is_matched_to_its_noise(shaker):
    test = shaker["test"]
    c = hbid.compare(shaker["model"], test.x, t=test.t, drive=test.drive, init=100)
    assert c.measured_drive and len(c.ranges) == 1
    r = c.ranges[0]
    assert r.scored == len(test.t) - 100
    assert 0.9e-3 < r.rmse < 1.15e-3, r
    assert r.fit_percent == pytest.approx(100 * (1 - r.nrmse))
    piece = c.runs[0][0]
    assert piece.start == 0 and piece.init == 100
    assert np.allclose(piece.t, test.t) and np.allclose(piece.measured, test.x)
    assert np.sqrt(np.mean((piece.x[100:] - test.x[100:]) ** 2)) == pytest.approx(r.rmse)


def test_the_same_scores_as_the_command_line(shaker, cli):
    c = hbid.compare(shaker["model_path"], str(shaker["csv"]), drive_col="p", range=[(0, 5000), "5000.."], init=64)
    out = subprocess.run(
        [str(cli), "--quiet", "compare", str(shaker["model_path"]), str(shaker["csv"]), "--drive-col", "p",
         "--range", "0..5000", "--range", "5000..", "--init", "64", "--json"],
        capture_output=True, text=True, check=True,
    )
    assert json.loads(out.stdout) == json.loads(c.to_json())
    assert [r.range for r in c.ranges] == [(0, 5000), (5000, len(shaker["test"].t))]


def test_simulate_a_model_under_a_records_input(shaker, tmp_path):
    run = hbid.simulate(model=shaker["model"], input=str(shaker["csv"]), drive_col="p", init=100, out=tmp_path / "r.csv")
    t, x, v = run
    test = shaker["test"]
    assert run.stopped is None and len(run) == len(test.t)
    assert np.allclose(t, test.t) and np.max(np.abs(x - test.x)) < 6e-3
    written = np.loadtxt(tmp_path / "r.csv", delimiter=",", skiprows=1)
    assert np.array_equal(written[:, 1], x)
    with pytest.raises(hbid.OptionsError, match="f"):
        hbid.simulate(model=shaker["model"], input=str(shaker["csv"]), drive_col="p", f=2.0)
    with pytest.raises(hbid.OptionsError, match="input"):
        hbid.simulate(model=shaker["model"])
    with pytest.raises(hbid.OptionsError, match="x0"):
        hbid.simulate(model=shaker["model"], input=str(shaker["csv"]), drive_col="p", x0=1.0)


def test_model_simulate_at_given_times_with_a_drive(shaker):
    test = shaker["test"]
    run = hbid.compare(shaker["model"], test.x, t=test.t, drive=test.drive, init=100)
    x0, v0, _ = run.ranges[0].initial_states[0]
    t, x, v = shaker["model"].simulate(t=test.t, drive=test.drive, x0=x0, v0=v0)
    assert np.allclose(x, run.runs[0][0].x, atol=1e-9)
    with pytest.raises(hbid.OptionsError, match="drive"):
        shaker["model"].simulate(t=test.t, x0=x0, v0=v0)
    with pytest.raises(hbid.OptionsError, match="even grid"):
        shaker["model"].simulate(t=test.t ** 1.01, drive=test.drive, x0=x0, v0=v0)


def test_bad_requests(shaker):
    test = shaker["test"]
    with pytest.raises(hbid.OptionsError, match="drive_col"):
        hbid.compare(shaker["model"], str(shaker["csv"]))
    with pytest.raises(hbid.OptionsError, match="range"):
        hbid.compare(shaker["model"], test.x, t=test.t, drive=test.drive, range="0..99999999")
    with pytest.raises(hbid.OptionsError, match="x0"):
        hbid.compare(shaker["model"], test.x, t=test.t, drive=test.drive, x0=1.0)
    with pytest.raises(hbid.ModelError):
        hbid.compare(str(shaker["csv"]), test.x, t=test.t, drive=test.drive)


def test_a_refined_model_keeps_the_weak_forms_beside(shaker):
    """identify(refine=True): the coefficients refined by the free run's error on the record,
    the weak form's kept in ``refinement["start"]``; the free run's error does not grow."""
    train = shaker["train"]
    kwargs = dict(t=train.t, drive=train.drive, signal="line", drive_frequency=6.5, terms="x', x, x^3, p", bootstrap=0)
    weak = hbid.identify(train.x, **kwargs)
    refined = hbid.identify(train.x, refine=True, refine_init=100, **kwargs)
    r = refined.refinement
    assert weak.refinement is None and r is not None
    # Scored on the record as analysed: resampled onto a whole number of samples per period.
    assert r["init"] == 100 and 0.99 * len(train.t) < r["scored"] + 100 <= len(train.t)
    assert r["rmse_after"] <= r["rmse_before"]
    assert r["start"] == weak.coefficients
    assert list(refined.coefficients) == list(weak.coefficients)
    with pytest.raises(hbid.OptionsError, match="refine"):
        hbid.identify(train.x, refine_init=100, **kwargs)


def test_bridged_samples_are_run_through_and_not_scored(shaker, tmp_path):
    # Every 97th row of the held-out record dropped (a logger's lost rows), bridged on reading.
    lines = open(shaker["csv"]).read().splitlines()
    rows = lines[1:]
    dropped = [i for i in range(len(rows)) if i % 97 == 50]
    path = tmp_path / "dropped.csv"
    path.write_text("\n".join([lines[0]] + [r for i, r in enumerate(rows) if i % 97 != 50]) + "\n")
    record = hbid.read(path, drive_col="p", signal="line", bridge_gaps=1)
    assert record.bridged == [(i, i + 1) for i in dropped]
    c = hbid.compare(shaker["model"], record, init=100)
    r = c.ranges[0]
    # The first (row 50) is among the 100 samples that set the state: neither scored nor counted.
    after_init = [i for i in dropped if i >= 100]
    assert r.bridged == len(after_init) == len(dropped) - 1
    assert r.scored == len(rows) - 100 - len(after_init)
    piece = c.runs[0][0]
    assert len(c.runs[0]) == 1 and len(piece.t) == len(rows), "one run through every gap"
    assert np.isnan(piece.measured[dropped]).all()
    assert np.isfinite(np.delete(piece.measured, dropped)).all()
    kept = np.isfinite(piece.measured)
    kept[:100] = False
    assert np.sqrt(np.mean((piece.x[kept] - piece.measured[kept]) ** 2)) == pytest.approx(r.rmse)
    assert json.loads(c.to_json())["ranges"][0]["bridged"] == len(after_init)
    # A record whose bridged samples are not inside its pieces is refused, not scored.
    for bad in ([(0, 1)], [(5, 5)], [(len(rows) - 1, len(rows) + 3)]):
        with pytest.raises(hbid.OptionsError, match="bridged samples lie inside its pieces"):
            hbid.compare(shaker["model"], dataclasses.replace(record, bridged=bad), init=100)


def test_a_refinement_does_not_score_bridged_samples(shaker, tmp_path):
    # The held-out record with every 97th row dropped, bridged: its refinement runs through the
    # bridged samples and scores none of them (each one is one or two samples once resampled onto
    # a whole number of samples per drive period).
    lines = open(shaker["csv"]).read().splitlines()
    rows = lines[1:]
    path = tmp_path / "dropped.csv"
    path.write_text("\n".join([lines[0]] + [r for i, r in enumerate(rows) if i % 97 != 50]) + "\n")
    kwargs = dict(drive_col="p", signal="line", drive_frequency=6.5, terms="x', x, x^3, p", bootstrap=0)
    kwargs.update(refine=True, refine_init=100)
    whole = hbid.identify(str(shaker["csv"]), **kwargs).refinement
    bridged = hbid.identify(str(path), bridge_gaps=1, **kwargs).refinement
    after_init = len([i for i in range(len(rows)) if i % 97 == 50 and i >= 100])
    assert after_init <= whole["scored"] - bridged["scored"] <= 2 * after_init + 2, (whole, bridged)
    # Two records joined: the second one's bridged samples are left out as the first one's.
    whole2 = hbid.identify([str(shaker["csv"])] * 2, **kwargs).refinement
    bridged2 = hbid.identify([str(path)] * 2, bridge_gaps=1, **kwargs).refinement
    assert whole2["scored"] - bridged2["scored"] == 2 * (whole["scored"] - bridged["scored"]), (whole2, bridged2)


def _one_cell_edited(shaker, path, line, column, edit):
    """The held-out record written to ``path`` with the cell of ``column`` on ``line`` (from
    0, the header's 0) replaced by ``edit(cell)``; its lines."""
    lines = open(shaker["csv"]).read().splitlines()
    cells = lines[line].split(",")
    cells[column] = edit(cells[column])
    lines[line] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    return lines


def test_a_model_runs_on_an_input_with_missing_values_on_request(shaker, tmp_path):
    path = tmp_path / "na.csv"
    lines = _one_cell_edited(shaker, path, 3001, 1, lambda _: "NA")
    with pytest.raises(hbid.InputError, match="line 3002: 'NA' .*skip_missing=True"):
        hbid.simulate(model=shaker["model"], input=str(path), drive_col="p", init=100)
    t, x, v = hbid.simulate(model=shaker["model"], input=str(path), drive_col="p", init=100, skip_missing=True)
    # The row left out is a gap, which the run's samples skip (the run starts again after it).
    rows = len(lines) - 1
    assert len(t) == rows - 1 and np.isfinite(x).all()
    steps = np.diff(t)
    assert np.argmax(steps) == 2999 and steps[2999] == pytest.approx(2 * np.median(steps), rel=1e-6)
    with pytest.raises(hbid.OptionsError, match="skip_missing"):
        hbid.simulate(system="duffing", skip_missing=True)


def test_a_model_runs_on_an_input_with_a_glitch_on_request(shaker, tmp_path):
    path = tmp_path / "glitch.csv"
    dt = shaker["test"].t[1] - shaker["test"].t[0]
    lines = _one_cell_edited(shaker, path, 2001, 0, lambda t: repr(float(float(t) + 0.4 * dt)))
    with pytest.raises(hbid.InputError, match="line 2002: .*repair=True"):
        hbid.simulate(model=shaker["model"], input=str(path), drive_col="p", init=100)
    t, x, v = hbid.simulate(model=shaker["model"], input=str(path), drive_col="p", init=100, repair=True)
    assert len(t) == len(lines) - 1 and np.isfinite(x).all()
