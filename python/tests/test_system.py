"""Several coordinates from Python: a system's record read, identified (one equation per
coordinate), saved, run freely and compared, with the command line's numbers, and bad inputs
refused as hbid errors."""

from __future__ import annotations

import json
import pickle
import re
import subprocess

import numpy as np
import pytest

import hbid

#: A clean, whirling double pendulum: its sharp turns are flagged by the spike test and kept
#: (a warning), which these tests do not look at.
pytestmark = pytest.mark.filterwarnings("ignore::hbid.HbidWarning")


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


@pytest.fixture(scope="module")
def double_pendulum(tmp_path_factory):
    """The noise-free double pendulum of ``hbid simulate --system double-pendulum``, 100 drive
    periods at 64 samples each, its record written and identified with the truth's options."""
    dir = tmp_path_factory.mktemp("double-pendulum")
    csv = dir / "dp.csv"
    sim = hbid.simulate(system="double-pendulum", samples=6400, out=csv, truth=dir / "truth.json")
    result = hbid.identify(csv, bootstrap=0, **sim.identify_options)
    return dict(dir=dir, csv=csv, sim=sim, result=result)


def test_the_truth_is_identified(double_pendulum):
    sim, result = double_pendulum["sim"], double_pendulum["result"]
    assert sim.columns == ("t", "theta1", "theta2", "omega1", "omega2")
    assert result.is_system and result.coordinates == ["theta1", "theta2"]
    assert set(result.equations) == set(sim.truth_equations)
    worst = 0.0
    for q, truth in sim.truth_equations.items():
        equation = result.equations[q]
        assert equation.coordinate == q and equation.terms == list(truth["coefficients"])
        assert equation.intervals is None and equation.explained > 0.999999
        for term, value in truth["coefficients"].items():
            worst = max(worst, abs(equation.coefficients[term] - value) / abs(value))
    # Measured: 1.0e-5 (the weak form on the clean record, as crates/hb-solve's double pendulum
    # test reaches); ten times that.
    assert worst < 1e-4, worst
    # Every equation's coefficients in one dict, keyed as the truth's.
    assert set(result.coefficients) == set(sim.truth)
    assert result.coefficients["theta2: sin(theta2)"] == result.equations["theta2"].coefficients["sin(theta2)"]
    assert result.equation.splitlines()[1].startswith("theta2'' + ")
    assert result.model.coordinates == ["theta1", "theta2"] and result.model.drives == []


def test_the_same_numbers_from_a_file_arrays_a_record_and_the_command_line(double_pendulum, cli):
    sim, result, csv = double_pendulum["sim"], double_pendulum["result"], double_pendulum["csv"]
    options = sim.identify_options
    out = subprocess.run(
        [str(cli), "--quiet", "identify", str(csv), "--json", "--bootstrap", "0", "--coords", options["coords"],
         "--signal", options["signal"], "--terms", options["terms"]],
        capture_output=True, text=True, check=True,
    )
    assert json.loads(out.stdout) == json.loads(result.to_json())

    # The terms per coordinate as a dict, the coordinates as a list.
    terms = {q: list(e["coefficients"]) for q, e in sim.truth_equations.items()}
    by_dict = hbid.identify(csv, coords=["theta1", "theta2"], terms=terms, bootstrap=0)
    assert by_dict.coefficients == result.coefficients

    # Arrays by coordinate name, and a Record read with the coordinates.
    arrays = {q: sim.named[q] for q in ("theta2", "theta1")}
    from_arrays = hbid.identify(arrays, t=sim.t, coords="theta1,theta2", terms=terms, bootstrap=0)
    assert from_arrays.coefficients == result.coefficients
    record = hbid.read(csv, coords=["theta1", "theta2"], velocity_col=["omega1", "omega2"])
    assert record.coordinates == ["theta1", "theta2"] and record.signals == ["circle", "circle"]
    np.testing.assert_array_equal(record.positions["theta2"], sim.named["theta2"])
    np.testing.assert_array_equal(record.velocities["theta1"], sim.named["omega1"])
    assert pickle.loads(pickle.dumps(record)).coordinates == record.coordinates
    assert hbid.identify(record, terms=terms, bootstrap=0).coefficients == result.coefficients

    # Bootstrap intervals per equation, as the command line's.
    boot = hbid.identify(csv, bootstrap=40, seed=2, **options)
    out = subprocess.run(
        [str(cli), "--quiet", "identify", str(csv), "--json", "--bootstrap", "40", "--seed", "2", "--coords",
         options["coords"], "--terms", options["terms"]],
        capture_output=True, text=True, check=True,
    )
    cli_json = json.loads(out.stdout)
    for q, equation in boot.equations.items():
        assert {k: tuple(v) for k, v in cli_json["equations"][q]["intervals"].items()} == equation.intervals
        lo, hi = equation.intervals["sin(" + q + ")"]
        assert lo < 0.8 < hi


def test_several_files_are_one_fit_as_on_the_command_line(double_pendulum, cli, tmp_path):
    sim, csv = double_pendulum["sim"], double_pendulum["csv"]
    other = tmp_path / "dp2.csv"
    hbid.simulate(system="double-pendulum", samples=3200, q0=(1.5, 0.5), out=other)
    joined = hbid.identify([csv, other], bootstrap=0, **sim.identify_options)
    assert joined.segments > double_pendulum["result"].segments
    out = subprocess.run(
        [str(cli), "--quiet", "identify", str(csv), str(other), "--json", "--bootstrap", "0", "--coords",
         "theta1,theta2", "--terms", sim.identify_options["terms"]],
        capture_output=True, text=True, check=True,
    )
    assert json.loads(out.stdout) == joined.report
    with pytest.raises(hbid.InputError, match="nope.csv"):
        hbid.identify([csv, tmp_path / "nope.csv"], bootstrap=0, **sim.identify_options)
    # Of several records, the one too short to resample is named, as on the command line.
    long, short = tmp_path / "long.csv", tmp_path / "short.csv"
    hbid.simulate(drive_frequency=1.3, sample_rate=500, samples=3000, out=long)
    hbid.simulate(drive_frequency=1.3, sample_rate=500, samples=129, out=short)
    with pytest.raises(hbid.IdentificationError, match="^" + re.escape(str(short)) + ": a drive period"):
        hbid.identify([long, short], drive_frequency=1.3, bootstrap=0)


def test_a_saved_system_round_trips_and_runs_as_the_command_line_runs_it(double_pendulum, cli):
    dir, csv, sim = double_pendulum["dir"], double_pendulum["csv"], double_pendulum["sim"]
    model = double_pendulum["result"].model
    model.save(dir / "m.json")
    model.save(dir / "m.bin")
    assert json.loads((dir / "m.json").read_text())["version"] == 5
    for path in ("m.json", "m.bin"):
        back = hbid.Model.load(dir / path)
        assert back == model and back.equations == model.equations
    assert pickle.loads(pickle.dumps(model)) == model
    assert hbid.Model.from_json(model.to_json()) == model

    # Python's compare is the command line's, a score per coordinate.
    compared = hbid.compare(dir / "m.json", str(csv), range=[(0, 640), "640.."])
    out = subprocess.run(
        [str(cli), "--quiet", "compare", str(dir / "m.json"), str(csv), "--json", "--range", "0..640",
         "--range", "640.."],
        capture_output=True, text=True, check=True,
    )
    assert json.loads(out.stdout) == compared.report
    assert compared.coordinates == ["theta1", "theta2"]
    assert [(r.range, r.coordinate) for r in compared.ranges] == [
        ((0, 640), "theta1"), ((0, 640), "theta2"), ((640, 6400), "theta1"), ((640, 6400), "theta2")
    ]
    assert list(compared.by_coordinate) == ["theta1", "theta2"]

    # The run from each coordinate's fitted state, at the record's times, is the command line's
    # run of the saved system under the record (hbid simulate --model --input).
    whole = hbid.compare(model, str(csv))
    x0 = [r.initial_states[0][0] for r in whole.ranges]
    v0 = [r.initial_states[0][1] for r in whole.ranges]
    run = model.simulate(t=sim.t, x0=x0, v0=v0)
    assert run.columns == ["t", "theta1", "theta2", "theta1'", "theta2'"]
    t, q1, q2, w1, w2 = run
    assert np.array_equal(run["theta2'"], w2) and np.array_equal(t, sim.t)
    subprocess.run(
        [str(cli), "--quiet", "simulate", "--model", str(dir / "m.bin"), "--input", str(csv), "--out",
         str(dir / "run.csv")],
        check=True,
    )
    with open(dir / "run.csv") as f:
        assert f.readline().strip() == "t,theta1,theta2,theta1',theta2'"
    cli_run = np.loadtxt(dir / "run.csv", delimiter=",", skiprows=1)
    assert np.abs(wrap(cli_run[:, 1] - q1)).max() < 1e-9
    assert np.abs(wrap(cli_run[:, 2] - q2)).max() < 1e-9
    assert np.abs(cli_run[:, 3] - w1).max() < 1e-9 and np.abs(cli_run[:, 4] - w2).max() < 1e-9
    same = hbid.simulate(model=model, input=str(csv))
    assert same.columns == ("t", "theta1", "theta2", "theta1'", "theta2'")
    np.testing.assert_array_equal(same.named["theta2'"], cli_run[:, 4])

    # The system is the record's: from the measured state, a drive period follows the record.
    start = model.simulate(t=sim.t[:64], x0=[sim.named["theta1"][0], sim.named["theta2"][0]],
                           v0=[sim.named["omega1"][0], sim.named["omega2"][0]])
    assert np.abs(wrap(start["theta1"] - sim.named["theta1"][:64])).max() < 1e-4


def test_measured_velocities_start_each_run(double_pendulum, cli):
    csv, model = double_pendulum["csv"], double_pendulum["result"].model
    c = hbid.compare(model, str(csv), velocity_col=["omega1", "omega2"], range=(0, 64))
    assert all(r.init == 0 and r.scored == 64 for r in c.ranges)
    assert all(r.rmse < 1e-4 for r in c.ranges), c.ranges
    model.save(csv.parent / "velocities.json")
    out = subprocess.run(
        [str(cli), "--quiet", "compare", str(csv.parent / "velocities.json"), str(csv), "--json", "--velocity-col",
         "omega1,omega2", "--range", "0..64"],
        capture_output=True, text=True, check=True,
    )
    assert json.loads(out.stdout) == c.report
    # A given state: every sample scored from it.
    x0 = [r.initial_states[0][0] for r in c.ranges]
    v0 = [r.initial_states[0][1] for r in c.ranges]
    given = hbid.compare(model, str(csv), x0=x0, v0=v0, range=(0, 64))
    assert [r.rmse for r in given.ranges] == pytest.approx([r.rmse for r in c.ranges], rel=1e-6)


def test_a_saved_system_runs_from_a_given_state(tmp_path):
    """simulate(model=, input=, init=0) of a system from one value per coordinate, by x0 and
    v0 or by q0 and dq0: the same run, from that state."""
    sim = hbid.simulate(system="arm", samples=2000, out=tmp_path / "arm.csv")
    n = sim.named
    model = hbid.identify(str(tmp_path / "arm.csv"), bootstrap=0, **sim.identify_options).model
    model.save(tmp_path / "arm-model.json")
    run = lambda **state: hbid.simulate(
        model=str(tmp_path / "arm-model.json"), input=str(tmp_path / "arm.csv"), drive_col=["tau1", "tau2"], init=0, **state
    )
    by_x = run(x0=[0.1, 0.0], v0=[0.0, 0.0])
    by_q = run(q0=[0.1, 0.0], dq0=[0.0, 0.0])
    np.testing.assert_array_equal(by_x.named["q1"], by_q.named["q1"])
    assert by_x.named["q1"][0] == pytest.approx(0.1, abs=1e-12) and by_x.named["q2"][0] == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(hbid.OptionsError, match="init"):
        hbid.simulate(model=str(tmp_path / "arm-model.json"), input=str(tmp_path / "arm.csv"), drive_col=["tau1", "tau2"], q0=[0.1, 0.0])
    assert n["q1"].shape == by_x.named["q1"].shape


def test_drives_by_name_from_arrays():
    """The coupled Duffing oscillators on a base shaken by a measured acceleration ``a``: the
    drive by its name from a dict of arrays, in identify, compare and the system's run."""
    sim = hbid.simulate(system="coupled-duffing", samples=4000)
    hint = dict(sim.identify_options)
    # Columns by name and position: a CSV's header or a .npy's columns alike.
    assert hint.pop("drive_col") == "a=6" and hint.pop("coords") == "x1=2,x2=3"
    x = {q: sim.named[q] for q in ("x1", "x2")}
    drive = {"a": sim.named["a"]}
    result = hbid.identify(x, t=sim.t, drive=drive, bootstrap=0, **hint)
    worst = max(abs(result.coefficients[k] - v) / abs(v) for k, v in sim.truth.items())
    assert worst < 1e-5, worst
    model = result.model
    assert model.drives == ["a"] and model.signals == ["line", "line"] and model.signal == "line"
    c = hbid.compare(model, {"x2": x["x2"], "x1": x["x1"]}, t=sim.t, drive=drive, range=(0, 1000))
    assert c.measured_drive and [r.coordinate for r in c.ranges] == ["x1", "x2"]
    # A drive by a name the model does not have is refused, not taken by its place.
    with pytest.raises(hbid.OptionsError, match=r"drive: \['b'\] is not a drive of the model \(its drives: a\)"):
        hbid.compare(model, x, t=sim.t, drive={"b": drive["a"]}, range=(0, 1000))
    x0 = [r.initial_states[0][0] for r in c.ranges]
    v0 = [r.initial_states[0][1] for r in c.ranges]
    # On the record's grid. The drive's spline takes its step from the times (the grid's step
    # to 12 digits at t ~ 1000), and the chaotic oscillators amplify the difference: 2.7e-10
    # after 50 samples, 5e-8 after 100, 3e-2 after 1000 (measured).
    t = c.runs[0][0].t
    run = model.simulate(t=t, x0=x0, v0=v0, drive={"a": drive["a"][:1000]})
    assert np.abs(run["x1"][:50] - c.runs[0][0].x[:50]).max() < 1e-8
    assert np.abs(run["x2'"][:50] - c.runs[1][0].v[:50]).max() < 1e-8
    same = model.simulate(t=t, x0=x0, v0=v0, drive=[drive["a"][:1000]])
    np.testing.assert_array_equal(same["x2"], run["x2"])


def test_one_coordinate_under_two_named_drives(tmp_path):
    """One coordinate under two measured drives by name (the pendulum's shaker ``u`` and a
    series ``w`` it does not feel): identified, saved and loaded as the system it is, compared
    and run under the drives by name."""
    sim = hbid.simulate(samples=3000, write_drive=True)
    t, x, v = sim
    drive = {"u": sim.drive, "w": np.cos(t)}
    result = hbid.identify(x, t=t, drive=drive, bootstrap=0)
    assert result.coefficients["u*cos(x)"] == pytest.approx(-1.0, abs=1e-6)
    assert abs(result.coefficients["w*cos(x)"]) < 1e-6
    result.model.save(tmp_path / "two.json")
    model = hbid.Model.load(tmp_path / "two.json")
    assert model.drives == ["u", "w"]
    c = hbid.compare(model, x, t=t, drive={"w": drive["w"], "u": drive["u"]}, range=(0, 100))
    assert c.ranges[0].rmse < 1e-3
    run = model.simulate(t=t[:50], drive={"u": drive["u"][:50], "w": drive["w"][:50]}, x0=[x[0]], v0=[v[0]])
    _, run_x, _ = run
    assert np.abs(wrap(run_x - x[:50])).max() < 1e-3


def test_compare_pairs_the_records_columns_with_the_model_by_name():
    """The robot arm's joints and torques given in the reverse order (a dict, an array named by
    ``coords`` and ``drive_col``, a Record read so) score as in the model's order; an array's
    columns named with positions are refused rather than taken by their place."""
    sim = hbid.simulate(system="arm", samples=6000)
    hint = dict(sim.identify_options)
    hint.pop("coords"), hint.pop("drive_col")
    q = {n: sim.named[n] for n in ("q1", "q2")}
    tau = {n: sim.named[n] for n in ("tau1", "tau2")}
    model = hbid.identify(q, t=sim.t, drive=tau, bootstrap=0, **hint).model
    assert model.coordinates == ["q1", "q2"] and model.drives == ["tau1", "tau2"]
    # Scored on a record the model was not fitted to: the arm from another initial state.
    sim = hbid.simulate(system="arm", samples=6000, q0=[0.5, -0.3])
    q = {n: sim.named[n] for n in ("q1", "q2")}
    tau = {n: sim.named[n] for n in ("tau1", "tau2")}

    def rmse(x, **kw):
        c = hbid.compare(model, x, range=(2000, 3000), **kw)
        assert [r.coordinate for r in c.ranges] == ["q1", "q2"]
        return [r.rmse for r in c.ranges]

    fitted = rmse(q, t=sim.t, drive=tau)
    assert max(fitted) < 1e-3, fitted
    reversed_q = np.column_stack([q["q2"], q["q1"]])
    reversed_tau = np.column_stack([tau["tau2"], tau["tau1"]])
    assert rmse({"q2": q["q2"], "q1": q["q1"]}, t=sim.t, drive={"tau2": tau["tau2"], "tau1": tau["tau1"]}) == fitted
    assert rmse(reversed_q, t=sim.t, coords=["q2", "q1"], drive=reversed_tau, drive_col=["tau2", "tau1"]) == fitted
    record = hbid.read({"q2": q["q2"], "q1": q["q1"]}, t=sim.t, drive={"tau2": tau["tau2"], "tau1": tau["tau1"]})
    assert rmse(record) == fitted
    # Names the model does not have are not paired by their place.
    with pytest.raises(hbid.OptionsError, match="the model's coordinates are q1, q2"):
        rmse(reversed_q, t=sim.t, coords=["a", "b"], drive=tau)
    # NAME=POSITION (or a dict) picks columns of a file: for an array the positions would be
    # dropped.
    for coords in (["q1=2", "q2=1"], {"q1": 2, "q2": 1}):
        with pytest.raises(hbid.OptionsError, match="name the columns of an array with a list of names"):
            hbid.identify(reversed_q, t=sim.t, coords=coords, drive=tau, bootstrap=0, **hint)


def test_bad_inputs_are_hbid_errors(double_pendulum):
    csv, sim = double_pendulum["csv"], double_pendulum["sim"]
    model = double_pendulum["result"].model
    t = sim.t[:100]
    for x0 in ([0.1], [0.1, 0.2, 0.3], 0.1):
        with pytest.raises(hbid.OptionsError, match=r"x0: \d value\(s\) for a system of 2 coordinate"):
            model.simulate(t=t, x0=x0, v0=[0.0, 0.0])
    with pytest.raises(hbid.OptionsError, match="v0"):
        model.simulate(t=t, x0=[0.1, 0.2], v0=[0.0])
    with pytest.raises(hbid.OptionsError, match="x0: give the initial position of each coordinate"):
        model.simulate(t=t)
    with pytest.raises(hbid.OptionsError, match="x0"):
        model.simulate(t=t, x0=[0.1, float("nan")])
    with pytest.raises(hbid.OptionsError, match="x0"):
        model.simulate(t=t, x0=["a", 0.2])
    with pytest.raises(hbid.OptionsError, match="t: a system runs over given times"):
        model.simulate(100)
    with pytest.raises(hbid.OptionsError, match="drive"):
        model.simulate(t=t, x0=[0.1, 0.2], drive=np.zeros(100))
    with pytest.raises(hbid.OptionsError, match="even grid"):
        model.simulate(t=t ** 1.5, x0=[0.1, 0.2])
    options = dict(sim.identify_options, bootstrap=0)
    with pytest.raises(hbid.OptionsError, match="names the coordinate 'theta3', which has no equation"):
        hbid.identify(csv, **dict(options, terms={"theta1": "sin(theta1)", "theta3": "sin(theta1)"}))
    with pytest.raises(hbid.OptionsError, match="the equation of theta1"):
        hbid.identify(csv, **dict(options, terms={"theta1": "sin(theta3)"}))
    with pytest.raises(hbid.OptionsError, match="terms"):
        hbid.identify(csv, **dict(options, terms={"theta1": 3}))
    with pytest.raises(hbid.OptionsError, match="signal"):
        hbid.identify(csv, **dict(options, signal=["circle", "line", "line"]))
    with pytest.raises(hbid.OptionsError, match="coords"):
        hbid.identify({"a": sim.named["theta1"], "b": sim.named["theta2"]}, t=sim.t, coords="theta1,theta2",
                      bootstrap=0)
    with pytest.raises(hbid.OptionsError, match="velocity_col"):
        hbid.identify({"theta1": sim.named["theta1"], "theta2": sim.named["theta2"]}, t=sim.t,
                      velocity_col=["omega1", "omega2"], bootstrap=0)
    with pytest.raises(hbid.OptionsError, match="velocity_col"):
        hbid.read(csv, coords=["theta1", "theta2"], velocity_col=["omega1"])
    with pytest.raises(hbid.OptionsError, match="x: the arrays are named"):
        hbid.compare(model, {"q1": sim.named["theta1"], "q2": sim.named["theta2"]}, t=sim.t)
    with pytest.raises(hbid.OptionsError, match="x0"):
        hbid.compare(model, str(csv), x0=[0.1], v0=[0.0])
    # One of the model's names beside one it does not have: not paired by place.
    with pytest.raises(hbid.OptionsError, match="'theta2' is one of the system's coordinates and 'nope' is not"):
        hbid.compare(model, str(csv), coords=["nope", "theta2"])
    with pytest.raises(hbid.InputError, match="nope"):
        hbid.compare(model, str(csv), coords=["nope", "omega2"])


def test_simulate_takes_the_systems_options():
    """The options of the systems of two coordinates, as ``hbid simulate`` takes them: tuples for
    the command line's ``A,B`` and ``A:OMEGA`` values, every column by name."""
    arm = hbid.simulate(system="arm", samples=300, torque1=(0.4, 10), torque2=["0.8:10:1.5707963267948966"],
                        joint_friction=(0.0, 0.0), q0=(0.1, -0.2), jitter=0.0)
    assert arm.columns == ("t", "q1", "q2", "v1", "v2", "tau1", "tau2")
    assert list(arm.named) == list(arm.columns) and len(arm.named["tau2"]) == 300
    np.testing.assert_array_equal(arm.x, arm.named["q1"])
    np.testing.assert_array_equal(arm.v, arm.named["v1"])
    assert arm.truth_equations.keys() == {"q1", "q2"}
    dp = hbid.simulate(system="double-pendulum", samples=200, mu=0.3, length_ratio=0.8, c2=0.02, dq0=[0.1, 0.0])
    assert dp.truth_equations["theta1"]["coefficients"]["theta2''*cos(theta1-theta2)"] == pytest.approx(0.3 * 0.8)
    cd = hbid.simulate(system="coupled-duffing", samples=200, a2=-0.5, b2=1.0, coupling=0.2, coupling_cubic=0.0,
                       mass_ratio=1.0, drive_seed=2)
    assert cd.drive is not None and cd.columns[-1] == "a"
    with pytest.raises(hbid.OptionsError, match="mu"):
        hbid.simulate(mu=0.3)
    with pytest.raises(hbid.OptionsError, match="q0"):
        hbid.simulate(system="double-pendulum", q0=(1.0, 0.0, 2.0))


def test_arrays_of_samples_by_coordinates_and_the_matrix_of_coefficients(double_pendulum):
    """A record as an array of shape (samples, coordinates) named by ``coords``, drives as an
    array of shape (samples, drives) named by ``drive_col``: the same numbers as by name; the
    coefficients as a matrix, equations by terms."""
    sim, result = double_pendulum["sim"], double_pendulum["result"]
    terms = {q: list(e["coefficients"]) for q, e in sim.truth_equations.items()}
    samples = np.column_stack([sim.named["theta1"], sim.named["theta2"]])
    by_columns = hbid.identify(samples, t=sim.t, coords=["theta1", "theta2"], terms=terms, bootstrap=0)
    assert by_columns.coefficients == result.coefficients
    coordinates, names, c = by_columns.matrix()
    assert coordinates == ["theta1", "theta2"] and c.shape == (2, len(names))
    for i, q in enumerate(coordinates):
        for k, name in enumerate(names):
            assert c[i, k] == by_columns.equations[q].coefficients.get(name, 0.0)
    # Every term of either equation is a column: the coupling terms are each in one row only.
    assert "theta2''*cos(theta1-theta2)" in names and c[1, names.index("theta2''*cos(theta1-theta2)")] == 0.0
    with pytest.raises(hbid.OptionsError, match="name each with coords"):
        hbid.identify(samples, t=sim.t, terms=terms, bootstrap=0)
    with pytest.raises(hbid.OptionsError, match=r"coords: 3 name\(s\) for an array of 2 columns"):
        hbid.identify(samples, t=sim.t, coords=["a", "b", "c"], bootstrap=0)

    duffing = hbid.simulate(system="coupled-duffing", samples=4000)
    hint = dict(duffing.identify_options)
    hint.pop("coords"), hint.pop("drive_col")
    x = np.column_stack([duffing.named["x1"], duffing.named["x2"]])
    drives = duffing.named["a"][:, None]
    one = hbid.identify(x, t=duffing.t, coords=["x1", "x2"], drive=drives, drive_col=["a"], bootstrap=0, **hint)
    named = hbid.identify({"x1": x[:, 0], "x2": x[:, 1]}, t=duffing.t, drive={"a": drives[:, 0]}, bootstrap=0, **hint)
    assert one.coefficients == named.coefficients
    with pytest.raises(hbid.OptionsError, match=r"drive_col: 2 name\(s\) for an array of 1 columns"):
        hbid.identify(x, t=duffing.t, coords=["x1", "x2"], drive=drives, drive_col=["a", "b"], bootstrap=0, **hint)


def _arm_tie(p):
    """The tie spec of the simulated arm's equations from its truth's parameters (the DFKI
    model's rigid-body parameters, g, l1 and the gear ratio known)."""
    g, l1, gr = p["g"], p["l1"], p["gr"]
    return {
        "parameters": ["Ia", "I2", "Ir", "mr1", "mr2", "b1", "cf1", "b2", "cf2"],
        "equations": {
            "q1": {"q1''": {"Ia": 1, "I2": 1, "Ir": gr * gr + 1}, "q1''*cos(q2)": {"mr2": 2 * l1},
                   "q2''": {"I2": 1, "Ir": -gr}, "q2''*cos(q2)": {"mr2": l1}, "sin(q2)*q1'*q2'": {"mr2": -2 * l1},
                   "sin(q2)*q2'^2": {"mr2": -l1}, "sin(q1)": {"mr1": g}, "sin(q1+q2)": {"mr2": g},
                   "q1'": {"b1": 1}, "sign(q1')": {"cf1": 1}, "tau1": -1},
            "q2": {"q2''": {"I2": 1, "Ir": gr * gr}, "q1''": {"I2": 1, "Ir": -gr}, "q1''*cos(q2)": {"mr2": l1},
                   "sin(q2)*q1'^2": {"mr2": l1}, "sin(q1+q2)": {"mr2": g}, "q2'": {"b2": 1},
                   "sign(q2')": {"cf2": 1}, "tau2": -1},
        },
    }


def test_a_tied_fit_from_a_dict_is_the_command_lines(cli, tmp_path):
    csv, truth = tmp_path / "arm.csv", tmp_path / "arm.json"
    sim = hbid.simulate(system="arm", out=csv, truth=truth)
    p = json.loads(truth.read_text())["parameters"]
    spec = _arm_tie(p)
    options = {k: v for k, v in sim.identify_options.items() if k != "terms"}
    result = hbid.identify(csv, tie=spec, **options)
    assert list(result.parameters) == spec["parameters"]
    assert result.parameters["mr2"]["value"] == pytest.approx(p["m2"] * p["r2"], rel=1e-3)
    assert result.parameters["Ir"]["value"] == pytest.approx(p["Ir"], rel=1e-3)
    assert all(e.intervals is None for e in result.equations.values())
    lo, hi = result.parameters["mr2"]["interval"]
    assert lo < result.parameters["mr2"]["value"] < hi and result.parameters["mr2"]["interval_level"] == 0.95
    path = tmp_path / "tie.json"
    path.write_text(json.dumps(spec))
    assert hbid.identify(csv, tie=path, **options).to_json() == result.to_json()
    out = subprocess.run(
        [str(cli), "--quiet", "identify", str(csv), "--json", "--coords", options["coords"], "--signal",
         options["signal"], "--drive-col", options["drive_col"], "--window", str(options["window"]), "--tie",
         str(path)],
        capture_output=True, text=True, check=True,
    )
    assert json.loads(out.stdout) == json.loads(result.to_json())
    with pytest.raises(hbid.OptionsError, match="tie"):
        hbid.identify(csv, tie=spec, terms=sim.identify_options["terms"], **options)
    bad = dict(spec, parameters=spec["parameters"] + ["unused"])
    with pytest.raises(hbid.OptionsError, match="'unused'"):
        hbid.identify(csv, tie=bad, **options)
