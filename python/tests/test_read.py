"""hbid.read: files as the command line reads them, with repairs, gaps and clear errors."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest

import hbid


def write_csv(path, t, x, header="t,theta"):
    with open(path, "w") as f:
        f.write(header + "\n")
        for ti, xi in zip(t, x):
            f.write(f"{float(ti)!r},{float(xi)!r}\n")
    return path


def test_reads_a_csv_onto_its_grid(tmp_path, pendulum):
    path = write_csv(tmp_path / "r.csv", pendulum.t, pendulum.x)
    record = hbid.read(path)
    assert isinstance(record.x, np.ndarray) and record.x.dtype == np.float64
    np.testing.assert_array_equal(record.x, pendulum.x)
    assert record.pieces == [(0, len(pendulum.x))]
    assert record.dt == pytest.approx(2 * np.pi / 25, rel=1e-12)
    assert record.t0 == pytest.approx(pendulum.t[0], abs=1e-9)
    np.testing.assert_allclose(record.t, pendulum.t, rtol=0, atol=1e-9)
    assert record.notes == [] and record.time_repairs == [] and record.spikes == []
    assert record.signal == "circle" and record.path == str(path)


def test_reads_npy_with_a_step(tmp_path, pendulum):
    path = tmp_path / "x.npy"
    np.save(path, pendulum.x)
    record = hbid.read(path, dt=0.25)
    np.testing.assert_array_equal(record.x, pendulum.x)
    assert record.t0 == pytest.approx(0.0, abs=1e-12) and record.dt == pytest.approx(0.25, rel=1e-12)
    with pytest.raises(hbid.InputError, match="give its sampling step with dt="):
        hbid.read(path)


def test_gaps_become_pieces_and_notes(tmp_path, pendulum):
    keep = np.r_[0:1000, 1010:3000]
    path = write_csv(tmp_path / "gap.csv", pendulum.t[keep], pendulum.x[keep])
    record = hbid.read(path)
    assert record.pieces == [(0, 1000), (1010, 3000)]
    assert np.isnan(record.x[1000:1010]).all()
    assert record.samples == 2990 and len(record) == 3000
    assert record.notes == [
        "1 gap(s) in the time stamps (10 samples missing): the record is analysed in 2 pieces"
    ]


def test_short_gaps_are_bridged_on_request_and_the_record_keeps_it(tmp_path, pendulum):
    # Rows 500, 1200 and 1201 dropped (a logger's lost rows), and a gap of 10 too long to bridge.
    keep = np.setdiff1d(np.arange(3000), np.r_[500, 1200, 1201, 2000:2010])
    path = write_csv(tmp_path / "dropped.csv", pendulum.t[keep], pendulum.x[keep])
    assert len(hbid.read(path).pieces) == 4
    record = hbid.read(path, bridge_gaps=2)
    assert record.pieces == [(0, 2000), (2010, 3000)]
    assert record.notes == [
        "1 gap(s) in the time stamps (10 samples missing): the record is analysed in 2 pieces",
        "2 gap(s) of at most 2 missing sample(s) bridged: 3 sample(s) interpolated in every column by the cubic "
        "through the two samples on each side",
    ]
    # The paper's 25 samples per period: the cubic misses by up to 1.2e-3 rad here (a straight
    # line between the neighbours of sample 500 would miss by 1.4e-2).
    missing = [500, 1200, 1201]
    error = np.abs(np.angle(np.exp(1j * (record.x[missing] - pendulum.x[missing]))))
    assert 0 < error.max() < 3e-3
    np.testing.assert_array_equal(record.x[keep[keep < 2000]], pendulum.x[keep[keep < 2000]])
    with pytest.raises(hbid.OptionsError, match="bridge_gaps: the Record was read with its own"):
        hbid.identify(record, bridge_gaps=1)
    with pytest.raises(hbid.OptionsError, match="at most 4"):
        hbid.read(path, bridge_gaps=5)


def test_a_glitch_is_an_error_unless_repaired(tmp_path, pendulum):
    t = pendulum.t.copy()
    t[500] += 0.4 * (t[1] - t[0])
    path = write_csv(tmp_path / "glitch.csv", t, pendulum.x)
    with pytest.raises(hbid.InputError, match="line 502: time .* run with repair=True") as e:
        hbid.read(path)
    assert isinstance(e.value, ValueError)
    record = hbid.read(path, repair=True)
    assert record.repaired
    assert len(record.time_repairs) == 1
    where, was, now = record.time_repairs[0]
    assert where == "line 502" and was == t[500]
    assert now == pytest.approx(pendulum.t[500], abs=1e-9)
    assert record.notes[0].startswith("line 502: time ")


def test_spikes_warn_and_are_replaced_with_repair(tmp_path, pendulum):
    """By default a spike is replaced only when a lone sample would decide by it (larger than
    the record's own steps, here 0.72 rad at the 99th percentile) and spikes are few (at most
    one in 1000 samples): an encoder's bit errors of half a turn are, with a note; a spike within
    the record's steps is kept with a warning. ``repair=True`` replaces every one,
    ``no_repair=True`` none (a warning)."""
    x = pendulum.x.copy()
    bit_errors = [1234, 2345]
    for i in bit_errors:
        x[i] = hbid_wrap(x[i] + np.pi)
    path = write_csv(tmp_path / "bits.csv", pendulum.t, x)
    with warnings.catch_warnings():
        warnings.simplefilter("error", hbid.HbidWarning)
        record = hbid.read(path)
    assert [(s[0], s[2]) for s in record.spikes] == [(i, True) for i in bit_errors]
    assert all(abs(abs(s[1]) - np.pi) < 0.05 for s in record.spikes)
    assert np.abs(record.x[bit_errors] - pendulum.x[bit_errors]).max() < 0.05
    assert "replaced by the local prediction (by default" in record.notes[0]
    assert record.notes[0].endswith("run with no_repair=True to keep them")
    with pytest.warns(hbid.HbidWarning, match="repair=True"):
        kept = hbid.read(path, no_repair=True)
    assert [(s[0], s[2]) for s in kept.spikes] == [(i, False) for i in bit_errors]
    np.testing.assert_array_equal(kept.x[bit_errors], x[bit_errors])

    # Too many to be bit errors of a sound encoder (more than one in 1000 samples): kept.
    many = pendulum.x.copy()
    for i in range(300, 3000, 600):
        many[i] = hbid_wrap(many[i] + np.pi)
    with pytest.warns(hbid.HbidWarning, match="more than one in 1000 samples"):
        record = hbid.read(write_csv(tmp_path / "many.csv", pendulum.t, many))
    assert len(record.spikes) == 5 and not any(s[2] for s in record.spikes)

    # Within the record's own steps: a sample the motion could reach, kept unless repair=True.
    small = pendulum.x.copy()
    small[1234] = hbid_wrap(small[1234] + 0.2)
    path = write_csv(tmp_path / "small.csv", pendulum.t, small)
    with pytest.warns(hbid.HbidWarning, match="within the record's own steps"):
        record = hbid.read(path)
    assert [s[0] for s in record.spikes] == [1234] and record.spikes[0][2] is False
    assert record.x[1234] == small[1234]
    fixed = hbid.read(path, repair=True)
    assert fixed.spikes[0][:1] == (1234,) and fixed.spikes[0][2] is True
    assert abs(fixed.x[1234] - pendulum.x[1234]) < 0.05
    with pytest.raises(hbid.OptionsError, match="not both"):
        hbid.read(path, repair=True, no_repair=True)


def hbid_wrap(v):
    return (v + np.pi) % (2 * np.pi) - np.pi


def test_unwrapped_angles_are_wrapped(tmp_path, pendulum):
    t, x, v = hbid.simulate(samples=500, unwrapped=True)
    assert np.abs(x).max() > np.pi
    record = hbid.read(write_csv(tmp_path / "u.csv", t, x))
    assert record.notes == ["values outside [-π, π): read as an unwrapped angle and wrapped"]
    assert record.x.min() >= -np.pi and record.x.max() < np.pi


def test_columns_by_name_and_position(tmp_path, pendulum):
    path = tmp_path / "cols.csv"
    with open(path, "w") as f:
        f.write("time;angle;other\n")
        for ti, xi in zip(pendulum.t[:200], pendulum.x[:200]):
            f.write(f"{float(ti)!r};{float(xi)!r};1\n")
    by_name = hbid.read(path, time_col="time", angle_col="angle")
    by_position = hbid.read(path, time_col=1, angle_col=2)
    np.testing.assert_array_equal(by_name.x, by_position.x)
    with pytest.raises(hbid.InputError, match="choose one with time_col="):
        hbid.read(path)
    with pytest.raises(hbid.InputError, match="no angle column 7"):
        hbid.read(path, time_col=1, angle_col=7)
    with pytest.raises(hbid.OptionsError):
        hbid.read(path, time_col=1.5)


@pytest.mark.parametrize(
    "content, message",
    [
        ("t,theta\n0,0.1\n1,abc\n", "line 3: 'abc' in column 'theta' is not a number"),
        ("t,theta\n0,0.1\n", "1 samples: at least 2 are needed"),
        ("", "empty"),
        ("t,theta\n0,0.1\n1,0.2,3\n", "line 3: 3 cells where the first row has 2"),
    ],
)
def test_bad_files_raise_input_errors_with_the_cli_messages(tmp_path, content, message):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(hbid.InputError, match=message):
        hbid.read(path)


def test_missing_file_folder_and_bad_options(tmp_path):
    with pytest.raises(hbid.InputError, match="nope.csv"):
        hbid.read(tmp_path / "nope.csv")
    with pytest.raises(hbid.InputError, match="folder"):
        hbid.read(tmp_path)
    with pytest.raises(hbid.OptionsError, match="signal='ring'"):
        hbid.read(tmp_path / "x.csv", signal="ring")
    with pytest.raises(hbid.OptionsError, match="dt=-1: must be positive and finite"):
        hbid.read(tmp_path / "x.csv", dt=-1.0)


def test_complex_and_boolean_samples_are_refused():
    """A conversion to floats would take the real part (with only NumPy's warning) or 0 and 1."""
    x = np.sin(np.arange(400) * 0.1)
    for bad, what in ((x + 1j, "complex"), (x > 0, "boolean"), ([complex(v) for v in x], "complex")):
        with pytest.raises(hbid.OptionsError, match=f"x: {what} values"):
            hbid.read(bad, dt=0.1)
    with pytest.raises(hbid.OptionsError, match="t: complex values"):
        hbid.read(x, t=np.arange(400) * 0.1 + 0j)
    with pytest.raises(hbid.OptionsError, match="x: complex values"):
        hbid.identify(np.column_stack([x, x]) + 2j, dt=0.1, coords=["a", "b"], terms="sin(a), sin(b)")


def test_records_pickle(tmp_path, pendulum):
    record = hbid.read(write_csv(tmp_path / "r.csv", pendulum.t[:300], pendulum.x[:300]))
    back = pickle.loads(pickle.dumps(record))
    np.testing.assert_array_equal(back.x, record.x)
    assert (back.t0, back.dt, back.pieces, back.notes) == (record.t0, record.dt, record.pieces, record.notes)


def test_the_paper_data_set(paper_csv):
    record = hbid.read(paper_csv)
    assert record.samples == 30000 and record.pieces == [(0, 30000)]
    assert record.dt == pytest.approx(2 * np.pi / 25, rel=1e-9)


def test_rows_with_a_missing_value_are_left_out_on_request(tmp_path, pendulum):
    # Rows 500 and 1200 of a logger's file hold no angle (an empty cell, NA).
    lines = [f"{float(t)!r},{float(x)!r}" for t, x in zip(pendulum.t[:3000], pendulum.x[:3000])]
    lines[500] = f"{float(pendulum.t[500])!r},"
    lines[1200] = f"{float(pendulum.t[1200])!r},NA"
    path = tmp_path / "missing.csv"
    path.write_text("t,theta\n" + "\n".join(lines) + "\n")
    with pytest.raises(hbid.InputError, match=r"line 502: '' in column 'theta' is not a number .*skip_missing=True"):
        hbid.read(path)
    record = hbid.read(path, skip_missing=True)
    assert record.pieces == [(0, 500), (501, 1200), (1201, 3000)]
    assert record.notes[0] == (
        "2 row(s) with a missing value in a column read left out, as a logger's dropped rows: line 502, line 1202"
    )
    bridged = hbid.read(path, skip_missing=True, bridge_gaps=1)
    assert bridged.pieces == [(0, 3000)] and bridged.bridged == [(500, 501), (1200, 1201)]
    # Arrays: a NaN is a missing value too, and the samples keep their times.
    x = pendulum.x[:3000].copy()
    x[[10, 2000]] = np.nan
    with pytest.raises(hbid.InputError, match="skip_missing=True"):
        hbid.read(x, t=pendulum.t[:3000])
    arrays = hbid.read(x, t=pendulum.t[:3000], skip_missing=True)
    assert arrays.pieces == [(0, 10), (11, 2000), (2001, 3000)]
    np.testing.assert_array_equal(arrays.x[11:2000], pendulum.x[11:2000])
